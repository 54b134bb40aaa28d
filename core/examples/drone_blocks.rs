//! The four-string drone of `cargo xtask bench` timed block by block, to tell a step that costs
//! more from a block the shared machine stretched:
//! `cargo run --release -p javari-core --example drone_blocks -- [TIER] [SECONDS] [RUNS]`
//! (defaults: live, 3, 3). Prints the slowest blocks with the time since the last pluck (one
//! every 22 050 samples, as the bench plucks), and the median and 99th-percentile block, each
//! as a share of the 64-sample deadline at 44.1 kHz. A timing loop; the bench is the figure of
//! record.

use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{FirstString, Tanpura, VoiceSettings};
use std::time::Instant;

const SAMPLE_RATE: f64 = 44_100.0;
const BLOCK: usize = 64;
const PLUCK_INTERVAL: usize = 22_050;

fn main() {
    let mut args = std::env::args().skip(1);
    let tier = args.next().unwrap_or_else(|| "live".to_owned());
    let quality = Quality::from_name(&tier).unwrap_or_else(|| panic!("unknown tier {tier}"));
    let seconds: f64 = args.next().map_or(3.0, |s| s.parse().expect("seconds"));
    let runs: usize = args.next().map_or(3, |s| s.parse().expect("runs"));
    let settings = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let sa = settings.fundamental_hz;
    let deadline_s = BLOCK as f64 / SAMPLE_RATE;
    let blocks = (seconds * SAMPLE_RATE / BLOCK as f64) as usize;
    // (share of the deadline, run, block)
    let mut timings: Vec<(f64, usize, usize)> = Vec::with_capacity(runs * blocks);
    for run in 0..runs {
        let mut tanpura = Tanpura::new(&settings, sa, SAMPLE_RATE);
        tanpura.set_tuning(&settings, sa, FirstString::Pa);
        for block in 0..blocks {
            let start = Instant::now();
            for offset in 0..BLOCK {
                let index = block * BLOCK + offset;
                if index.is_multiple_of(PLUCK_INTERVAL) {
                    tanpura.pluck((index / PLUCK_INTERVAL) % 4, &Pluck::default());
                }
                std::hint::black_box(tanpura.next_sample());
            }
            let share = start.elapsed().as_secs_f64() / deadline_s;
            timings.push((100.0 * share, run, block));
        }
    }
    let mut slowest = timings.clone();
    slowest.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (percent, run, block) in slowest.iter().take(12) {
        let first_sample = block * BLOCK;
        let since_pluck_ms = (first_sample % PLUCK_INTERVAL) as f64 / SAMPLE_RATE * 1e3;
        println!(
            "run {run}, block {block}: {percent:.2} % of the deadline, {since_pluck_ms:.1} ms \
             after the last pluck"
        );
    }
    let mut shares: Vec<f64> = timings.iter().map(|timing| timing.0).collect();
    shares.sort_by(f64::total_cmp);
    let at = |fraction: f64| shares[((shares.len() - 1) as f64 * fraction) as usize];
    println!(
        "{tier}: {} blocks, median {:.2} %, 99th percentile {:.2} %, 99.9th {:.2} %",
        shares.len(),
        at(0.5),
        at(0.99),
        at(0.999)
    );
}
