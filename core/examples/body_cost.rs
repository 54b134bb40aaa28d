//! What the tanpura body costs per output sample: `cargo run --release --example body_cost`.
//! (The body runs once per engine, on the summed bridge force, whatever the number of strings.)

use javari_core::tanpura::body::{Body, TANPURA_BODY};
use std::time::Instant;

fn main() {
    let mut body = Body::new(&TANPURA_BODY, 44_100.0);
    let samples = 20_000_000;
    let mut sum = 0.0;
    let start = Instant::now();
    for n in 0..samples {
        sum += body.tick(if n % 1000 == 0 { 1.0 } else { 0.0 });
    }
    let per_sample = start.elapsed().as_secs_f64() / samples as f64;
    println!(
        "{:.2} ns per sample, {:.0}x real time at 44.1 kHz (checksum {sum:e})",
        per_sample * 1e9,
        1.0 / (per_sample * 44_100.0)
    );
}
