//! What a humanised drone pluck costs inside a ringing drone:
//! `cargo run --release -p javari-core --example humanised_plucks -- [TIER] [PLUCKS]`
//! (defaults: fine, 40). Four strings (Pa Sa Sa sa), one pluck every 0.5 s in turn, each
//! pressed at 90–100 % of the default amplitude as the drone's humanised strength draws it
//! (`drone_humanize_strength` 0.1, the shipped presets'), all of them left ringing. Each pluck
//! is timed on its own; prints the median, 90th percentile and worst over the plucks after the
//! first four (each string's first press is solved). A timing loop for before/after
//! comparisons in one session (`docs/performance.md`, "Stop 53: a humanised pluck's press").

use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use std::time::Instant;

const SAMPLE_RATE: f64 = 44_100.0;
const BLOCK: usize = 64;
const PLUCK_INTERVAL: usize = 22_050;

fn main() {
    let mut args = std::env::args().skip(1);
    let tier = args.next().unwrap_or_else(|| "fine".to_owned());
    let quality = Quality::from_name(&tier).unwrap_or_else(|| panic!("unknown tier {tier}"));
    let plucks: usize = args.next().map_or(40, |s| s.parse().expect("plucks"));
    let settings = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let sa = settings.fundamental_hz;
    let mut voices: Vec<TanpuraVoice> = [1.5 * sa, 2.0 * sa, 2.0 * sa, sa]
        .iter()
        .map(|&hz| {
            let string = VoiceSettings {
                fundamental_hz: hz,
                ..settings
            };
            TanpuraVoice::new(&string, SAMPLE_RATE)
        })
        .collect();
    let full = Pluck::default();
    let mut block = [0.0f32; BLOCK];
    let mut times_us = Vec::with_capacity(plucks);
    for index in 0..plucks.max(5) {
        // A low-discrepancy draw of the softening in [0, 0.1).
        let softening = (index as f64 * 0.618_033_988_7).fract() * 0.1;
        let pluck = Pluck {
            amplitude_m: full.amplitude_m * (1.0 - softening),
            ..full
        };
        let string = index % voices.len();
        let start = Instant::now();
        voices[string].pluck(&pluck);
        times_us.push(start.elapsed().as_secs_f64() * 1e6);
        for _ in 0..PLUCK_INTERVAL / BLOCK {
            for voice in &mut voices {
                voice.process(&mut block);
            }
        }
    }
    let later = &mut times_us[voices.len()..];
    later.sort_by(f64::total_cmp);
    let at = |fraction: f64| later[((later.len() - 1) as f64 * fraction).round() as usize];
    println!(
        "{tier}: {} humanised plucks in a ringing drone: median {:.1} µs, 90th percentile {:.1} µs, worst {:.1} µs",
        later.len(),
        at(0.5),
        at(0.9),
        at(1.0)
    );
}
