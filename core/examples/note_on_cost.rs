//! What a note-on costs: `cargo run --release -p javari-core --example note_on_cost -- [TIER]
//! [RUNS]` (defaults: fine, 3). Two parts, each a timing loop for profiling and before/after
//! comparisons in one session (the bench is the figure of record):
//!
//! 1. One voice, a new pitch each time (the bench's eight notes in turn, the voice reset as the
//!    engine resets a stolen one): the retune that tunes the string (`set_settings`), the one
//!    that configures it at a known tension (`set_settings_tuned`, what the engine's tuning
//!    memory gives), the pluck, and the first 64 samples after it, each as a mean in µs.
//! 2. The bench's eight-voices scene block by block, the engine unprepared and prepared
//!    (`Engine::prepare_tunings`, as the plugin prepares it on activation): the slowest blocks
//!    (each block's fastest time over the runs, as the bench takes it) as a share of the
//!    64-sample deadline at 44.1 kHz, and the real-time factor.
//! 3. A tuning plan's strings tuned as the plugin's tuning worker tunes them after a change of
//!    the bridge or thread control (`Engine::take_wanted_tuning_plan`), off the audio thread:
//!    the time for all of them on one scratch voice.

use javari_core::engine::pitch::note_to_hz;
use javari_core::engine::{Engine, EngineEvent, EngineSettings, TimedEvent};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use std::time::Instant;

const SAMPLE_RATE: f64 = 44_100.0;
const BLOCK: usize = 64;
/// The bench's eight-voices scene: these notes, one every 0.1 s, all left ringing, over 3 s.
const NOTES: [u8; 8] = [50, 53, 57, 60, 62, 65, 69, 72];
const NOTE_INTERVAL: usize = 4_410;
const SCENE_SECONDS: f64 = 3.0;

fn main() {
    let mut args = std::env::args().skip(1);
    let tier = args.next().unwrap_or_else(|| "fine".to_owned());
    let quality = Quality::from_name(&tier).unwrap_or_else(|| panic!("unknown tier {tier}"));
    let runs: usize = args.next().map_or(3, |s| s.parse().expect("runs"));
    let deadline_us = BLOCK as f64 / SAMPLE_RATE * 1e6;
    println!("{tier}: a 64-sample block's deadline is {deadline_us:.0} µs");
    voice_costs(quality);
    for prepared in [false, true] {
        eight_voices(quality, runs, prepared, deadline_us);
    }
    plan_cost(quality);
}

/// Part 3: a tuning plan's strings, tuned on one scratch voice.
fn plan_cost(quality: Quality) {
    let mut settings = EngineSettings::default();
    settings.voice.quality = quality;
    let plan = Engine::new(&settings, SAMPLE_RATE, 1).tuning_plan();
    let start = Instant::now();
    let mut voice = plan.scratch_voice();
    let count = plan
        .strings()
        .map(|string| std::hint::black_box(plan.tune(&mut voice, &string)))
        .count();
    println!(
        "a tuning plan, off the audio thread: {count} strings in {:.1} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
}

/// Part 1: the mean cost of each stage of a note-on on one voice, µs.
fn voice_costs(quality: Quality) {
    let base = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let settings: Vec<VoiceSettings> = NOTES
        .iter()
        .map(|&note| VoiceSettings {
            fundamental_hz: note_to_hz(note),
            ..base
        })
        .collect();
    // The tension each note's string is tuned to, as the engine remembers it.
    let tensions: Vec<f64> = settings
        .iter()
        .map(|settings| TanpuraVoice::new(settings, SAMPLE_RATE).tension_n())
        .collect();
    let mut voice = TanpuraVoice::new(&base, SAMPLE_RATE);
    let repeats = 10 * NOTES.len();
    let (mut tuned, mut configured, mut plucked, mut first_block) = (0.0, 0.0, 0.0, 0.0);
    for index in 0..repeats {
        let note = index % NOTES.len();
        // Tuned: a pitch the voice was not at.
        voice.reset();
        let start = Instant::now();
        voice.set_settings(&settings[note]);
        tuned += start.elapsed().as_secs_f64();
        // Configured at the known tension: a pitch four notes on (neither this one nor the
        // next iteration's).
        let next = (note + 4) % NOTES.len();
        voice.reset();
        let start = Instant::now();
        voice.set_settings_tuned(&settings[next], tensions[next]);
        configured += start.elapsed().as_secs_f64();
        let start = Instant::now();
        voice.pluck(&Pluck::default());
        plucked += start.elapsed().as_secs_f64();
        let start = Instant::now();
        for _ in 0..BLOCK {
            std::hint::black_box(voice.next_sample());
        }
        first_block += start.elapsed().as_secs_f64();
    }
    let mean_us = |total: f64| total / repeats as f64 * 1e6;
    println!(
        "one voice, a new pitch: tuned {:.1} µs, configured at a known tension {:.1} µs, \
         pluck {:.1} µs, the first 64 samples {:.1} µs",
        mean_us(tuned),
        mean_us(configured),
        mean_us(plucked),
        mean_us(first_block)
    );
}

/// Part 2: the eight-voices scene block by block.
fn eight_voices(quality: Quality, runs: usize, prepared: bool, deadline_us: f64) {
    let settings = EngineSettings {
        voice: VoiceSettings {
            quality,
            ..VoiceSettings::default()
        },
        ..EngineSettings::default()
    };
    let blocks = (SCENE_SECONDS * SAMPLE_RATE) as usize / BLOCK;
    let mut fastest = vec![f64::INFINITY; blocks];
    let mut output = [0.0f32; BLOCK];
    for _ in 0..runs {
        let mut engine = Engine::new(&settings, SAMPLE_RATE, NOTES.len());
        if prepared {
            engine.prepare_tunings();
        }
        for (block, fastest) in fastest.iter_mut().enumerate() {
            let mut events = [TimedEvent::note_on(0, 0, 0.0)];
            let mut count = 0;
            for offset in 0..BLOCK {
                let index = block * BLOCK + offset;
                let note = index / NOTE_INTERVAL;
                if index.is_multiple_of(NOTE_INTERVAL) && note < NOTES.len() {
                    events[0] = TimedEvent {
                        offset,
                        event: EngineEvent::NoteOn {
                            note: NOTES[note],
                            velocity: 0.8,
                        },
                    };
                    count = 1;
                }
            }
            let start = Instant::now();
            engine.process(&events[..count], &mut output);
            let share = start.elapsed().as_secs_f64() * 1e6 / deadline_us;
            *fastest = fastest.min(share);
        }
    }
    let mut order: Vec<usize> = (0..blocks).collect();
    order.sort_by(|&a, &b| fastest[b].total_cmp(&fastest[a]));
    let label = if prepared { "prepared" } else { "unprepared" };
    let total: f64 = fastest.iter().sum();
    println!(
        "eight voices, engine {label}: {:.2}× real time; slowest blocks:",
        blocks as f64 / total
    );
    for &block in order.iter().take(4) {
        let first_sample = block * BLOCK;
        let note_on = (first_sample..first_sample + BLOCK).any(|index| {
            index.is_multiple_of(NOTE_INTERVAL) && index / NOTE_INTERVAL < NOTES.len()
        });
        println!(
            "  block {block}{}: {:.1} %",
            if note_on { " (a note-on)" } else { "" },
            100.0 * fastest[block]
        );
    }
}
