//! What retuning a ringing string costs per tier (`TanpuraVoice::set_settings`): 200 changes of
//! the thread position (a new rest state and the tuning passes), then 200 of γ only, each
//! followed by one output sample, against the cost of one sample and a 64-sample block's
//! deadline. `cargo run --release -p javari-core --example retune_cost [TIER ...] [key=NN]`
//! (docs/performance.md); with tier names (live, fine, studio) only those tiers, with `key=NN`
//! the string at that MIDI key instead of D3.

use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use std::time::Instant;

const RATE: f64 = 44_100.0;
const CHANGES: usize = 200;

/// Mean time of `change(i)` followed by one sample, µs.
fn per_change(voice: &mut TanpuraVoice, mut change: impl FnMut(usize, &mut TanpuraVoice)) -> f64 {
    let start = Instant::now();
    for index in 0..CHANGES {
        change(index, voice);
        voice.next_sample();
    }
    start.elapsed().as_secs_f64() / CHANGES as f64 * 1e6
}

fn main() {
    println!(
        "deadline of a 64-sample block at 44.1 kHz: {:.0} µs",
        64.0 / RATE * 1e6
    );
    let args: Vec<String> = std::env::args().skip(1).collect();
    // `key=NN`: the string at that MIDI key instead of D3.
    let fundamental_hz = args
        .iter()
        .find_map(|arg| arg.strip_prefix("key="))
        .map_or(146.8, |key| note_to_hz(key.parse().expect("key=NN")));
    let chosen: Vec<&String> = args.iter().filter(|arg| !arg.starts_with("key=")).collect();
    let tiers = [Quality::Live, Quality::Fine, Quality::Studio];
    for quality in tiers.into_iter().filter(|quality| {
        chosen.is_empty() || chosen.iter().any(|name| name.as_str() == quality.name())
    }) {
        let settings = VoiceSettings {
            fundamental_hz,
            quality,
            ..VoiceSettings::default()
        };
        let mut voice = TanpuraVoice::new(&settings, RATE);
        voice.pluck(&Pluck::default());
        for _ in 0..4410 {
            voice.next_sample();
        }
        let thread = per_change(&mut voice, |index, voice| {
            let moved = VoiceSettings {
                thread_position_m: 0.040 + 1e-5 * (index % 50) as f64,
                ..settings
            };
            voice.set_settings(&moved);
        });
        let losses = per_change(&mut voice, |index, voice| {
            let damped = VoiceSettings {
                gamma_per_s: 0.6 + 1e-3 * (index % 50) as f64,
                ..settings
            };
            voice.set_settings(&damped);
        });
        let start = Instant::now();
        for _ in 0..44_100 {
            voice.next_sample();
        }
        let sample = start.elapsed().as_secs_f64() / 44_100.0 * 1e6;
        println!(
            "{}: retune (thread moved) {thread:.0} µs, losses only {losses:.0} µs, one sample {sample:.2} µs",
            quality.name()
        );
    }
}
