//! Cost of one bowed voice, both tiers: real-time factor = simulated seconds per CPU second
//! (wall-clock time of a single thread, best of five runs of 4 simulated seconds, so that other
//! work on a shared machine inflates the figure as little as possible).
//!
//! `cargo bench -p javari-core --bench bowed`

use std::hint::black_box;
use std::time::Instant;

use javari_core::bowed::{BowTableString, BowedCapacity, BowedString, BowedVoice, StringConstants};

/// Simulated seconds per run.
const SIMULATED_S: f64 = 4.0;

/// Runs per figure; the fastest is reported.
const RUNS: usize = 5;

fn measure<V: BowedVoice>(voice: &mut V, sample_rate_hz: f64, body: bool) -> (f64, f64) {
    voice.prepare(sample_rate_hz).unwrap();
    voice.set_pitch_hz(440.0);
    voice.set_bow_position(0.1);
    voice.set_bow_velocity_m_s(0.1);
    voice.set_bow_force_n(0.3);
    voice.set_body_enabled(body);
    // Warm up past the attack so the steady Helmholtz motion is what is timed.
    for _ in 0..(0.5 * sample_rate_hz) as usize {
        black_box(voice.next_sample());
    }
    let samples = (SIMULATED_S * sample_rate_hz) as usize;
    let mut best = f64::INFINITY;
    for _ in 0..RUNS {
        let start = Instant::now();
        let mut sum = 0.0;
        for _ in 0..samples {
            sum += black_box(voice.next_sample()).radiated;
        }
        best = best.min(start.elapsed().as_secs_f64());
        black_box(sum);
    }
    (SIMULATED_S / best, 1e9 * best / samples as f64)
}

fn main() {
    let capacity = BowedCapacity::default();
    println!("bowed voice, violin A string constants, 440 Hz, β = 0.1, F_b = 0.3 N, v_b = 0.1 m/s");
    println!(
        "{:<28} {:>10} {:>6} {:>16} {:>12}",
        "tier", "rate (Hz)", "body", "real-time factor", "ns/sample"
    );
    for &rate in &[44_100.0, 48_000.0, 96_000.0, 192_000.0] {
        for body in [false, true] {
            let mut rounded = BowedString::new(capacity, StringConstants::violin_a());
            let (rtf, ns) = measure(&mut rounded, rate, body);
            print_row("rounded corner (BowedString)", rate, body, rtf, ns);
            let mut table = BowTableString::new(capacity, StringConstants::violin_a());
            let (rtf, ns) = measure(&mut table, rate, body);
            print_row("bow table (BowTableString)", rate, body, rtf, ns);
        }
    }
}

fn print_row(tier: &str, rate: f64, body: bool, rtf: f64, ns: f64) {
    println!(
        "{tier:<28} {rate:>10.0} {:>6} {rtf:>16.0} {ns:>12.1}",
        if body { "on" } else { "off" }
    );
}
