//! `cargo xtask soak`: an hour of play, simulated. The engine is driven exactly as the plugin
//! drives it (`plugin/src/lib.rs`: 64-sample blocks at 44.1 kHz, eight voices, the settings and
//! host tempo passed every block, the block rendered under `FlushDenormals`), with the drone and
//! MIDI playing while every parameter the plugin exposes is automated at random.
//!
//! The scene ([`SoakScene`]), from a seed, so that a run is reproducible:
//! - MIDI: a note held from the start (the drone's Sa); notes at random intervals (0.2–3 s),
//!   pitches D2–E5, velocities 0.2–1, each held 0.1–2 s; now and then pitch bend, CCs 1, 2, 11
//!   and 74, channel pressure; every few minutes all notes off (CC 123), rarely all sound off;
//! - automation: [`CHANGES_PER_SECOND`] parameter changes a second on average
//!   (`--changes-per-second`), each to a random value
//!   of one randomly chosen parameter within its range (k_b log-uniform), switches and choices
//!   included (instrument, tanpura output, drone on/off, pattern, first string, tempo sync,
//!   humanize seed, bow model, bowed string, body, thread, bridge beyond thread), and the host
//!   tempo; one change in [`HOSTILE_FRACTION`] sends
//!   a value no host should (NaN, ±∞, or far out of range), which the engine must clamp;
//! - the quality tier stays at `--quality` (the plugin's default, fine), unless
//!   `--automate-quality` adds tier switches to the automation.
//!
//! Reported per window of simulated time (`--window-s`): the worst and the 99.9th-percentile
//! block time as a fraction of the block's deadline (64 / 44 100 s = 1.45 ms), by the wall
//! clock (what an audio callback lives by, preemption by other processes included) and by the
//! thread's CPU clock (the engine's own work: on a shared machine the honest measure of the
//! code, since it leaves out the time other processes held the core); over the run:
//! allocations on the audio path (counted by a global allocator on the soak's thread around
//! exactly the calls the plugin makes in `process`) and non-finite samples. Then the string-age
//! probe ([`age_probe`]): the block time of a lightly damped string that has rung a minute beside
//! the same string fresh, with and without flushing subnormals, to show whether denormals slow a
//! ringing string down.
//!
//! Exits with an error when an allocation or a non-finite sample occurred. Timing is reported,
//! never asserted: a shared machine's preemption shows in the worst blocks.

use crate::args::number_in;
use crate::bench::{percentile, BLOCK, SAMPLE_RATE};
use clap::Parser;
use javari_core::bowed::BowTier;
use javari_core::denormals::FlushDenormals;
use javari_core::engine::preset::QUALITY_NAMES;
use javari_core::engine::render::DEFAULT_VOICE_COUNT;
use javari_core::engine::{
    BowedStringKind, Engine, EngineEvent, EngineSettings, Instrument, TimedEvent,
};
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::FirstString;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::error::Error;
use std::io::Write as _;
use std::time::Instant;

#[derive(Debug, Parser)]
pub struct SoakArgs {
    /// Simulated minutes of play (0.05 to 600).
    #[arg(long, value_name = "N", default_value_t = 10.0, value_parser = number_in(0.05, 600.0))]
    minutes: f64,
    /// Seed of the scene's randomness (the same seed plays the same scene).
    #[arg(long, value_name = "S", default_value_t = 1)]
    seed: u64,
    /// Quality tier: live, fine (the plugin's default), studio or reference.
    #[arg(long, value_name = "TIER", default_value = "fine", value_parser = quality_name)]
    quality: Quality,
    /// Automate the quality tier too (switches among all four tiers).
    #[arg(long)]
    automate_quality: bool,
    /// Parameter changes per simulated second, all parameters together (0 to 100; 0 plays the
    /// notes without automation).
    #[arg(long, value_name = "N", default_value_t = CHANGES_PER_SECOND, value_parser = number_in(0.0, 100.0))]
    changes_per_second: f64,
    /// Length of a reporting window, simulated seconds (1 to 3600).
    #[arg(long, value_name = "S", default_value_t = 60.0, value_parser = number_in(1.0, 3600.0))]
    window_s: f64,
}

fn quality_name(text: &str) -> Result<Quality, String> {
    Quality::from_name(text.trim())
        .ok_or_else(|| format!("`{text}` is not a tier: {}", QUALITY_NAMES.join(", ")))
}

// ---------------------------------------------------------------------------------------------
// Allocation counting on the audio path.

/// Counts allocations made on a thread while its [`AUDIO_PATH`] flag is set; every other
/// allocation (other threads, the soak's own bookkeeping) passes through uncounted.
struct CountingAllocator;

thread_local! {
    /// Set around the engine calls that the plugin makes in `process`.
    static AUDIO_PATH: Cell<bool> = const { Cell::new(false) };
    /// Allocations this thread made while its flag was set. Per thread, so that another
    /// thread counting at the same time (tests run in parallel) never shows up here.
    static AUDIO_PATH_ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count_if_on_audio_path() {
    // `try_with`: const-initialised cells need no lazy set-up, so this never allocates.
    if AUDIO_PATH.try_with(Cell::get).unwrap_or(false) {
        let _ = AUDIO_PATH_ALLOCATIONS.try_with(|count| count.set(count.get() + 1));
    }
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_if_on_audio_path();
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count_if_on_audio_path();
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        count_if_on_audio_path();
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_if_on_audio_path();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Allocations (and frees) counted on this thread while `body` ran, and its result.
fn counting_allocations<T>(body: impl FnOnce() -> T) -> (u64, T) {
    let before = AUDIO_PATH_ALLOCATIONS.with(Cell::get);
    AUDIO_PATH.with(|flag| flag.set(true));
    let result = body();
    AUDIO_PATH.with(|flag| flag.set(false));
    (AUDIO_PATH_ALLOCATIONS.with(Cell::get) - before, result)
}

/// Time of one block, seconds: by the wall clock and by the thread's CPU clock.
#[derive(Debug, Clone, Copy)]
pub struct BlockTime {
    pub wall_s: f64,
    pub cpu_s: f64,
}

/// CPU time this thread has used, seconds (`CLOCK_THREAD_CPUTIME_ID`).
#[cfg(unix)]
fn thread_cpu_time_s() -> f64 {
    let mut time = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `time` is a valid timespec for the call to fill.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut time) };
    time.tv_sec as f64 + time.tv_nsec as f64 * 1e-9
}

/// Without a thread CPU clock, the wall clock stands in for it.
#[cfg(not(unix))]
fn thread_cpu_time_s() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Times `body` by both clocks.
fn timed(body: impl FnOnce()) -> BlockTime {
    let (wall, cpu) = (Instant::now(), thread_cpu_time_s());
    body();
    BlockTime {
        cpu_s: thread_cpu_time_s() - cpu,
        wall_s: wall.elapsed().as_secs_f64(),
    }
}

// ---------------------------------------------------------------------------------------------
// The scene.

/// Parameter changes per simulated second, all parameters together, by default.
pub const CHANGES_PER_SECOND: f64 = 8.0;
/// Fraction of parameter changes that send a value no host should (NaN, ±∞, far out of range).
pub const HOSTILE_FRACTION: f64 = 0.02;
/// The note held from the start: D3, the drone's Sa.
const DRONE_NOTE: u8 = 50;
/// Range of the played notes: D2 to E5.
const NOTE_RANGE: (u8, u8) = (38, 76);
/// Most notes held at once by the scene (the rest wait for a release).
const MAX_HELD: usize = 8;
/// Most events the scene sends in one block.
const MAX_EVENTS: usize = 16;

/// The parameters the plugin exposes (`plugin/src/params.rs`), by what they set.
#[derive(Debug, Clone, Copy)]
enum Parameter {
    ThreadEnabled,
    ThreadPosition,
    BridgeStiffness,
    BridgeBeyondThread,
    Gamma,
    Eta,
    NutPickup,
    Quality,
    PluckPosition,
    PluckWidth,
    PluckAmplitude,
    OutputGain,
    DroneEnabled,
    DroneFirstString,
    DroneTempoSync,
    DroneTempo,
    ReferencePitch,
    FineTuning,
    DronePattern,
    PluckSpacing,
    CyclePause,
    HumanizeTiming,
    HumanizeStrength,
    HumanizeSeed,
    TanpuraOutput,
    Instrument,
    BowModel,
    BowedString,
    BowPressure,
    BowVelocity,
    BowPosition,
    Glide,
    Vibrato,
    Body,
    HostTempo,
}

impl Parameter {
    /// Whether the parameter is a number (the others are switches and choices).
    fn is_number(self) -> bool {
        !matches!(
            self,
            Parameter::ThreadEnabled
                | Parameter::BridgeBeyondThread
                | Parameter::Quality
                | Parameter::DroneEnabled
                | Parameter::DroneFirstString
                | Parameter::DroneTempoSync
                | Parameter::DronePattern
                | Parameter::HumanizeSeed
                | Parameter::TanpuraOutput
                | Parameter::Instrument
                | Parameter::BowModel
                | Parameter::BowedString
                | Parameter::Body
        )
    }

    const ALL: [Parameter; 35] = [
        Parameter::ThreadEnabled,
        Parameter::ThreadPosition,
        Parameter::BridgeStiffness,
        Parameter::BridgeBeyondThread,
        Parameter::Gamma,
        Parameter::Eta,
        Parameter::NutPickup,
        Parameter::Quality,
        Parameter::PluckPosition,
        Parameter::PluckWidth,
        Parameter::PluckAmplitude,
        Parameter::OutputGain,
        Parameter::DroneEnabled,
        Parameter::DroneFirstString,
        Parameter::DroneTempoSync,
        Parameter::DroneTempo,
        Parameter::ReferencePitch,
        Parameter::FineTuning,
        Parameter::DronePattern,
        Parameter::PluckSpacing,
        Parameter::CyclePause,
        Parameter::HumanizeTiming,
        Parameter::HumanizeStrength,
        Parameter::HumanizeSeed,
        Parameter::TanpuraOutput,
        Parameter::Instrument,
        Parameter::BowModel,
        Parameter::BowedString,
        Parameter::BowPressure,
        Parameter::BowVelocity,
        Parameter::BowPosition,
        Parameter::Glide,
        Parameter::Vibrato,
        Parameter::Body,
        Parameter::HostTempo,
    ];
}

/// A note the scene holds and the block it releases it in.
#[derive(Debug, Clone, Copy)]
struct HeldNote {
    note: u8,
    release_block: u64,
}

/// What a run of the scene counted.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SoakCounts {
    pub blocks: u64,
    pub allocations: u64,
    pub non_finite_samples: u64,
    pub note_ons: u64,
    pub parameter_changes: u64,
    pub hostile_changes: u64,
    /// A hash of the output's bits, to check that a seed replays the same run.
    pub output_hash: u64,
}

/// The engine and the random player and automation around it.
pub struct SoakScene {
    engine: Engine,
    settings: EngineSettings,
    host_tempo_bpm: Option<f64>,
    random: fastrand::Rng,
    automate_quality: bool,
    changes_per_second: f64,
    block_index: u64,
    next_note_block: u64,
    held: [Option<HeldNote>; MAX_HELD],
    events: [TimedEvent; MAX_EVENTS],
    pub counts: SoakCounts,
}

fn seconds_to_blocks(seconds: f64) -> u64 {
    (seconds * SAMPLE_RATE / BLOCK as f64).round().max(1.0) as u64
}

impl SoakScene {
    /// The plugin's defaults at `quality`, the drone on, Sa held from the first sample;
    /// `changes_per_second` parameter changes a second (tier switches among them when
    /// `automate_quality`).
    pub fn new(
        seed: u64,
        quality: Quality,
        automate_quality: bool,
        changes_per_second: f64,
    ) -> Self {
        let mut settings = EngineSettings::default();
        settings.voice.quality = quality;
        settings.drone.enabled = true;
        let engine = Engine::new(&settings, SAMPLE_RATE, DEFAULT_VOICE_COUNT);
        let mut scene = Self {
            engine,
            settings,
            host_tempo_bpm: Some(72.0),
            random: fastrand::Rng::with_seed(seed),
            automate_quality,
            changes_per_second,
            block_index: 0,
            next_note_block: 0,
            held: [None; MAX_HELD],
            events: [TimedEvent {
                offset: 0,
                event: EngineEvent::AllNotesOff,
            }; MAX_EVENTS],
            counts: SoakCounts::default(),
        };
        scene.held[0] = Some(HeldNote {
            note: DRONE_NOTE,
            release_block: u64::MAX,
        });
        scene.events[0] = TimedEvent::note_on(0, DRONE_NOTE, 0.8);
        scene.next_note_block = seconds_to_blocks(1.0);
        scene
    }

    fn uniform(&mut self, (min, max): (f64, f64)) -> f64 {
        min + (max - min) * self.random.f64()
    }

    /// A value outside anything a host should send.
    fn hostile_value(&mut self) -> f64 {
        [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e12, -1e12][self.random.usize(..5)]
    }

    /// Changes one random parameter; returns whether the value sent was hostile.
    fn automate(&mut self) -> bool {
        use javari_core::engine::drone::{
            DronePattern, CYCLE_PAUSE_RANGE_BEATS, HUMANIZE_STRENGTH_RANGE,
            HUMANIZE_TIMING_RANGE_S, PLUCK_SPACING_RANGE_BEATS, TEMPO_RANGE_BPM,
        };
        use javari_core::engine::pitch::{A4_RANGE_HZ, FINE_TUNE_RANGE_CENTS};
        use javari_core::engine::preset::{
            BOW_GLIDE_RANGE_S, BOW_POSITION_RANGE, BOW_VELOCITY_RANGE_M_S, BOW_VIBRATO_RANGE_CENTS,
            PLUCK_POSITION_RANGE_M,
        };
        use javari_core::engine::TanpuraOutput;
        use javari_core::engine::OUTPUT_GAIN_RANGE_DB;
        use javari_core::tanpura::excitation::Pluck;
        use javari_core::tanpura::geometry::ThreadSettings;
        use javari_core::tanpura::VoiceSettings;

        let parameter = Parameter::ALL[self.random.usize(..Parameter::ALL.len())];
        let hostile = parameter.is_number() && self.random.f64() < HOSTILE_FRACTION;
        let number = |scene: &mut Self, range: (f64, f64)| {
            if hostile {
                scene.hostile_value()
            } else {
                scene.uniform(range)
            }
        };
        let s = &mut self.settings;
        match parameter {
            Parameter::ThreadEnabled => s.voice.thread_enabled = self.random.bool(),
            Parameter::ThreadPosition => {
                let value = number(self, ThreadSettings::POSITION_RANGE_M);
                self.settings.voice.thread_position_m = value;
            }
            Parameter::BridgeStiffness => {
                // The plugin's `kb` knob: log10 of k_b from 5 to 11.
                let log10 = number(self, (5.0, 11.0));
                self.settings.voice.bridge_stiffness_n_m2 = 10f64.powf(log10);
            }
            Parameter::BridgeBeyondThread => s.voice.bridge_beyond_thread = self.random.bool(),
            Parameter::Gamma => {
                let value = number(self, VoiceSettings::GAMMA_RANGE);
                self.settings.voice.gamma_per_s = value;
            }
            Parameter::Eta => {
                let value = number(self, VoiceSettings::ETA_RANGE);
                self.settings.voice.eta_s = value;
            }
            Parameter::NutPickup => {
                let value = number(self, (0.0, 1.0));
                self.settings.voice.nut_pickup_weight = value;
            }
            Parameter::Quality => {
                if self.automate_quality {
                    s.voice.quality = Quality::ALL[self.random.usize(..Quality::ALL.len())];
                }
            }
            Parameter::PluckPosition => {
                let value = number(self, PLUCK_POSITION_RANGE_M);
                self.settings.pluck.position_m = value;
            }
            Parameter::PluckWidth => {
                let value = number(self, Pluck::WIDTH_RANGE_M);
                self.settings.pluck.width_m = value;
            }
            Parameter::PluckAmplitude => {
                let value = number(self, Pluck::AMPLITUDE_RANGE_M);
                self.settings.pluck.amplitude_m = value;
            }
            Parameter::OutputGain => {
                let value = number(self, OUTPUT_GAIN_RANGE_DB);
                self.settings.output_gain_db = value;
            }
            Parameter::DroneEnabled => s.drone.enabled = self.random.bool(),
            Parameter::DroneFirstString => {
                s.drone.first_string =
                    [FirstString::Pa, FirstString::Ma, FirstString::Ni][self.random.usize(..3)]
            }
            Parameter::DroneTempoSync => s.drone.tempo_sync = self.random.bool(),
            Parameter::DroneTempo => {
                let value = number(self, TEMPO_RANGE_BPM);
                self.settings.drone.free_tempo_bpm = value;
            }
            Parameter::ReferencePitch => {
                let value = number(self, A4_RANGE_HZ);
                self.settings.tuning.a4_hz = value;
            }
            Parameter::FineTuning => {
                let value = number(self, FINE_TUNE_RANGE_CENTS);
                self.settings.tuning.fine_tune_cents = value;
            }
            Parameter::DronePattern => {
                s.drone.pattern = DronePattern::ALL[self.random.usize(..DronePattern::ALL.len())];
            }
            Parameter::PluckSpacing => {
                let value = number(self, PLUCK_SPACING_RANGE_BEATS);
                self.settings.drone.pluck_spacing_beats = value;
            }
            Parameter::CyclePause => {
                let value = number(self, CYCLE_PAUSE_RANGE_BEATS);
                self.settings.drone.cycle_pause_beats = value;
            }
            Parameter::HumanizeTiming => {
                let value = number(self, HUMANIZE_TIMING_RANGE_S);
                self.settings.drone.humanize_timing_s = value;
            }
            Parameter::HumanizeStrength => {
                let value = number(self, HUMANIZE_STRENGTH_RANGE);
                self.settings.drone.humanize_strength = value;
            }
            Parameter::HumanizeSeed => s.drone.humanize_seed = self.random.u32(..),
            Parameter::TanpuraOutput => {
                s.tanpura_output = if self.random.bool() {
                    TanpuraOutput::Pickup
                } else {
                    TanpuraOutput::Radiated
                }
            }
            Parameter::Instrument => {
                s.instrument = if self.random.bool() {
                    Instrument::Tanpura
                } else {
                    Instrument::Bowed
                }
            }
            Parameter::BowModel => {
                s.bowed.player.tier = if self.random.bool() {
                    BowTier::RoundedCorner
                } else {
                    BowTier::BowTable
                }
            }
            Parameter::BowedString => {
                s.bowed.string = BowedStringKind::ALL[self.random.usize(..2)];
            }
            Parameter::BowPressure => {
                let value = number(self, (0.0, 1.0));
                self.settings.bowed.pressure = value;
            }
            Parameter::BowVelocity => {
                let value = number(self, BOW_VELOCITY_RANGE_M_S);
                self.settings.bowed.bow_velocity_m_s = value;
            }
            Parameter::BowPosition => {
                let value = number(self, BOW_POSITION_RANGE);
                self.settings.bowed.bow_position = value;
            }
            Parameter::Glide => {
                let value = number(self, BOW_GLIDE_RANGE_S);
                self.settings.bowed.player.glide_time_s = value;
            }
            Parameter::Vibrato => {
                let value = number(self, BOW_VIBRATO_RANGE_CENTS);
                self.settings.bowed.player.max_vibrato_cents = value;
            }
            Parameter::Body => s.bowed.player.body_enabled = self.random.bool(),
            Parameter::HostTempo => {
                // A host without a transport reports no tempo now and then.
                self.host_tempo_bpm = if self.random.f64() < 0.1 {
                    None
                } else {
                    Some(number(self, (40.0, 200.0)))
                };
            }
        }
        hostile
    }

    /// This block's MIDI, in `self.events` (at most [`MAX_EVENTS`]); returns how many.
    fn play_midi(&mut self, mut count: usize) -> usize {
        let block = self.block_index;
        let mut push = |events: &mut [TimedEvent; MAX_EVENTS], offset: usize, event| {
            if count < MAX_EVENTS {
                events[count] = TimedEvent { offset, event };
                count += 1;
            }
        };
        for slot in &mut self.held {
            if let Some(held) = *slot {
                if held.release_block == block {
                    push(
                        &mut self.events,
                        self.random.usize(..BLOCK),
                        EngineEvent::NoteOff { note: held.note },
                    );
                    *slot = None;
                }
            }
        }
        if block >= self.next_note_block {
            self.next_note_block = block + seconds_to_blocks(0.2 + 2.8 * self.random.f64());
            if let Some(free) = self.held.iter().position(Option::is_none) {
                let note = self.random.u8(NOTE_RANGE.0..=NOTE_RANGE.1);
                let velocity = (0.2 + 0.8 * self.random.f64()) as f32;
                let held_for = seconds_to_blocks(0.1 + 1.9 * self.random.f64());
                self.held[free] = Some(HeldNote {
                    note,
                    release_block: block + held_for,
                });
                push(
                    &mut self.events,
                    self.random.usize(..BLOCK),
                    EngineEvent::NoteOn { note, velocity },
                );
                self.counts.note_ons += 1;
            }
        }
        // Expression for the bowed string: about twice a second.
        if self.random.f64() < 2.0 * BLOCK as f64 / SAMPLE_RATE {
            let value = self.random.f32();
            let event = match self.random.usize(..6) {
                0 => EngineEvent::PitchBend(2.0 * value - 1.0),
                1 => EngineEvent::ChannelPressure(value),
                choice => EngineEvent::Controller {
                    number: [1, 2, 11, 74][choice - 2],
                    value,
                },
            };
            push(&mut self.events, self.random.usize(..BLOCK), event);
        }
        // All notes off every few minutes (the held Sa is pressed again), all sound off rarely.
        if self.random.f64() < BLOCK as f64 / (180.0 * SAMPLE_RATE) {
            push(&mut self.events, 0, EngineEvent::AllNotesOff);
            self.held = [None; MAX_HELD];
            self.held[0] = Some(HeldNote {
                note: DRONE_NOTE,
                release_block: u64::MAX,
            });
            push(
                &mut self.events,
                1,
                EngineEvent::NoteOn {
                    note: DRONE_NOTE,
                    velocity: 0.8,
                },
            );
        }
        if self.random.f64() < BLOCK as f64 / (900.0 * SAMPLE_RATE) {
            push(&mut self.events, BLOCK / 2, EngineEvent::AllSoundOff);
        }
        count
    }

    /// Renders the next block into `output` (64 samples); returns the time the engine took.
    /// Only the engine calls are timed and watched for allocations.
    pub fn render_block(&mut self, output: &mut [f32; BLOCK]) -> BlockTime {
        // The first block already holds the Sa note-on.
        let mut count = usize::from(self.block_index == 0);
        let changes = self.random.f64() < self.changes_per_second * BLOCK as f64 / SAMPLE_RATE;
        if changes {
            self.counts.parameter_changes += 1;
            self.counts.hostile_changes += u64::from(self.automate());
        }
        count = self.play_midi(count);
        self.events[..count].sort_by_key(|event| event.offset);

        let (engine, settings, tempo, events) = (
            &mut self.engine,
            &self.settings,
            self.host_tempo_bpm,
            &self.events[..count],
        );
        let (allocations, time) = counting_allocations(|| {
            timed(|| {
                let _flush = FlushDenormals::enable();
                engine.set_settings(settings);
                engine.set_host_tempo(tempo);
                engine.process(events, output);
                // As the plugin's tuning worker takes it after every block.
                let _ = engine.take_wanted_tuning_plan();
            })
        });
        self.counts.allocations += allocations;
        self.counts.blocks += 1;
        for sample in output.iter() {
            if !sample.is_finite() {
                self.counts.non_finite_samples += 1;
            }
            self.counts.output_hash = (self.counts.output_hash ^ u64::from(sample.to_bits()))
                .wrapping_mul(0x0000_0100_0000_01b3);
        }
        self.block_index += 1;
        time
    }
}

// ---------------------------------------------------------------------------------------------
// The run and its report.

/// Block times as fractions of the deadline: 99.9th percentile, worst, median.
#[derive(Debug, Clone, Copy)]
pub struct Summary {
    pub p999: f64,
    pub worst: f64,
    pub median: f64,
}

/// Block times of a stretch of blocks, as fractions of the deadline, by both clocks.
#[derive(Debug, Default)]
struct Loads {
    wall: Vec<f64>,
    cpu: Vec<f64>,
}

impl Loads {
    fn push(&mut self, time: BlockTime) {
        let deadline_s = BLOCK as f64 / SAMPLE_RATE;
        self.wall.push(time.wall_s / deadline_s);
        self.cpu.push(time.cpu_s / deadline_s);
    }

    fn summarise(&mut self, start_s: f64) -> WindowReport {
        let summary = |loads: &mut Vec<f64>| {
            loads.sort_by(f64::total_cmp);
            Summary {
                p999: percentile(loads, 0.999),
                worst: *loads.last().unwrap_or(&0.0),
                median: percentile(loads, 0.5),
            }
        };
        let report = WindowReport {
            start_s,
            blocks: self.wall.len(),
            wall: summary(&mut self.wall),
            cpu: summary(&mut self.cpu),
        };
        self.wall.clear();
        self.cpu.clear();
        report
    }
}

/// One window of simulated time.
#[derive(Debug, Clone, Copy)]
pub struct WindowReport {
    pub start_s: f64,
    pub blocks: usize,
    pub wall: Summary,
    pub cpu: Summary,
}

/// Runs the scene for `seconds`, calling `window_done` after each window of `window_s`
/// (windows are cut at whole multiples of `window_s` in simulated time).
pub fn run_scene(
    scene: &mut SoakScene,
    seconds: f64,
    window_s: f64,
    mut window_done: impl FnMut(&WindowReport, &SoakCounts),
) -> Vec<WindowReport> {
    let block_s = BLOCK as f64 / SAMPLE_RATE;
    let total_blocks = seconds_to_blocks(seconds);
    let window_of = |block: u64| (block as f64 * block_s / window_s) as u64;
    let mut loads = Loads::default();
    let mut windows = Vec::new();
    let mut output = [0.0f32; BLOCK];
    for block in 0..total_blocks {
        loads.push(scene.render_block(&mut output));
        if block + 1 == total_blocks || window_of(block + 1) != window_of(block) {
            let report = loads.summarise(window_of(block) as f64 * window_s);
            window_done(&report, &scene.counts);
            windows.push(report);
        }
    }
    windows
}

/// Block times of one string that has rung a minute, beside the same string fresh.
#[derive(Debug, Clone, Copy)]
pub struct AgeProbe {
    pub flush_denormals: bool,
    pub fresh: WindowReport,
    pub aged: WindowReport,
    pub non_finite_samples: u64,
}

/// One string (A3) plucked at `quality` with the least damping the plugin allows (γ = 0, so it
/// still rings after a minute; η keeps its seed value, so the upper partials decay through the
/// subnormal range), alone in the engine: block times over seconds 1–6 after the pluck (fresh)
/// and 61–66 (a minute old).
pub fn age_probe(quality: Quality, flush_denormals: bool) -> AgeProbe {
    let mut settings = EngineSettings::default();
    settings.voice.quality = quality;
    settings.voice.gamma_per_s = 0.0;
    let mut engine = Engine::new(&settings, SAMPLE_RATE, DEFAULT_VOICE_COUNT);
    let pluck = [TimedEvent::note_on(0, 57, 1.0)];
    let mut output = [0.0f32; BLOCK];
    let (fresh_from, aged_from, span) = (
        seconds_to_blocks(1.0),
        seconds_to_blocks(61.0),
        seconds_to_blocks(5.0),
    );
    let (mut fresh, mut aged) = (Loads::default(), Loads::default());
    let mut non_finite_samples = 0;
    for block in 0..aged_from + span {
        let events = if block == 0 { &pluck[..] } else { &[] };
        let time = timed(|| {
            let _flush = flush_denormals.then(FlushDenormals::enable);
            engine.set_settings(&settings);
            engine.process(events, &mut output);
        });
        non_finite_samples += output.iter().filter(|x| !x.is_finite()).count() as u64;
        if (fresh_from..fresh_from + span).contains(&block) {
            fresh.push(time);
        } else if block >= aged_from {
            aged.push(time);
        }
    }
    AgeProbe {
        flush_denormals,
        fresh: fresh.summarise(1.0),
        aged: aged.summarise(61.0),
        non_finite_samples,
    }
}

fn percent(fraction: f64) -> String {
    format!("{:.1} %", 100.0 * fraction)
}

pub fn run(args: SoakArgs) -> Result<(), Box<dyn Error>> {
    let seconds = args.minutes * 60.0;
    println!(
        "soak: {:.1} simulated minutes, seed {}, {} parameter changes/s, {} tier{}, \
         {BLOCK}-sample blocks at {} Hz, {DEFAULT_VOICE_COUNT} voices; block time as a fraction \
         of its {:.3} ms deadline",
        args.minutes,
        args.seed,
        args.changes_per_second,
        args.quality.name(),
        if args.automate_quality {
            " (tier automated)"
        } else {
            ""
        },
        SAMPLE_RATE,
        1e3 * BLOCK as f64 / SAMPLE_RATE,
    );
    println!(
        "| window (simulated) | wall p99.9 | wall worst | CPU p99.9 | CPU worst | CPU median |"
    );
    println!("|---|---|---|---|---|---|");
    let started = Instant::now();
    let mut scene = SoakScene::new(
        args.seed,
        args.quality,
        args.automate_quality,
        args.changes_per_second,
    );
    let windows = run_scene(&mut scene, seconds, args.window_s, |window, _| {
        println!(
            "| {:.0}–{:.0} s | {} | {} | {} | {} | {} |",
            window.start_s,
            window.start_s + window.blocks as f64 * BLOCK as f64 / SAMPLE_RATE,
            percent(window.wall.p999),
            percent(window.wall.worst),
            percent(window.cpu.p999),
            percent(window.cpu.worst),
            percent(window.cpu.median),
        );
        let _ = std::io::stdout().flush();
    });
    let wall_s = started.elapsed().as_secs_f64();
    let counts = scene.counts;
    let highest = |pick: fn(&WindowReport) -> f64| windows.iter().map(pick).fold(0.0, f64::max);
    println!(
        "\nrun: {} blocks in {wall_s:.1} s of wall time ({:.2}× real time); over all windows: \
         wall p99.9 at most {}, worst {}; CPU p99.9 at most {}, worst {}",
        counts.blocks,
        seconds / wall_s,
        percent(highest(|w| w.wall.p999)),
        percent(highest(|w| w.wall.worst)),
        percent(highest(|w| w.cpu.p999)),
        percent(highest(|w| w.cpu.worst)),
    );
    println!(
        "played: {} notes, {} parameter changes ({} of them NaN, ±∞ or far out of range)",
        counts.note_ons, counts.parameter_changes, counts.hostile_changes
    );
    println!(
        "audio path: {} allocations, {} non-finite samples",
        counts.allocations, counts.non_finite_samples
    );

    println!(
        "\nstring age ({} tier, A3, γ = 0): block time 1–6 s (fresh) and 61–66 s (a minute old) \
         after the pluck",
        args.quality.name()
    );
    println!(
        "| subnormals | fresh CPU median | fresh CPU p99.9 | old CPU median | old CPU p99.9 | \
         fresh wall p99.9 | old wall p99.9 |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut probe_non_finite = 0;
    for flush in [true, false] {
        let probe = age_probe(args.quality, flush);
        probe_non_finite += probe.non_finite_samples;
        println!(
            "| {} | {} | {} | {} | {} | {} | {} |",
            if probe.flush_denormals {
                "flushed (as the plugin runs)"
            } else {
                "IEEE (not flushed)"
            },
            percent(probe.fresh.cpu.median),
            percent(probe.fresh.cpu.p999),
            percent(probe.aged.cpu.median),
            percent(probe.aged.cpu.p999),
            percent(probe.fresh.wall.p999),
            percent(probe.aged.wall.p999),
        );
    }

    if counts.allocations > 0 || counts.non_finite_samples > 0 || probe_non_finite > 0 {
        return Err(format!(
            "the audio path allocated {} times and produced {} non-finite samples ({} in the \
             string-age probe); both must be 0",
            counts.allocations, counts.non_finite_samples, probe_non_finite
        )
        .into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The soak's loop for a few simulated seconds at the plugin's default tier: notes played,
    /// parameters changed (hostile values included), no allocation on the audio path, no
    /// non-finite sample; the same seed replays the same output and another seed does not.
    #[test]
    fn a_short_soak_allocates_nothing_and_stays_finite() {
        let run = |seed| {
            let mut scene = SoakScene::new(seed, Quality::Fine, false, CHANGES_PER_SECOND);
            let windows = run_scene(&mut scene, 6.0, 2.0, |_, _| {});
            assert_eq!(windows.len(), 3);
            scene.counts
        };
        let counts = run(7);
        println!("{counts:?}");
        assert_eq!(counts.allocations, 0, "allocations on the audio path");
        assert_eq!(counts.non_finite_samples, 0);
        assert!(counts.note_ons >= 3, "{counts:?}");
        assert!(counts.parameter_changes >= 20, "{counts:?}");
        assert_eq!(run(7), counts, "a seed replays its run");
        assert_ne!(run(8).output_hash, counts.output_hash);
    }

    /// The counter sees an allocation made on the audio path, and only there.
    #[test]
    fn the_counter_sees_audio_path_allocations() {
        let (allocations, vector) = counting_allocations(|| Vec::<u8>::with_capacity(10));
        assert!(allocations >= 1);
        drop(vector);
        let (allocations, ()) = counting_allocations(|| ());
        assert_eq!(allocations, 0);
    }

    /// Every tier survives the automated scene, tier switches included.
    #[test]
    fn tier_automation_stays_finite() {
        let mut scene = SoakScene::new(3, Quality::Live, true, CHANGES_PER_SECOND);
        run_scene(&mut scene, 2.0, 2.0, |_, _| {});
        assert_eq!(scene.counts.allocations, 0);
        assert_eq!(scene.counts.non_finite_samples, 0);
    }
}
