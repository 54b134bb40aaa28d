//! Where a modal tier's step spends its time, part by part, at each key asked for:
//! `cargo run --release -p javari-core --features step-timers --example step_parts -- [TIER]
//! [SECONDS] [KEY...]` (defaults: fine, 2, and keys 36 to 64 every fourth with 62, the bench's
//! slowest in stop 59). One string of the tier plucked as the bench's one-string scene plucks it
//! (`tier_cost`'s voice), timed by the time-stamp counter around each part of the step on the
//! grid's nodes (`javari_core::step_timers`): cycles per output sample for each part, its share
//! of the whole run's cycles, and what the parts leave ("rest": the pickups, the decimator, the
//! step's untimed lines). The counters cost a little themselves (about 20 cycles a read), so the
//! real-time factor printed is below `tier_cost`'s. It fails (exit status 1) if a key's run
//! counted no time in any part, so CI runs it briefly as the check that the counters count.

use javari_core::engine::pitch::note_to_hz;
use javari_core::step_timers::{self, STEP_PARTS};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use std::time::Instant;

const SAMPLE_RATE: f64 = 44_100.0;
const BLOCK: usize = 64;

fn main() {
    let mut args = std::env::args().skip(1);
    let tier = args.next().unwrap_or_else(|| "fine".to_owned());
    let quality = Quality::from_name(&tier).unwrap_or_else(|| panic!("unknown tier {tier}"));
    let seconds: f64 = args.next().map_or(2.0, |s| s.parse().expect("seconds"));
    let mut keys: Vec<u8> = args.map(|s| s.parse().expect("key")).collect();
    if keys.is_empty() {
        keys = vec![36, 40, 44, 48, 52, 56, 60, 62, 64];
    }
    let blocks = (seconds * SAMPLE_RATE / BLOCK as f64).ceil() as usize;
    let samples = (blocks * BLOCK) as f64;
    print!("{:>4} {:>8} {:>7}", "key", "realtime", "cycles");
    for part in STEP_PARTS {
        print!(" {:>15}", format!("{part:?}"));
    }
    println!(" {:>15}", "rest");
    for key in keys {
        let settings = VoiceSettings {
            quality,
            fundamental_hz: note_to_hz(key),
            ..VoiceSettings::default()
        };
        let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
        voice.pluck(&Pluck::default());
        let mut block = [0.0_f32; BLOCK];
        step_timers::reset();
        let (wall, counter) = (Instant::now(), step_timers::start());
        for _ in 0..blocks {
            voice.process(&mut block);
        }
        let cycles = step_timers::start().wrapping_sub(counter) as f64;
        let factor = samples / SAMPLE_RATE / wall.elapsed().as_secs_f64();
        let totals = step_timers::totals();
        if totals.iter().all(|&total| total == 0) {
            eprintln!(
                "key {key}: no part counted any time (built without `--features step-timers`?)"
            );
            std::process::exit(1);
        }
        print!("{key:>4} {factor:>7.2}x {:>7.0}", cycles / samples);
        for total in totals {
            let share = 100.0 * total as f64 / cycles;
            print!(
                " {:>15}",
                format!("{:.0} ({share:.1} %)", total as f64 / samples)
            );
        }
        let rest = cycles - totals.iter().sum::<u64>() as f64;
        println!(
            " {:>15}",
            format!("{:.0} ({:.1} %)", rest / samples, 100.0 * rest / cycles)
        );
    }
}
