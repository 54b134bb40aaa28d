//! One string of a tier plucked as `cargo xtask bench`'s one-string scene plucks it, timed:
//! `cargo run --release --example tier_cost -- [TIER] [SECONDS] [RUNS] [KEY]` (defaults: reference,
//! 3, 5, and the bench's own string; KEY is a MIDI note, as the bench's timing at every key sets
//! it). Prints the real-time factor of each run and the fastest, with a checksum of the output so
//! that two builds can be compared for the same arithmetic. A timing loop for profiling and
//! before/after comparisons in one session; the bench is the figure of record.

use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use std::time::Instant;

const SAMPLE_RATE: f64 = 44_100.0;
const BLOCK: usize = 64;

fn main() {
    let mut args = std::env::args().skip(1);
    let tier = args.next().unwrap_or_else(|| "reference".to_owned());
    let quality = Quality::from_name(&tier).unwrap_or_else(|| panic!("unknown tier {tier}"));
    let seconds: f64 = args.next().map_or(3.0, |s| s.parse().expect("seconds"));
    let runs: usize = args.next().map_or(5, |s| s.parse().expect("runs"));
    let key: Option<u8> = args.next().map(|s| s.parse().expect("key"));
    let mut settings = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    if let Some(key) = key {
        settings.fundamental_hz = note_to_hz(key);
    }
    let blocks = (seconds * SAMPLE_RATE / BLOCK as f64).ceil() as usize;
    let mut best = 0.0_f64;
    for run in 0..runs {
        let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
        voice.pluck(&Pluck::default());
        let mut block = [0.0_f32; BLOCK];
        let mut checksum = 0.0_f64;
        let start = Instant::now();
        for _ in 0..blocks {
            voice.process(&mut block);
            checksum += block.iter().map(|&s| f64::from(s).abs()).sum::<f64>();
        }
        let factor = (blocks * BLOCK) as f64 / SAMPLE_RATE / start.elapsed().as_secs_f64();
        best = best.max(factor);
        let stats = voice.newton_stats();
        println!(
            "run {run}: {factor:.2}x real time, Newton {:.3} updates per step, checksum {checksum:.17e}",
            stats.mean_iterations()
        );
    }
    println!("{tier}: fastest {best:.2}x real time over {runs} runs of {seconds} s");
}
