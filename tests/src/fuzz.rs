//! What each fuzz target checks on one input: the `cargo fuzz` targets in `fuzz/` (nightly) call
//! these functions, and `tests/tests/fuzz_regressions.rs` (stable `cargo test`) replays the kept
//! corpus and every input that once failed through the same functions. A check panics when the
//! code under test breaks its promise; an input the code refuses with an error is a pass.
//!
//! - [`midi_file()`]: bytes → `midi_file::parse` → a score whose times are finite, sorted and
//!   non-negative, with no more events than the file has bytes, or an error naming the file;
//! - [`preset_text`]: text → `Preset::parse` → settings that write back to the same preset, or
//!   an error naming the file and a line that exists;
//! - [`plugin_state`]: bytes → the plugin's state load (`javari::state::restore`) → every
//!   parameter inside its range, finite engine settings, and a state that saves without panic;
//! - [`engine_events`]: bytes decoded ([`arbitrary`]) into settings, then a stream of events,
//!   parameter changes, tempo changes, resets and blocks → `Engine::process`: finite output
//!   within ±[`ENGINE_OUTPUT_BOUND`], and no allocation in any call the audio thread makes (the
//!   tuning worker's exchange after each block among them: the wanted tuning plan taken, its
//!   first strings' tensions handed back).
//!
//! No allocation is checked as the plugin's tests check it: each call runs inside
//! `nice_assert_no_alloc::assert_no_alloc`, and the binary's global allocator (nice-plug's, with
//! its `assert_process_allocs` feature, or the fuzz target's own `AllocDisabler`) aborts the
//! process on an allocation there when debug assertions are on. `tests/tests/fuzz_regressions.rs`
//! checks that the guard is armed.

use arbitrary::{Arbitrary, Unstructured};
use javari::params::JavariParams;
use javari_core::bowed::BowTier;
use javari_core::engine::drone::{DronePattern, MAX_DRONE_STRINGS};
use javari_core::engine::midi_file;
use javari_core::engine::preset::Preset;
use javari_core::engine::render::{rendered_length, RenderOptions, ScoreAction};
use javari_core::engine::{
    BowedStringKind, Engine, EngineEvent, EngineSettings, Instrument, TimedEvent,
};
use javari_core::tanpura::as_played::Calibration;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{FirstString, TanpuraVoice};
use nice_assert_no_alloc::assert_no_alloc;

/// The MIDI target's check (see the module doc).
pub fn midi_file(bytes: &[u8]) {
    match midi_file::parse(bytes, "fuzz.mid") {
        Ok(read) => {
            let score = &read.score;
            assert!(read.note_count > 0, "a score without notes was accepted");
            // The initial tempo and the final all-notes-off are the only events without bytes.
            assert!(
                score.events.len() <= bytes.len() + 2,
                "{} events from {} bytes",
                score.events.len(),
                bytes.len()
            );
            let mut previous_s = 0.0;
            for event in &score.events {
                assert!(
                    event.time_s.is_finite() && event.time_s >= previous_s,
                    "event at {} s after {previous_s} s",
                    event.time_s
                );
                previous_s = event.time_s;
                if let ScoreAction::Tempo(bpm) = event.action {
                    assert!(bpm.is_finite() && bpm > 0.0, "tempo {bpm}");
                }
            }
            assert!(score.end_s.is_finite() && score.end_s >= previous_s);
            for warning in &read.warnings {
                assert!(!warning.is_empty());
            }
            // The renderer's length arithmetic holds for any score, however long.
            let samples = rendered_length(score, &RenderOptions::default());
            assert!(samples >= 1);
            assert!(!read.describe_length().is_empty());
        }
        Err(error) => {
            let message = error.to_string();
            assert!(message.starts_with("fuzz.mid: "), "{message}");
            assert!(!error.reason.is_empty());
        }
    }
}

/// The preset target's check (see the module doc).
pub fn preset_text(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    match Preset::parse(&text, "fuzz.toml") {
        Ok(preset) => {
            let written = preset.to_text();
            let again = Preset::parse(&written, "written.toml")
                .unwrap_or_else(|error| panic!("a parsed preset writes back unreadably: {error}"));
            assert_eq!(again, preset, "{written}");
        }
        Err(error) => {
            let message = error.to_string();
            assert!(message.starts_with("fuzz.toml:"), "{message}");
            assert!(
                error.line <= text.lines().count() + 1,
                "line {} of a {}-line text",
                error.line,
                text.lines().count()
            );
        }
    }
}

/// The saved-state target's check (see the module doc).
pub fn plugin_state(bytes: &[u8]) {
    let params = JavariParams::default();
    // An error (bytes that are not a state) leaves the parameters as they were: still checked.
    let _ = javari::state::restore(&params, bytes);
    let outside = javari::state::parameters_out_of_range(&params);
    assert!(outside.is_empty(), "parameters out of range: {outside:?}");
    let settings = params.engine_settings(&javari::factory_presets());
    assert_settings_finite(&settings);
    // The host saves the state again (nice-plug reads each enum's ID by its index).
    let saved = javari::state::save(&params);
    let restored = JavariParams::default();
    let bytes = serde_json::to_vec(&saved).expect("a state serialises");
    javari::state::restore(&restored, &bytes).expect("a saved state loads");
    assert_eq!(
        javari::state::save(&restored).params.len(),
        saved.params.len()
    );
}

fn assert_settings_finite(settings: &EngineSettings) {
    let text = format!("{settings:?}");
    assert!(
        !text.contains("NaN") && !text.contains("inf"),
        "settings not finite: {text}"
    );
}

/// Largest magnitude [`engine_events`] accepts in the engine's output: the loudest plucks and
/// bows at the highest output gain (+24 dB) stay far below it; past it the output is a runaway.
pub const ENGINE_OUTPUT_BOUND: f32 = 64.0;
/// Samples one input may render at most (keeps each run short enough to fuzz).
const MAX_SAMPLES_PER_INPUT: usize = 4096;
/// Operations one input may hold at most.
const MAX_OPERATIONS: usize = 64;
/// Sample rate of the fuzzed engine, Hz.
const SAMPLE_RATE_HZ: f64 = 44_100.0;
/// Voices of the fuzzed engine (fewer than the plugin's eight, so that runs stay short).
const VOICES: usize = 4;
/// A handed-out tuning plan's strings tuned and handed back after a block (the drone's first, in
/// drone mode); the plugin's worker tunes them all.
const PLANNED_STRINGS_TUNED: usize = 2;

/// A number from the fuzzer: mostly near the useful range, sometimes anything (NaN, ±∞, huge).
#[derive(Debug, Clone, Copy, Arbitrary)]
enum Number {
    /// A fraction of the way from `low` to `high` of the field's own scale.
    Fraction(u16),
    Raw(f64),
}

impl Number {
    fn scaled(self, low: f64, high: f64) -> f64 {
        match self {
            Number::Fraction(step) => low + (high - low) * f64::from(step) / f64::from(u16::MAX),
            Number::Raw(value) => value,
        }
    }
}

/// A change of one setting, as a host moving a parameter (or a preset load) would make.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum SettingChange {
    BridgeStiffness(Number),
    ThreadEnabled(bool),
    ThreadPosition(Number),
    BridgeBeyondThread(bool),
    Gamma(Number),
    Eta(Number),
    NutPickupWeight(Number),
    Quality(u8),
    PluckPosition(Number),
    PluckWidth(Number),
    PluckAmplitude(Number),
    OutputGain(Number),
    DroneEnabled(bool),
    DroneFirstString(u8),
    DroneTempoSync(bool),
    DroneTempo(Number),
    Instrument(bool),
    BowTier(bool),
    BowString(bool),
    BowPressure(Number),
    BowVelocity(Number),
    BowPosition(Number),
    Glide(Number),
    Vibrato(Number),
    BodyEnabled(bool),
    DronePattern(u8),
    DroneSa(Option<u8>),
    StringFineTune(u8, Number),
    StringLevel(u8, Number),
    StringThread(u8, Number),
    TuneAsPlayed(bool),
    TanpuraOutput(bool),
    StereoWidth(Number),
}

impl SettingChange {
    fn apply(self, settings: &mut EngineSettings) {
        let voice = &mut settings.voice;
        let bowed = &mut settings.bowed;
        match self {
            SettingChange::BridgeStiffness(value) => {
                voice.bridge_stiffness_n_m2 = value.scaled(0.0, 1e12)
            }
            SettingChange::ThreadEnabled(on) => voice.thread_enabled = on,
            SettingChange::ThreadPosition(value) => {
                voice.thread_position_m = value.scaled(0.03, 0.045)
            }
            SettingChange::BridgeBeyondThread(on) => voice.bridge_beyond_thread = on,
            SettingChange::Gamma(value) => voice.gamma_per_s = value.scaled(0.0, 20.0),
            SettingChange::Eta(value) => voice.eta_s = value.scaled(0.0, 1e-6),
            SettingChange::NutPickupWeight(value) => {
                voice.nut_pickup_weight = value.scaled(0.0, 1.0)
            }
            // The cheaper tiers only: Reference costs a second per input.
            SettingChange::Quality(index) => {
                voice.quality =
                    [Quality::Live, Quality::Fine, Quality::Studio][usize::from(index) % 3]
            }
            SettingChange::PluckPosition(value) => {
                settings.pluck.position_m = value.scaled(0.05, 0.6)
            }
            SettingChange::PluckWidth(value) => settings.pluck.width_m = value.scaled(0.002, 0.04),
            SettingChange::PluckAmplitude(value) => {
                settings.pluck.amplitude_m = value.scaled(0.0, 0.005)
            }
            SettingChange::OutputGain(value) => settings.output_gain_db = value.scaled(-60.0, 24.0),
            SettingChange::DroneEnabled(on) => settings.drone.enabled = on,
            SettingChange::DroneFirstString(index) => {
                settings.drone.first_string =
                    [FirstString::Pa, FirstString::Ma, FirstString::Ni][usize::from(index) % 3]
            }
            SettingChange::DroneTempoSync(on) => settings.drone.tempo_sync = on,
            SettingChange::DroneTempo(value) => {
                settings.drone.free_tempo_bpm = value.scaled(20.0, 300.0)
            }
            SettingChange::Instrument(bowed_on) => {
                settings.instrument = if bowed_on {
                    Instrument::Bowed
                } else {
                    Instrument::Tanpura
                }
            }
            SettingChange::BowTier(table) => {
                bowed.player.tier = if table {
                    BowTier::BowTable
                } else {
                    BowTier::RoundedCorner
                }
            }
            SettingChange::BowString(cello) => {
                bowed.string = if cello {
                    BowedStringKind::CelloD
                } else {
                    BowedStringKind::ViolinA
                }
            }
            SettingChange::BowPressure(value) => bowed.pressure = value.scaled(0.0, 1.0),
            SettingChange::BowVelocity(value) => bowed.bow_velocity_m_s = value.scaled(0.02, 1.0),
            SettingChange::BowPosition(value) => bowed.bow_position = value.scaled(0.02, 0.5),
            SettingChange::Glide(value) => bowed.player.glide_time_s = value.scaled(0.0, 1.0),
            SettingChange::Vibrato(value) => {
                bowed.player.max_vibrato_cents = value.scaled(0.0, 100.0)
            }
            SettingChange::BodyEnabled(on) => bowed.player.body_enabled = on,
            SettingChange::DronePattern(index) => {
                settings.drone.pattern = DronePattern::ALL[usize::from(index) % 3]
            }
            SettingChange::DroneSa(note) => settings.drone.sa_note = note,
            SettingChange::StringFineTune(string, value) => {
                settings.drone.strings[usize::from(string) % MAX_DRONE_STRINGS].fine_tune_cents =
                    value.scaled(-50.0, 50.0)
            }
            SettingChange::StringLevel(string, value) => {
                settings.drone.strings[usize::from(string) % MAX_DRONE_STRINGS].level_db =
                    value.scaled(-60.0, 6.0)
            }
            SettingChange::StringThread(string, value) => {
                settings.drone.strings[usize::from(string) % MAX_DRONE_STRINGS].thread_offset_m =
                    value.scaled(-0.005, 0.005)
            }
            SettingChange::TuneAsPlayed(on) => settings.tuning.as_played = on,
            SettingChange::TanpuraOutput(radiated) => {
                settings.tanpura_output = if radiated {
                    javari_core::engine::TanpuraOutput::Radiated
                } else {
                    javari_core::engine::TanpuraOutput::Pickup
                }
            }
            SettingChange::StereoWidth(value) => settings.stereo_width = value.scaled(0.0, 1.0),
        }
    }
}

/// A MIDI-like event as the plugin hands it to the engine.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum FuzzEvent {
    NoteOn { note: u8, velocity: Number },
    NoteOff { note: u8 },
    AllNotesOff,
    AllSoundOff,
    Controller { number: u8, value: Number },
    ChannelPressure(Number),
    PolyPressure { note: u8, value: Number },
    PitchBend(Number),
}

impl FuzzEvent {
    fn engine_event(self) -> EngineEvent {
        match self {
            FuzzEvent::NoteOn { note, velocity } => EngineEvent::NoteOn {
                note,
                velocity: velocity.scaled(0.0, 1.0) as f32,
            },
            FuzzEvent::NoteOff { note } => EngineEvent::NoteOff { note },
            FuzzEvent::AllNotesOff => EngineEvent::AllNotesOff,
            FuzzEvent::AllSoundOff => EngineEvent::AllSoundOff,
            FuzzEvent::Controller { number, value } => EngineEvent::Controller {
                number,
                value: value.scaled(0.0, 1.0) as f32,
            },
            FuzzEvent::ChannelPressure(value) => {
                EngineEvent::ChannelPressure(value.scaled(0.0, 1.0) as f32)
            }
            FuzzEvent::PolyPressure { note, value } => EngineEvent::PolyPressure {
                note,
                value: value.scaled(0.0, 1.0) as f32,
            },
            FuzzEvent::PitchBend(value) => EngineEvent::PitchBend(value.scaled(-1.0, 1.0) as f32),
        }
    }
}

/// One call the host (through the plugin) makes on the audio thread.
#[derive(Debug, Clone, Arbitrary)]
enum Operation {
    /// A block of `length` samples with events at the given offsets (unsorted offsets are
    /// sorted first, as the plugin's event queue is).
    Process {
        length: u16,
        events: Vec<(u16, FuzzEvent)>,
        /// Through [`Engine::process_stereo`] (both channels checked).
        stereo: bool,
    },
    /// The host hands back a calibration of a wanted string with this offset (cents; a
    /// hostile one too).
    Calibrate(Number),
    Settings(Vec<SettingChange>),
    HostTempo(Option<Number>),
    Reset,
}

/// The engine target's check (see the module doc).
pub fn engine_events(bytes: &[u8]) {
    let mut input = Unstructured::new(bytes);
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    let Ok(initial) = Vec::<SettingChange>::arbitrary(&mut input) else {
        return;
    };
    for change in initial {
        change.apply(&mut settings);
    }
    let mut engine = Engine::new(&settings, SAMPLE_RATE_HZ, VOICES);
    // Left (or mono) and right halves.
    let mut output = vec![0.0f32; 2 * MAX_SAMPLES_PER_INPUT];
    let mut events: Vec<TimedEvent> = Vec::with_capacity(256);
    // The tuning worker's voice (`plugin/src/tuning_worker.rs`), built at the first plan.
    let mut scratch: Option<TanpuraVoice> = None;
    let mut rendered = 0;
    for _ in 0..MAX_OPERATIONS {
        let Ok(operation) = Operation::arbitrary(&mut input) else {
            break;
        };
        match operation {
            Operation::Process {
                length,
                events: fuzz_events,
                stereo,
            } => {
                let length = usize::from(length).clamp(1, MAX_SAMPLES_PER_INPUT - rendered);
                events.clear();
                events.extend(
                    fuzz_events
                        .iter()
                        .take(256)
                        .map(|(offset, event)| TimedEvent {
                            offset: usize::from(*offset),
                            event: event.engine_event(),
                        }),
                );
                events.sort_by_key(|event| event.offset);
                let (left, right) = output.split_at_mut(MAX_SAMPLES_PER_INPUT);
                let (block, right) = (&mut left[..length], &mut right[..length]);
                if stereo {
                    assert_no_alloc(|| engine.process_stereo(&events, block, right));
                } else {
                    assert_no_alloc(|| engine.process(&events, block));
                    right.fill(0.0);
                }
                for (index, sample) in block.iter().chain(right.iter()).enumerate() {
                    assert!(
                        sample.is_finite() && sample.abs() <= ENGINE_OUTPUT_BOUND,
                        "sample {} of the block is {sample}",
                        rendered + index
                    );
                }
                // The plugin's worker exchange after the block: the wanted tuning plan, its first
                // strings tuned off the audio thread and handed back.
                if let Some(plan) = assert_no_alloc(|| engine.take_wanted_tuning_plan()) {
                    let voice = scratch.get_or_insert_with(|| plan.scratch_voice());
                    for string in plan.strings().take(PLANNED_STRINGS_TUNED) {
                        let tuned = plan.tune(voice, &string);
                        assert_no_alloc(|| engine.remember_tuning(&tuned));
                    }
                }
                rendered += length;
                if rendered >= MAX_SAMPLES_PER_INPUT {
                    break;
                }
            }
            Operation::Settings(changes) => {
                for change in changes {
                    change.apply(&mut settings);
                }
                assert_no_alloc(|| engine.set_settings(&settings));
            }
            Operation::HostTempo(tempo) => {
                let tempo = tempo.map(|tempo| tempo.scaled(20.0, 300.0));
                assert_no_alloc(|| engine.set_host_tempo(tempo));
            }
            Operation::Reset => {
                assert_no_alloc(|| engine.reset());
            }
            Operation::Calibrate(offset) => {
                if let Some(request) = assert_no_alloc(|| engine.take_wanted_calibration()) {
                    let calibration = Calibration {
                        request,
                        sample_rate_hz: SAMPLE_RATE_HZ,
                        offset_cents: offset.scaled(-50.0, 50.0),
                        // Past the ±0.3 mm a calibration can find: the engine clamps it.
                        thread_offset_m: offset.scaled(-1e-3, 1e-3),
                    };
                    assert_no_alloc(|| engine.set_calibration(&calibration));
                }
            }
        }
    }
}
