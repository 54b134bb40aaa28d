//! The playing engine: MIDI-like events in, audio out, shared by the plugin and the offline
//! renderer so that both make exactly the same sound.
//!
//! What it does, and where:
//! - a pool of [`TanpuraVoice`] strings (polyphonic). A string rings on after note-off, as a real
//!   string does; a voice is taken from another string only by a new pluck: a string already
//!   tuned to the note is plucked again, else a silent voice is used, else the quietest (then the
//!   oldest) ringing one is stolen (`Engine::choose_voice`);
//! - note to pitch: 12-TET from a reference A4 (415–466 Hz) with fine tuning ([`pitch`]);
//! - drone mode ([`drone`]): a held note (or the settings' Sa) sets Sa and the strings (4, 5 or
//!   6, each with its own fine tuning, level and thread) are plucked in the cycle at the host's
//!   tempo;
//! - each string tuned by its sustained pitch as played, from calibrations measured off the audio
//!   thread (`tanpura/as_played.rs`, [`Engine::set_calibration`]);
//! - stereo ([`Engine::process_stereo`]): the strings spread over the image by a side signal,
//!   the mid exactly the mono output;
//! - a change of quality tier applies to each string from its next pluck (a voice switching tier
//!   restarts at rest, which would silence a ringing string);
//! - smoothing of continuous settings in SI units ([`smoothing`]): the string settings move at
//!   a control rate of one update every [`CONTROL_INTERVAL`] samples (a string's settings change
//!   rebuilds its step matrix, so it is not done per sample), reaching the target in
//!   [`SMOOTHING_TIME_S`]; the output gain ramps per sample;
//! - sample-accurate events: [`Engine::process`] splits the block at every event, control tick
//!   and drone pluck. All of these sit at absolute sample times, so the output does not depend on
//!   the block size. Offline ([`Engine::process_with`]) a segment runs on through the control
//!   ticks that would change nothing, so that its voices run as longer tasks on the threads,
//!   with the same samples (`Engine::control_ticks_are_idle`);
//! - the output level: see [`NEWTONS_AT_FULL_SCALE`];
//! - the boundary with the host: settings pass through [`EngineSettings::clamped`] and events
//!   through [`EngineEvent::sanitised`], so a non-finite or out-of-range value from automation
//!   or MIDI is clamped (NaN takes the default) before it reaches a string;
//! - the output latency a host must compensate ([`Engine::latency_samples`]): the latency of the
//!   tier in use, the decimator's delay at the oversampled tiers, studio and reference (29 samples
//!   at 44.1 kHz), or none for the tiers at the output rate and the bowed string. It is fixed when
//!   the engine is built and when the plugin adopts the tier's latency at activation
//!   ([`Engine::adopt_tier_latency`]); a change of tier between two activations applies to each
//!   string from its next pluck, and the plugin asks the host to restart it so that the reported
//!   latency follows ([`Engine::tier_latency_samples`] says what it will be). A voice whose own
//!   latency is lower than the reported one is delayed to match (`OutputDelay`); one whose latency
//!   is higher (an FD string still ringing after a switch to a modal tier, until the host restarts
//!   the plugin) sounds that much late.
//!
//! Lifecycle (design.md): [`Engine::new`] allocates every voice; [`Engine::process`],
//! [`Engine::set_settings`], [`Engine::set_host_tempo`] and [`Engine::reset`] never allocate,
//! lock or panic.

pub mod bowed_stability;
pub mod drone;
pub mod midi_file;
pub mod pitch;
pub mod preset;
pub mod render;
pub mod smoothing;
pub mod tuning_memory;
pub mod wav;

use crate::bowed::{BowedEvent, BowedInstrument, BowedPlayerSettings, StringConstants};
use crate::tanpura::as_played::{AsPlayedTuning, Calibration, CalibrationRequest, NOTE_VELOCITIES};
use crate::tanpura::body::{Body, TANPURA_BODY};
use crate::tanpura::excitation::Pluck;
use crate::tanpura::{reference_fundamental_hz, TanpuraVoice, VoiceSettings};
use drone::{string_ratios, DroneSequencer, DroneSettings};
use smoothing::Ramp;
use tuning_memory::{PlannedTension, TuningMemory, TuningPlan};

/// The pickup force, in newtons, that maps to digital full scale (±1.0) at 0 dB output gain,
/// for a string at the reference pitch ([`reference_fundamental_hz`]).
///
/// Measured (`default_pluck_peaks_near_minus_12_dbfs`): the default pluck (2 mm at 0.35 m, 10 mm
/// finger) on the reference string peaks at about 0.49 N at the nut, so 2 N puts it near
/// −12 dBFS, which leaves headroom for several strings ringing together.
pub const NEWTONS_AT_FULL_SCALE: f64 = 2.0;
/// Longest output delay an [`OutputDelay`] holds, samples.
const MAX_OUTPUT_DELAY: usize = 64;

/// A fixed delay of up to [`MAX_OUTPUT_DELAY`] samples (a ring buffer), to bring a voice whose
/// own latency is lower up to the engine's reported latency. Allocation-free.
#[derive(Debug, Clone)]
struct OutputDelay {
    buffer: [f32; MAX_OUTPUT_DELAY],
    length: usize,
    position: usize,
}

impl OutputDelay {
    fn new(length: usize) -> Self {
        Self {
            buffer: [0.0; MAX_OUTPUT_DELAY],
            length: length.min(MAX_OUTPUT_DELAY),
            position: 0,
        }
    }

    /// Changes the delay (and clears it: what it held belongs to the old latency).
    fn set_length(&mut self, length: usize) {
        *self = Self::new(length);
    }

    fn clear(&mut self) {
        self.buffer.fill(0.0);
    }

    /// Pushes `value` in and returns the value `length` samples old.
    fn process(&mut self, value: f32) -> f32 {
        if self.length == 0 {
            return value;
        }
        let delayed = self.buffer[self.position];
        self.buffer[self.position] = value;
        self.position += 1;
        if self.position == self.length {
            self.position = 0;
        }
        delayed
    }
}

/// The latency `settings` ask for, whole samples at the output rate: the tanpura's tier's own
/// (the oversampled tiers' decimator delay, none for the tiers at the output rate), none for the
/// bowed string.
fn tier_latency(slots: &[Slot], settings: &EngineSettings) -> usize {
    if settings.instrument == Instrument::Bowed {
        return 0;
    }
    let latency = slots.first().map_or(0.0, |slot| {
        slot.voice.latency_samples_at(settings.voice.quality)
    });
    (latency.round() as usize).min(MAX_OUTPUT_DELAY)
}

/// Samples between two updates of the strings' smoothed settings.
pub const CONTROL_INTERVAL: u64 = 32;
/// Samples at least between two retunes of ringing strings to the smoothed settings (every other
/// control tick): a retune at the fine tier costs about a seventh of a 64-sample block's
/// deadline, so that a glide's retunes add at most one to each block (`Engine::control_tick`).
pub const RETUNE_INTERVAL: u64 = 2 * CONTROL_INTERVAL;
/// Time a continuous setting takes to reach a new value, s.
pub const SMOOTHING_TIME_S: f64 = 0.02;
/// The stereo width a new engine has (0–1).
pub const DEFAULT_STEREO_WIDTH: f64 = 0.5;
/// Notes this many semitones either side of middle C sit at the stereo image's edges.
const NOTE_PAN_SPAN_SEMITONES: f64 = 24.0;
/// Output gain range, dB.
pub const OUTPUT_GAIN_RANGE_DB: (f64, f64) = (-60.0, 24.0);
/// Time constant of each voice's level follower (used to pick the quietest voice to steal), s.
const LEVEL_RELEASE_S: f64 = 0.05;

/// The bowed voice's force, in newtons at the bridge, that maps to full scale at 0 dB gain: a
/// violin-A note at mid pressure peaks near −10 dBFS (`bowed_note_level`).
pub const BOWED_NEWTONS_AT_FULL_SCALE: f64 = 2.0;

/// Which instrument the engine plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Instrument {
    /// Plucked tanpura strings (polyphonic, drone mode).
    #[default]
    Tanpura,
    /// One bowed string (monophonic, legato), `bowed/instrument.rs`.
    Bowed,
}

/// The bowed string's physical constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BowedStringKind {
    #[default]
    ViolinA,
    CelloD,
}

impl BowedStringKind {
    pub const ALL: [BowedStringKind; 2] = [BowedStringKind::ViolinA, BowedStringKind::CelloD];

    pub fn constants(self) -> StringConstants {
        match self {
            BowedStringKind::ViolinA => StringConstants::violin_a(),
            BowedStringKind::CelloD => StringConstants::cello_d(),
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// The bowed instrument's settings: the player's, the string, and the bow controls that knobs
/// set (MIDI controllers move them too; whichever moved last wins).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BowedEngineSettings {
    pub player: BowedPlayerSettings,
    pub string: BowedStringKind,
    /// Bow pressure, 0–1: the bow force as a fraction of Schelleng's range.
    pub pressure: f64,
    /// Bow speed, m/s (0.02–1).
    pub bow_velocity_m_s: f64,
    /// Bow position β (0.02–0.5).
    pub bow_position: f64,
}

impl Default for BowedEngineSettings {
    fn default() -> Self {
        Self {
            player: BowedPlayerSettings::default(),
            string: BowedStringKind::ViolinA,
            pressure: 0.5,
            bow_velocity_m_s: 0.2,
            bow_position: 0.1,
        }
    }
}

/// What the tanpura's output is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TanpuraOutput {
    /// The strings' forces at the nut and the bridge, mixed by
    /// [`VoiceSettings::nut_pickup_weight`] (1: the nut force, the seed's signal; 0: the bridge
    /// force).
    #[default]
    Pickup,
    /// The sound the body radiates: the total bridge force of all strings through the body's
    /// resonances (`tanpura/body.rs`, fitted to the response measured in DAFx-16).
    Radiated,
}

/// Everything the engine plays with, in SI units (normalised mappings live in the plugin).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineSettings {
    /// Settings shared by every string; `fundamental_hz` is ignored (each string has its note's
    /// pitch).
    pub voice: VoiceSettings,
    /// The pluck used for every note, at full velocity (amplitude scales with velocity).
    pub pluck: Pluck,
    /// Output gain, dB (−60 to +24), applied after [`NEWTONS_AT_FULL_SCALE`].
    pub output_gain_db: f64,
    pub drone: DroneSettings,
    pub instrument: Instrument,
    pub bowed: BowedEngineSettings,
    /// The tanpura's output: pickup forces or the body's radiated sound.
    pub tanpura_output: TanpuraOutput,
    /// Reference pitch and fine tuning of every note (MIDI notes and the drone's Sa).
    pub tuning: pitch::Tuning,
    /// How far the strings spread over the stereo image ([`Engine::process_stereo`]), 0–1
    /// (0: both channels the same).
    pub stereo_width: f64,
}

impl Default for EngineSettings {
    fn default() -> Self {
        Self {
            voice: VoiceSettings::default(),
            pluck: Pluck::default(),
            output_gain_db: 0.0,
            drone: DroneSettings::default(),
            instrument: Instrument::Tanpura,
            bowed: BowedEngineSettings::default(),
            tanpura_output: TanpuraOutput::Pickup,
            tuning: pitch::Tuning::default(),
            stereo_width: DEFAULT_STEREO_WIDTH,
        }
    }
}

/// `value` within `range`; NaN becomes `fallback` (±∞ clamps to the nearer end).
fn clamp_or(value: f64, (min, max): (f64, f64), fallback: f64) -> f64 {
    if value.is_nan() {
        fallback
    } else {
        value.clamp(min, max)
    }
}

impl EngineSettings {
    /// The nearest valid settings: every number within its documented range, NaN replaced by
    /// the default. What the engine applies, so that whatever a host sends (a NaN from broken
    /// automation, a value far outside a range from a foreign state) reaches no string.
    pub fn clamped(&self) -> Self {
        use preset::{
            BOW_GLIDE_RANGE_S, BOW_POSITION_RANGE, BOW_VELOCITY_RANGE_M_S, BOW_VIBRATO_RANGE_CENTS,
            PLUCK_POSITION_RANGE_M,
        };
        let default = Self::default();
        let (pluck, bowed, player) = (self.pluck, self.bowed, self.bowed.player);
        let default_player = default.bowed.player;
        Self {
            voice: self.voice.clamped(),
            pluck: Pluck {
                position_m: clamp_or(
                    pluck.position_m,
                    PLUCK_POSITION_RANGE_M,
                    default.pluck.position_m,
                ),
                width_m: clamp_or(pluck.width_m, Pluck::WIDTH_RANGE_M, default.pluck.width_m),
                amplitude_m: clamp_or(
                    pluck.amplitude_m,
                    Pluck::AMPLITUDE_RANGE_M,
                    default.pluck.amplitude_m,
                ),
            },
            output_gain_db: clamp_or(
                self.output_gain_db,
                OUTPUT_GAIN_RANGE_DB,
                default.output_gain_db,
            ),
            drone: DroneSettings {
                free_tempo_bpm: clamp_or(
                    self.drone.free_tempo_bpm,
                    drone::TEMPO_RANGE_BPM,
                    default.drone.free_tempo_bpm,
                ),
                pluck_spacing_beats: clamp_or(
                    self.drone.pluck_spacing_beats,
                    drone::PLUCK_SPACING_RANGE_BEATS,
                    default.drone.pluck_spacing_beats,
                ),
                cycle_pause_beats: clamp_or(
                    self.drone.cycle_pause_beats,
                    drone::CYCLE_PAUSE_RANGE_BEATS,
                    default.drone.cycle_pause_beats,
                ),
                humanize_timing_s: clamp_or(
                    self.drone.humanize_timing_s,
                    drone::HUMANIZE_TIMING_RANGE_S,
                    default.drone.humanize_timing_s,
                ),
                humanize_strength: clamp_or(
                    self.drone.humanize_strength,
                    drone::HUMANIZE_STRENGTH_RANGE,
                    default.drone.humanize_strength,
                ),
                strings: self.drone.strings.map(|string| string.clamped()),
                sa_note: self.drone.sa_note.map(|note| note.min(127)),
                ..self.drone
            },
            instrument: self.instrument,
            tanpura_output: self.tanpura_output,
            stereo_width: clamp_or(self.stereo_width, (0.0, 1.0), default.stereo_width),
            tuning: pitch::Tuning {
                a4_hz: clamp_or(self.tuning.a4_hz, pitch::A4_RANGE_HZ, default.tuning.a4_hz),
                fine_tune_cents: clamp_or(
                    self.tuning.fine_tune_cents,
                    pitch::FINE_TUNE_RANGE_CENTS,
                    default.tuning.fine_tune_cents,
                ),
                as_played: self.tuning.as_played,
            },
            bowed: BowedEngineSettings {
                player: BowedPlayerSettings {
                    glide_time_s: clamp_or(
                        player.glide_time_s,
                        BOW_GLIDE_RANGE_S,
                        default_player.glide_time_s,
                    ),
                    vibrato_rate_hz: clamp_or(
                        player.vibrato_rate_hz,
                        BowedPlayerSettings::VIBRATO_RATE_RANGE_HZ,
                        default_player.vibrato_rate_hz,
                    ),
                    max_vibrato_cents: clamp_or(
                        player.max_vibrato_cents,
                        BOW_VIBRATO_RANGE_CENTS,
                        default_player.max_vibrato_cents,
                    ),
                    pitch_bend_range_semitones: clamp_or(
                        player.pitch_bend_range_semitones,
                        BowedPlayerSettings::PITCH_BEND_RANGE_SEMITONES,
                        default_player.pitch_bend_range_semitones,
                    ),
                    bow_lift_time_s: clamp_or(
                        player.bow_lift_time_s,
                        BowedPlayerSettings::BOW_LIFT_TIME_RANGE_S,
                        default_player.bow_lift_time_s,
                    ),
                    ..player
                },
                pressure: clamp_or(bowed.pressure, (0.0, 1.0), default.bowed.pressure),
                bow_velocity_m_s: clamp_or(
                    bowed.bow_velocity_m_s,
                    BOW_VELOCITY_RANGE_M_S,
                    default.bowed.bow_velocity_m_s,
                ),
                bow_position: clamp_or(
                    bowed.bow_position,
                    BOW_POSITION_RANGE,
                    default.bowed.bow_position,
                ),
                ..bowed
            },
        }
    }
}

/// A musical event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EngineEvent {
    /// `velocity` in (0, 1]; a note-on with velocity 0 is a note-off, as in MIDI.
    NoteOn { note: u8, velocity: f32 },
    /// Releases a held note (drone mode); a plucked string rings on regardless.
    NoteOff { note: u8 },
    /// Releases every held note; strings ring on.
    AllNotesOff,
    /// Silences every string at once.
    AllSoundOff,
    /// A control change, value 0–1 (the bowed instrument maps CC 1, 2, 11 and 74).
    Controller { number: u8, value: f32 },
    /// Channel pressure (aftertouch), 0–1.
    ChannelPressure(f32),
    /// Per-note pressure (polyphonic aftertouch, MPE), 0–1.
    PolyPressure { note: u8, value: f32 },
    /// Pitch bend, −1 to 1.
    PitchBend(f32),
}

impl EngineEvent {
    /// The event with its value inside its documented range, or `None` when the value is not a
    /// number at all (NaN or ±∞ say nothing about what the player meant, so the event is
    /// dropped rather than guessed).
    pub fn sanitised(self) -> Option<Self> {
        let unit = |value: f32| value.is_finite().then(|| value.clamp(0.0, 1.0));
        Some(match self {
            EngineEvent::NoteOn { note, velocity } => EngineEvent::NoteOn {
                note,
                velocity: unit(velocity)?,
            },
            EngineEvent::Controller { number, value } => EngineEvent::Controller {
                number,
                value: unit(value)?,
            },
            EngineEvent::ChannelPressure(value) => EngineEvent::ChannelPressure(unit(value)?),
            EngineEvent::PolyPressure { note, value } => EngineEvent::PolyPressure {
                note,
                value: unit(value)?,
            },
            EngineEvent::PitchBend(value) => {
                EngineEvent::PitchBend(value.is_finite().then(|| value.clamp(-1.0, 1.0))?)
            }
            EngineEvent::NoteOff { .. } | EngineEvent::AllNotesOff | EngineEvent::AllSoundOff => {
                self
            }
        })
    }
}

/// An event at a sample offset within the block passed to [`Engine::process`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimedEvent {
    pub offset: usize,
    pub event: EngineEvent,
}

impl TimedEvent {
    /// A note-on of `note` at `velocity` (0–1) at sample `offset` of the block.
    pub fn note_on(offset: usize, note: u8, velocity: f32) -> Self {
        Self {
            offset,
            event: EngineEvent::NoteOn { note, velocity },
        }
    }
}

/// What a voice currently is: which string of the instrument it plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum StringKey {
    Note(u8),
    Drone(usize),
}

#[derive(Debug, Clone)]
struct Slot {
    voice: TanpuraVoice,
    key: Option<StringKey>,
    /// The note the string sounds (its key's pitch).
    fundamental_hz: f64,
    /// What its linearised tuning aims at: the note moved by its as-played offset.
    tuned_hz: f64,
    /// How far its as-played calibration moved its thread, m (`tanpura/as_played.rs`).
    thread_set_m: f64,
    /// Output scaling that keeps the level independent of pitch (see [`pitch_level_factor`]),
    /// fixed at the pluck.
    pitch_level: f64,
    /// `pitch_level` times a drone string's own level.
    level_factor: f64,
    /// Where the string sits in the stereo image, −1 (left) to 1 (right), before the width.
    pan: f32,
    /// Brings the string's own latency (its tier's) up to the engine's.
    delay: OutputDelay,
    /// Absolute sample of the last pluck.
    plucked_at: u64,
    /// Peak-following level of the scaled output, for stealing.
    level: f32,
}

impl Slot {
    /// The delay that brings this string's own latency (its tier's) up to `latency`.
    fn padding_to(&self, latency: usize) -> usize {
        latency.saturating_sub(self.voice.latency_samples().round() as usize)
    }
}

/// Samples a voice renders at a time in [`run_slot`] (a stack buffer).
const VOICE_RUN: usize = 64;

/// Runs `slot`'s voice for `length` samples, handing each scaled sample to `emit(index, value)`,
/// and updates the slot's level. A voice that blows up is silenced and emits nothing more.
///
/// `first_tick` is the index of the first control tick inside the run (the ticks follow every
/// [`CONTROL_INTERVAL`] samples; one at or beyond `length` is none). A segment of the audio
/// thread ends at its next tick, so it has none inside; an offline segment runs through the
/// ticks that change nothing (`Engine::control_ticks_are_idle`), and at each of them the voice
/// is looked at as a segment starting there would look at it: asleep, it stops and its level
/// is 0. So the samples and the level do not depend on where the segments end.
fn run_slot(
    slot: &mut Slot,
    release: f32,
    length: usize,
    first_tick: usize,
    mut emit: impl FnMut(usize, f32),
) {
    if !slot.voice.is_active() {
        slot.level = 0.0;
        return;
    }
    let scale = (slot.level_factor / NEWTONS_AT_FULL_SCALE) as f32;
    let mut level = slot.level;
    // The voice renders a run of samples at a time (`TanpuraVoice::process`: the samples of
    // `next_sample`, with one dispatch to the vector unit per run for a modal string).
    let mut run = [0.0f32; VOICE_RUN];
    let mut start = 0;
    let mut next_tick = first_tick.max(1);
    'samples: while start < length {
        if start == next_tick {
            next_tick = next_tick.saturating_add(CONTROL_INTERVAL as usize);
            if !slot.voice.is_active() {
                level = 0.0;
                break;
            }
        }
        let count = (length - start).min(VOICE_RUN).min(next_tick - start);
        slot.voice.process(&mut run[..count]);
        for (index, &sample) in (start..).zip(&run[..count]) {
            let value = slot.delay.process(sample * scale);
            if !value.is_finite() {
                // Fail soft: a voice that blew up is silenced, never passed on.
                slot.voice.reset();
                slot.delay.clear();
                level = 0.0;
                break 'samples;
            }
            emit(index, value);
            level = value.abs().max(level * release);
        }
        start += count;
    }
    slot.level = level;
}

/// One sounding voice's share of a segment in [`Engine::process_with`]; [`VoiceTask::run`] may be
/// called on any thread, and each task touches only its own voice and buffer.
pub struct VoiceTask<'a> {
    slot: &'a mut Slot,
    release: f32,
    /// The first control tick inside the segment ([`run_slot`]).
    first_tick: usize,
    samples: &'a mut [f32],
    /// Samples produced: all of them, or fewer when the voice blew up and was silenced.
    written: usize,
}

impl VoiceTask<'_> {
    /// Computes this voice's samples for the segment.
    pub fn run(&mut self) {
        let samples = &mut *self.samples;
        let mut written = 0;
        run_slot(
            self.slot,
            self.release,
            samples.len(),
            self.first_tick,
            |index, value| {
                samples[index] = value;
                written = index + 1;
            },
        );
        self.written = written;
    }
}

/// Runs every task of a segment once, in any order and on any threads (e.g.
/// `|tasks| tasks.par_iter_mut().for_each(VoiceTask::run)` with rayon).
pub type VoiceRunner<'r> = &'r (dyn Fn(&mut [VoiceTask<'_>]) + Sync);

/// The tension, and with it the force at the nut and bridge for a given displacement, grows
/// with the square of the pitch. So that a pluck sounds equally loud on any note, each string's
/// force is multiplied by `(f_ref / f)²`.
pub fn pitch_level_factor(fundamental_hz: f64) -> f64 {
    let ratio = reference_fundamental_hz() / fundamental_hz;
    ratio * ratio
}

/// A drone string's place in the stereo image: the strings in playing order spread evenly from
/// left (−1) to right (1).
fn drone_string_pan(string: usize, count: usize) -> f32 {
    if count < 2 {
        return 0.0;
    }
    (2.0 * string.min(count - 1) as f64 / (count - 1) as f64 - 1.0) as f32
}

/// The soft and firm ends of a drone string's plucks (fractions of full): full strength, less
/// the humanisation's largest softening.
fn drone_velocities(drone: &DroneSettings) -> [f64; 2] {
    [1.0 - drone.humanize_strength, 1.0]
}

/// The polyphonic tanpura engine.
#[derive(Debug, Clone)]
pub struct Engine {
    sample_rate_hz: f64,
    slots: Vec<Slot>,
    target: EngineSettings,
    /// The smoothed shared string settings (fundamental ignored).
    current_voice: VoiceSettings,
    bridge_stiffness_log: Ramp,
    thread_position: Ramp,
    gamma: Ramp,
    eta: Ramp,
    pickup_weight: Ramp,
    output_gain: Ramp,
    drone: DroneSequencer,
    host_tempo_bpm: Option<f64>,
    /// Absolute sample index of the next sample to be produced.
    clock: u64,
    next_control_tick: u64,
    level_release: f32,
    /// One bowed instrument per string kind, built up front.
    bowed: Vec<BowedInstrument>,
    /// The engine's output latency, whole samples (see [`Engine::latency_samples`]).
    latency: usize,
    /// The slot [`Engine::control_tick`] looks at first for a string to retune.
    retune_cursor: usize,
    /// Whether a ringing string may still lack the current settings (set when they change,
    /// cleared by a control tick that finds none to retune).
    retune_pending: bool,
    /// The sample from which a ringing string may be retuned again ([`RETUNE_INTERVAL`]).
    next_retune: u64,
    /// Each drone string's level as an amplitude factor (from the settings, once per change).
    drone_levels: [f64; drone::MAX_DRONE_STRINGS],
    /// Brings the bowed string (no latency of its own) up to it.
    bowed_delay: OutputDelay,
    /// The bow controls last applied from the settings (knobs), to apply only their changes.
    applied_bow_controls: Option<(f64, f64, f64)>,
    /// One buffer per voice for [`Engine::process_with`] (empty until it is used).
    scratch: Vec<Vec<f32>>,
    /// The tanpura's body, between the strings' total bridge force and the output.
    body: Body,
    /// The same body for the side signal (the strings' panned bridge forces), so that the
    /// stereo image is the body's sound too.
    side_body: Body,
    /// Each string's tuning by its sustained pitch as played (`tanpura/as_played.rs`).
    as_played: AsPlayedTuning,
    /// Strings plucked without a current calibration, for the host to measure off the audio
    /// thread ([`Engine::take_wanted_calibration`]).
    wanted: [Option<CalibrationRequest>; WANTED_CAPACITY],
    /// The tensions strings were tuned to, by their settings (`tuning_memory.rs`).
    tunings: TuningMemory,
    /// The last plan the memory was prepared for or handed out to be
    /// ([`Engine::take_wanted_tuning_plan`]).
    planned: Option<TuningPlan>,
    /// The Sa the drone last plucked on, whose strings the tuning plan holds while no Sa is set
    /// in the settings (a held note's drone keeps its tensions after the note is released).
    last_drone_sa: Option<u8>,
}

/// Calibration requests an engine keeps until they are taken.
const WANTED_CAPACITY: usize = 8;

/// `ln(1 + k_b)`: stiffness ramps in a logarithmic domain (its range spans twelve decades) that
/// still contains 0.
fn stiffness_to_log(stiffness_n_m2: f64) -> f64 {
    stiffness_n_m2.ln_1p()
}

fn log_to_stiffness(log_value: f64) -> f64 {
    log_value.exp_m1().max(0.0)
}

fn db_to_amplitude(db: f64) -> f64 {
    10f64.powf(db / 20.0)
}

impl Engine {
    /// An engine with `voice_count` strings (at least 1) at `sample_rate_hz`. Allocates.
    pub fn new(settings: &EngineSettings, sample_rate_hz: f64, voice_count: usize) -> Self {
        let settings = &settings.clamped();
        let voice = settings.voice;
        let slots: Vec<Slot> = (0..voice_count.max(1))
            .map(|_| Slot {
                voice: TanpuraVoice::new(&voice, sample_rate_hz),
                key: None,
                fundamental_hz: voice.fundamental_hz,
                tuned_hz: voice.fundamental_hz,
                thread_set_m: 0.0,
                pitch_level: 1.0,
                level_factor: 1.0,
                pan: 0.0,
                delay: OutputDelay::new(0),
                plucked_at: 0,
                level: 0.0,
            })
            .collect();
        let control_steps =
            (SMOOTHING_TIME_S * sample_rate_hz / CONTROL_INTERVAL as f64).ceil() as u32;
        let gain_steps = (SMOOTHING_TIME_S * sample_rate_hz).ceil() as u32;
        let gain = db_to_amplitude(settings.output_gain_db);
        let latency = tier_latency(&slots, settings);
        let mut engine = Self {
            sample_rate_hz,
            slots,
            target: *settings,
            current_voice: voice,
            bridge_stiffness_log: Ramp::new(
                stiffness_to_log(voice.bridge_stiffness_n_m2),
                control_steps,
            ),
            thread_position: Ramp::new(voice.thread_position_m, control_steps),
            gamma: Ramp::new(voice.gamma_per_s, control_steps),
            eta: Ramp::new(voice.eta_s, control_steps),
            pickup_weight: Ramp::new(voice.nut_pickup_weight, control_steps),
            output_gain: Ramp::new(gain, gain_steps),
            drone: DroneSequencer::default(),
            host_tempo_bpm: None,
            clock: 0,
            next_control_tick: 0,
            level_release: (-1.0 / (LEVEL_RELEASE_S * sample_rate_hz)).exp() as f32,
            bowed: BowedStringKind::ALL
                .iter()
                .map(|kind| {
                    // A rate outside the bowed capacity (8 kHz–384 kHz) falls back to the
                    // nearest supported one; the tanpura accepts the same hosts.
                    let rate = sample_rate_hz.clamp(8_000.0, 384_000.0);
                    BowedInstrument::new(kind.constants(), settings.bowed.player, rate)
                        .expect("the clamped rate is inside the bowed capacity")
                })
                .collect(),
            applied_bow_controls: None,
            latency,
            retune_cursor: 0,
            retune_pending: false,
            next_retune: 0,
            drone_levels: settings.drone.strings.map(|string| string.level_factor()),
            bowed_delay: OutputDelay::new(latency),
            scratch: Vec::new(),
            body: Body::new(&TANPURA_BODY, sample_rate_hz),
            side_body: Body::new(&TANPURA_BODY, sample_rate_hz),
            as_played: AsPlayedTuning::default(),
            wanted: [None; WANTED_CAPACITY],
            tunings: TuningMemory::new(),
            planned: None,
            last_drone_sa: None,
        };
        engine.apply_bowed_settings();
        engine
    }

    fn bowed_mut(&mut self) -> &mut BowedInstrument {
        let index = self.target.bowed.string.index();
        &mut self.bowed[index]
    }

    /// Passes the bowed settings on; the knob-set bow controls only when they changed, so that
    /// MIDI controllers keep what they set until a knob moves.
    fn apply_bowed_settings(&mut self) {
        let bowed = self.target.bowed;
        for instrument in &mut self.bowed {
            instrument.set_settings(bowed.player);
        }
        let controls = (bowed.pressure, bowed.bow_velocity_m_s, bowed.bow_position);
        if self.applied_bow_controls != Some(controls) {
            self.applied_bow_controls = Some(controls);
            for instrument in &mut self.bowed {
                instrument.set_pressure(bowed.pressure);
                instrument.set_bow_velocity_m_s(bowed.bow_velocity_m_s);
                instrument.set_bow_position(bowed.bow_position);
            }
        }
    }

    /// Fills `snapshot` with the state of the loudest ringing string (when none rings, the one
    /// plucked last, at rest), the Newton statistics of all strings, and the factor that turns
    /// this engine's output back into pickup force. For the editor's live view
    /// (`crate::snapshot`); allocation-free, never panics.
    pub fn fill_snapshot(&self, snapshot: &mut crate::snapshot::TanpuraSnapshot) {
        let Some(shown) = self.slots.iter().max_by(|a, b| {
            a.voice
                .is_active()
                .cmp(&b.voice.is_active())
                .then(a.level.total_cmp(&b.level))
                .then(a.plucked_at.cmp(&b.plucked_at))
        }) else {
            return;
        };
        if self.target.instrument == Instrument::Bowed {
            snapshot
                .bowed
                .fill(&self.bowed[self.target.bowed.string.index()]);
        } else {
            snapshot.bowed.active = false;
        }
        let string = shown.voice.string();
        snapshot.fill_string(string);
        snapshot.active_voices = self.active_voices();
        snapshot.fundamental_hz = shown.fundamental_hz;
        snapshot.sample_rate_hz = self.sample_rate_hz;
        snapshot.oversample = (1.0 / (string.time_step_s() * self.sample_rate_hz)).round() as u32;
        snapshot.newton = self.newton_stats();
        // Output = force · level_factor / NEWTONS_AT_FULL_SCALE · gain (`render_segment`).
        let gain = self.output_gain.value();
        snapshot.output_to_force_n = if gain > 0.0 && shown.level_factor > 0.0 {
            NEWTONS_AT_FULL_SCALE / (shown.level_factor * gain)
        } else {
            0.0
        };
    }

    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    pub fn voice_count(&self) -> usize {
        self.slots.len()
    }

    /// Newton statistics of every string together, since each string's last reset.
    pub fn newton_stats(&self) -> crate::newton::NewtonStats {
        let mut stats = crate::newton::NewtonStats::default();
        for slot in &self.slots {
            stats.merge(slot.voice.newton_stats());
        }
        stats
    }

    /// Number of strings currently computing.
    pub fn active_voices(&self) -> usize {
        self.slots
            .iter()
            .filter(|slot| slot.voice.is_active())
            .count()
    }

    /// New targets. Continuous settings (k_b, thread position, γ, η, pickup mix, gain) glide
    /// there over [`SMOOTHING_TIME_S`]; switches and quality apply at the next control tick; the
    /// pluck applies from the next pluck. Allocation-free; out-of-range values are clamped.
    pub fn set_settings(&mut self, settings: &EngineSettings) {
        let previous_strings = self.target.drone.strings;
        self.target = settings.clamped();
        if self.target.drone.strings != previous_strings {
            // A drone string's thread may have moved.
            self.retune_pending = true;
        }
        let voice = self.target.voice;
        self.bridge_stiffness_log
            .set_target(stiffness_to_log(voice.bridge_stiffness_n_m2));
        self.thread_position.set_target(voice.thread_position_m);
        self.gamma.set_target(voice.gamma_per_s);
        self.eta.set_target(voice.eta_s);
        self.pickup_weight.set_target(voice.nut_pickup_weight);
        self.output_gain
            .set_target(db_to_amplitude(self.target.output_gain_db));
        self.drone_levels = self
            .target
            .drone
            .strings
            .map(|string| string.level_factor());
        self.apply_bowed_settings();
    }

    /// The settings being applied (after [`EngineSettings::clamped`]).
    pub fn settings(&self) -> &EngineSettings {
        &self.target
    }

    /// The output latency a host must compensate, samples at the output rate: the latency of the
    /// tier the engine was built with or last adopted ([`Engine::adopt_tier_latency`]); voices
    /// with less latency of their own are delayed to it.
    pub fn latency_samples(&self) -> f64 {
        self.latency as f64
    }

    /// The latency the current settings ask for: the decimator's delay (whole samples) for the
    /// tanpura at the oversampled tiers (studio and reference, 29 samples either at 44.1 kHz),
    /// none for the tiers at the output rate and the bowed string. When it differs from
    /// [`Engine::latency_samples`], the plugin asks the host for a restart and adopts it at the
    /// next activation.
    pub fn tier_latency_samples(&self) -> f64 {
        tier_latency(&self.slots, &self.target) as f64
    }

    /// Makes the tier's latency ([`Engine::tier_latency_samples`]) the reported one: every
    /// voice's delay is set to make up the difference to its own latency, and cleared (the
    /// plugin calls this at activation, where the host expects a discontinuity).
    /// Allocation-free.
    pub fn adopt_tier_latency(&mut self) {
        self.latency = tier_latency(&self.slots, &self.target);
        for slot in &mut self.slots {
            slot.delay.set_length(slot.padding_to(self.latency));
        }
        self.bowed_delay.set_length(self.latency);
    }

    /// Adds a string's as-played calibration (measured off the audio thread with
    /// [`Calibration::measure`]); it applies from that string's next pluck. Allocation-free.
    pub fn set_calibration(&mut self, calibration: &Calibration) {
        self.as_played.insert(*calibration);
    }

    /// [`Engine::set_calibration`] with the tension that tunes the calibrated string
    /// ([`Calibration::calibrated_tension_n`], found off the audio thread where the calibration
    /// was measured): the engine remembers it (`tuning_memory.rs`), so the string's next pluck
    /// configures it once instead of tuning it on the audio thread. A calibration for another
    /// sample rate, or one the engine does not take, remembers nothing. Allocation-free.
    pub fn set_calibration_tuned(&mut self, calibration: &Calibration, tension_n: f64) {
        self.set_calibration(calibration);
        if calibration.sample_rate_hz != self.sample_rate_hz {
            return;
        }
        if let Some(settings) = calibration.calibrated_settings() {
            self.tunings.remember(&settings, tension_n);
        }
    }

    /// The calibrations the engine tunes with.
    pub fn as_played_tuning(&self) -> &AsPlayedTuning {
        &self.as_played
    }

    /// A string that was plucked without a current calibration: the host measures it off the audio thread and hands it
    /// back through [`Engine::set_calibration`]. Allocation-free.
    pub fn take_wanted_calibration(&mut self) -> Option<CalibrationRequest> {
        self.wanted.iter_mut().find_map(Option::take)
    }

    /// The settings of every string that a score of `notes` (note numbers, in any order, repeats
    /// allowed) plucks with these settings: each note's string, or in drone mode each string of
    /// the drone on each note as Sa. What an offline renderer calibrates before it renders
    /// (before glides: the targets' settings). Allocates.
    pub fn planned_strings(settings: &EngineSettings, notes: &[u8]) -> Vec<CalibrationRequest> {
        let settings = settings.clamped();
        let mut strings: Vec<CalibrationRequest> = Vec::new();
        let mut add = |fundamental_hz: f64, thread_offset_m: f64, velocities: [f64; 2]| {
            let (low, high) = VoiceSettings::FUNDAMENTAL_RANGE_HZ;
            if !(low..=high).contains(&fundamental_hz) {
                return;
            }
            let mut voice = settings.voice;
            voice.fundamental_hz = fundamental_hz;
            voice.thread_position_m += thread_offset_m;
            if settings.tanpura_output == TanpuraOutput::Radiated {
                voice.nut_pickup_weight = 0.0;
            }
            let request = CalibrationRequest {
                settings: voice.clamped(),
                pluck: settings.pluck.clamped(),
                velocities,
            };
            if !strings.contains(&request) {
                strings.push(request);
            }
        };
        let fixed_sa = settings.drone.sa_note.filter(|_| settings.drone.enabled);
        let notes: &[u8] = match &fixed_sa {
            Some(sa) => std::slice::from_ref(sa),
            None => notes,
        };
        for &note in notes {
            let hz = settings.tuning.note_hz(note);
            if settings.drone.enabled {
                let drone = settings.drone;
                for (fundamental_hz, thread_offset_m) in drone.string_pitches(hz) {
                    add(fundamental_hz, thread_offset_m, drone_velocities(&drone));
                }
            } else {
                add(hz, 0.0, NOTE_VELOCITIES);
            }
        }
        strings
    }

    /// The host's tempo for the drone, beats per minute (None when the host reports none).
    pub fn set_host_tempo(&mut self, tempo_bpm: Option<f64>) {
        self.host_tempo_bpm = tempo_bpm.filter(|tempo| tempo.is_finite() && *tempo > 0.0);
    }

    /// Silences every string, releases every note and jumps the smoothed settings to their
    /// targets. The clock restarts at 0, so a reset engine renders exactly as a new one.
    pub fn reset(&mut self) {
        let voice = self.target.voice;
        self.bridge_stiffness_log
            .jump_to(stiffness_to_log(voice.bridge_stiffness_n_m2));
        self.thread_position.jump_to(voice.thread_position_m);
        self.gamma.jump_to(voice.gamma_per_s);
        self.eta.jump_to(voice.eta_s);
        self.pickup_weight.jump_to(voice.nut_pickup_weight);
        self.output_gain
            .jump_to(db_to_amplitude(self.target.output_gain_db));
        self.current_voice = voice;
        for slot in &mut self.slots {
            slot.voice.reset();
            slot.delay.clear();
            slot.key = None;
            slot.level = 0.0;
            slot.plucked_at = 0;
        }
        self.drone.reset();
        self.body.reset();
        self.side_body.reset();
        self.clock = 0;
        self.next_control_tick = 0;
        self.retune_cursor = 0;
        self.next_retune = 0;
        for instrument in &mut self.bowed {
            instrument.reset();
        }
        self.bowed_delay.clear();
        self.applied_bow_controls = None;
        self.apply_bowed_settings();
    }

    /// Renders `output.len()` samples (overwriting `output`) while applying `events` at their
    /// offsets. Events must be sorted by offset; an offset past the block is applied at its last
    /// sample. Allocation-free, never panics.
    pub fn process(&mut self, events: &[TimedEvent], output: &mut [f32]) {
        self.process_inner(events, output, None, None);
    }

    /// [`Engine::process`] in stereo: the mid signal `M` is exactly [`Engine::process`]'s, the
    /// side signal `S` the strings' outputs weighted by their places in the image (drone
    /// strings spread evenly from left to right in playing order, notes by pitch: two octaves
    /// either side of middle C at the edges) times [`EngineSettings::stereo_width`], through its
    /// own copy of the body when the output is radiated; `left = M − S`, `right = M + S`. So the
    /// mono sum `(left + right) / 2` is the mono output (mono-compatible by construction) and a
    /// width of 0 gives two equal channels. `left` and `right` must have the same length.
    /// Allocation-free, never panics.
    pub fn process_stereo(&mut self, events: &[TimedEvent], left: &mut [f32], right: &mut [f32]) {
        self.process_stereo_inner(events, left, right, None);
    }

    /// [`Engine::process_stereo`] with the voices run by `runner`, as [`Engine::process_with`]:
    /// bit-identical to it, allocates (offline rendering).
    pub fn process_stereo_with(
        &mut self,
        events: &[TimedEvent],
        left: &mut [f32],
        right: &mut [f32],
        runner: VoiceRunner<'_>,
    ) {
        self.process_stereo_inner(events, left, right, Some(runner));
    }

    fn process_stereo_inner(
        &mut self,
        events: &[TimedEvent],
        left: &mut [f32],
        right: &mut [f32],
        runner: Option<VoiceRunner<'_>>,
    ) {
        let length = left.len().min(right.len());
        let (left, right) = (&mut left[..length], &mut right[..length]);
        self.process_inner(events, left, Some(&mut *right), runner);
        for (left, right) in left.iter_mut().zip(right.iter_mut()) {
            let (mid, side) = (*left, *right);
            *left = mid - side;
            *right = mid + side;
        }
    }

    /// [`Engine::process`] with the voices of each segment run by `runner` (offline rendering
    /// on a thread pool): the output is bit-identical to [`Engine::process`]'s whatever order or
    /// threads `runner` runs the tasks in. Allocates (per-voice buffers and the task list), so
    /// it is not for the audio thread.
    pub fn process_with(
        &mut self,
        events: &[TimedEvent],
        output: &mut [f32],
        runner: VoiceRunner<'_>,
    ) {
        self.process_inner(events, output, None, Some(runner));
    }

    /// Renders the mid signal into `output` and, when given, the side signal into `side`.
    fn process_inner(
        &mut self,
        events: &[TimedEvent],
        output: &mut [f32],
        mut side: Option<&mut [f32]>,
        runner: Option<VoiceRunner<'_>>,
    ) {
        output.fill(0.0);
        if let Some(side) = side.as_deref_mut() {
            side.fill(0.0);
        }
        let length = output.len();
        let mut position = 0;
        let mut next_event = 0;
        while position < length {
            if self.clock >= self.next_control_tick {
                self.control_tick();
                self.next_control_tick = self.clock + CONTROL_INTERVAL;
            }
            while let Some(timed) = events.get(next_event) {
                if timed.offset.min(length - 1) > position {
                    break;
                }
                self.handle_event(timed.event);
                next_event += 1;
            }
            self.play_due_drone_pluck();

            let mut end = length;
            if let Some(timed) = events.get(next_event) {
                end = end.min(timed.offset.min(length - 1));
            }
            // Ticks until the next tick, at or after the clock (the tick of this sample has run).
            let first_tick = (self.next_control_tick - self.clock) as usize;
            // Offline (a runner), a segment runs through the control ticks that would change
            // nothing, so that a segment hands its voices out once, not every
            // [`CONTROL_INTERVAL`] samples; the ticks inside it are then skipped, on their grid.
            let through_ticks = runner.is_some() && self.control_ticks_are_idle();
            if !through_ticks {
                end = end.min(position + first_tick);
            }
            if let Some(pluck_sample) = self
                .drone
                .next_pluck_sample(&self.target.drone, self.sample_rate_hz)
            {
                let until = pluck_sample.saturating_sub(self.clock).max(1);
                end = end.min(position + until.min(length as u64) as usize);
            }
            let end = end.max(position + 1);
            let side_segment = side.as_deref_mut().map(|side| &mut side[position..end]);
            self.render_segment(&mut output[position..end], side_segment, runner, first_tick);
            self.clock += (end - position) as u64;
            position = end;
            if self.next_control_tick < self.clock {
                // The idle ticks the segment ran through: the next is the first at or after the
                // clock, on the same grid.
                let skipped = (self.clock - self.next_control_tick).div_ceil(CONTROL_INTERVAL);
                self.next_control_tick += skipped * CONTROL_INTERVAL;
            }
        }
    }

    /// Renders one segment: `first_tick` is the index of its first control tick inside it, if
    /// any (beyond its end on the audio thread; [`run_slot`]).
    fn render_segment(
        &mut self,
        output: &mut [f32],
        mut side: Option<&mut [f32]>,
        runner: Option<VoiceRunner<'_>>,
        first_tick: usize,
    ) {
        let width = self.target.stereo_width as f32;
        if self.target.instrument == Instrument::Bowed {
            let scale = 1.0 / BOWED_NEWTONS_AT_FULL_SCALE;
            let index = self.target.bowed.string.index();
            let (bowed, delay) = (&mut self.bowed[index], &mut self.bowed_delay);
            for sample in output.iter_mut() {
                let value = delay.process((bowed.next_sample() * scale) as f32);
                if !value.is_finite() {
                    // Fail soft, as for a tanpura voice: a bowed string that blew up is
                    // silenced and restarts at rest.
                    bowed.reset();
                    delay.clear();
                    break;
                }
                *sample += value;
            }
        }
        let release = self.level_release;
        match runner {
            // The audio thread: each voice adds into the output in turn.
            None => {
                for slot in &mut self.slots {
                    match side.as_deref_mut() {
                        Some(side) => {
                            let weight = slot.pan * width;
                            run_slot(slot, release, output.len(), first_tick, |index, value| {
                                output[index] += value;
                                side[index] += weight * value;
                            });
                        }
                        None => {
                            run_slot(slot, release, output.len(), first_tick, |index, value| {
                                output[index] += value
                            })
                        }
                    }
                }
            }
            // Offline: each active voice fills its own buffer, on whatever thread the runner
            // picks; the buffers are then added in slot order, so that the sum (and its
            // rounding) is the same as above.
            Some(runner) => {
                self.scratch.resize_with(self.slots.len(), Vec::new);
                let mut tasks: Vec<VoiceTask<'_>> = self
                    .slots
                    .iter_mut()
                    .zip(&mut self.scratch)
                    .filter_map(|(slot, samples)| {
                        if !slot.voice.is_active() {
                            slot.level = 0.0;
                            return None;
                        }
                        samples.resize(output.len(), 0.0);
                        Some(VoiceTask {
                            slot,
                            release,
                            first_tick,
                            samples,
                            written: 0,
                        })
                    })
                    .collect();
                runner(&mut tasks);
                for task in &tasks {
                    let samples = &task.samples[..task.written];
                    for (sample, value) in output.iter_mut().zip(samples) {
                        *sample += *value;
                    }
                    if let Some(side) = side.as_deref_mut() {
                        let weight = task.slot.pan * width;
                        for (sample, value) in side.iter_mut().zip(samples) {
                            *sample += weight * *value;
                        }
                    }
                }
            }
        }
        if self.target.instrument == Instrument::Tanpura
            && self.target.tanpura_output == TanpuraOutput::Radiated
        {
            // The strings' outputs are their bridge forces here (`control_tick`), summed: the
            // body is driven by the total force on the bridge.
            for sample in output.iter_mut() {
                *sample = self.body.tick(f64::from(*sample)) as f32;
            }
            if let Some(side) = side.as_deref_mut() {
                for sample in side.iter_mut() {
                    *sample = self.side_body.tick(f64::from(*sample)) as f32;
                }
            }
        }
        match side {
            Some(side) => {
                for (sample, side) in output.iter_mut().zip(side.iter_mut()) {
                    let gain = self.output_gain.step() as f32;
                    *sample *= gain;
                    *side *= gain;
                }
            }
            None => {
                for sample in output.iter_mut() {
                    *sample *= self.output_gain.step() as f32;
                }
            }
        }
    }

    /// `read` of each smoothed control, in the order [`Engine::voice_with_controls`] takes
    /// them: the bridge's stiffness (logarithmic), the thread's position, γ, η, the pickup mix.
    /// True when every control tick until the next event or drone pluck would change nothing
    /// ([`Engine::control_tick`]): the smoothed controls settled at the settings the strings
    /// were last given, no retune pending, and each drone string's level at its setting's. Such
    /// a tick leaves the next one idle too, so a segment may run through all of them.
    fn control_ticks_are_idle(&self) -> bool {
        let ramps = [
            &self.bridge_stiffness_log,
            &self.thread_position,
            &self.gamma,
            &self.eta,
            &self.pickup_weight,
        ];
        if self.retune_pending || ramps.iter().any(|ramp| ramp.is_ramping()) {
            return false;
        }
        // In the order of [`Engine::smoothed_controls`].
        let mut settings = self.voice_with_controls(ramps.map(Ramp::value));
        settings.fundamental_hz = self.current_voice.fundamental_hz;
        // A drone string's level changes with its setting, which also sets a retune pending
        // (`Engine::set_settings`); looked at here all the same, so that the ticks' effect is
        // checked where it is made.
        settings == self.current_voice
            && self.slots.iter().all(|slot| match slot.key {
                Some(StringKey::Drone(index)) => {
                    slot.level_factor == slot.pitch_level * self.drone_levels[index]
                }
                _ => true,
            })
    }

    fn smoothed_controls(&mut self, mut read: impl FnMut(&mut Ramp) -> f64) -> [f64; 5] {
        [
            read(&mut self.bridge_stiffness_log),
            read(&mut self.thread_position),
            read(&mut self.gamma),
            read(&mut self.eta),
            read(&mut self.pickup_weight),
        ]
    }

    /// The target's voice settings with the smoothed controls at `controls`: the bridge's
    /// stiffness (in its logarithmic domain), the thread's position, γ, η and the pickup mix.
    fn voice_with_controls(&self, controls: [f64; 5]) -> VoiceSettings {
        let [stiffness_log, thread_position_m, gamma_per_s, eta_s, nut_pickup_weight] = controls;
        let mut settings = self.target.voice;
        settings.bridge_stiffness_n_m2 = log_to_stiffness(stiffness_log);
        settings.thread_position_m = thread_position_m;
        settings.gamma_per_s = gamma_per_s;
        settings.eta_s = eta_s;
        settings.nut_pickup_weight = nut_pickup_weight;
        if self.target.tanpura_output == TanpuraOutput::Radiated {
            // The body hears the bridge.
            settings.nut_pickup_weight = 0.0;
        }
        settings
    }

    /// Tunes a string for every note the current tuning can play and remembers the tensions
    /// (`tuning_memory.rs`), with the settings the strings take once the smoothed controls have
    /// reached their targets: a note-on on one of them then configures its string once instead
    /// of tuning it. For the host to call off the audio thread when it activates the plugin;
    /// allocates a scratch voice, and took 19–21 ms at the fine tier (80 notes) on a 2.6 GHz
    /// Xeon (stop 55).
    pub fn prepare_tunings(&mut self) {
        let plan = self.tuning_plan();
        let mut voice = plan.scratch_voice();
        for settings in plan.strings() {
            if self.tunings.tension_n(&settings).is_none() {
                let tuned = plan.tune(&mut voice, &settings);
                self.tunings.remember(&tuned.settings, tuned.tension_n);
            }
        }
        self.planned = Some(plan);
    }

    /// The notes' strings once the smoothed controls reach their targets, as the tuning sees
    /// them ([`TuningPlan`]), and in drone mode the drone's strings on its Sa (the settings'
    /// Sa, else the one it last plucked on). Takes `&mut self` only because it reads the
    /// controls' targets through the accessor that also steps them. Allocation-free.
    pub fn tuning_plan(&mut self) -> TuningPlan {
        let controls = self.smoothed_controls(|control| control.target());
        let plan = TuningPlan::new(
            &self.voice_with_controls(controls),
            &self.target.tuning,
            self.sample_rate_hz,
        );
        let drone = self.target.drone;
        let Some(sa_note) = drone
            .sa_note
            .or(self.last_drone_sa)
            .filter(|_| drone.enabled)
        else {
            return plan;
        };
        plan.with_drone_strings(drone.string_pitches(self.target.tuning.note_hz(sa_note)))
    }

    /// The plan whose tensions the memory lacks, once after each change of what the tuning sees
    /// (the bridge's or the thread's control, the tier, the tuning, the sample rate, the drone's
    /// Sa or its strings), for a worker to tune off the audio thread and hand back through
    /// [`Engine::remember_tuning`]; `None` while nothing changed since the last plan prepared or
    /// handed out, and while the bowed string plays. Without it each string's first pluck after
    /// such a change tunes it on the audio thread: 235–237 µs at the fine tier against
    /// 67–68 µs to configure it (`tuning_memory.rs`). Allocation-free.
    pub fn take_wanted_tuning_plan(&mut self) -> Option<TuningPlan> {
        if self.target.instrument != Instrument::Tanpura {
            return None;
        }
        let plan = self.tuning_plan();
        if self.planned == Some(plan) {
            return None;
        }
        self.planned = Some(plan);
        Some(plan)
    }

    /// Remembers a tension found off the audio thread for a plan's string
    /// ([`Engine::take_wanted_tuning_plan`]); one for another sample rate is dropped.
    /// Allocation-free.
    pub fn remember_tuning(&mut self, tuned: &PlannedTension) {
        if tuned.sample_rate_hz == self.sample_rate_hz {
            self.tunings.remember(&tuned.settings, tuned.tension_n);
        }
    }

    /// How many times the engine's strings were tuned (a string configured at a remembered
    /// tension is not: `tuning_memory.rs`).
    pub fn string_tunings(&self) -> u64 {
        self.slots.iter().map(|slot| slot.voice.tunings()).sum()
    }

    /// The tuning memory (`tuning_memory.rs`).
    pub fn tuning_memory(&self) -> &TuningMemory {
        &self.tunings
    }

    /// Moves the smoothed settings one control step and passes them to the ringing strings.
    fn control_tick(&mut self) {
        let controls = self.smoothed_controls(Ramp::step);
        let mut settings = self.voice_with_controls(controls);
        settings.fundamental_hz = self.current_voice.fundamental_hz;
        let drone_strings = self.target.drone.strings;
        for slot in &mut self.slots {
            if let Some(StringKey::Drone(index)) = slot.key {
                // A drone string's level follows its setting while it rings.
                slot.level_factor = slot.pitch_level * self.drone_levels[index];
            }
        }
        if settings != self.current_voice {
            self.retune_pending = true;
        }
        self.current_voice = settings;
        if !self.retune_pending || self.clock < self.next_retune {
            return;
        }
        // At most one ringing string takes the new settings every [`RETUNE_INTERVAL`] samples
        // (every other control tick), the next in turn whose settings differ: retuning a string
        // (a new rest state and its linearised fundamental) costs about a fourteenth of a
        // 64-sample block's deadline at the live tier (102–104 µs: `--example retune_cost`)
        // and about a seventh at the fine tier (218–221 µs; 290 µs before stop 55), so retuning
        // every string at every tick of a glide of k_b or the thread missed the deadline
        // several times over (the soak), and one at every tick still lifted the fine tier's
        // slowest blocks under automation by a third (`docs/performance.md`, stop 54). With
        // eight strings ringing each follows a glide every sixteen ticks (11.6 ms at 44.1 kHz)
        // and reaches the target at most that late. On the sample clock, so the same whatever
        // the host's block size.
        let count = self.slots.len();
        for step in 0..count {
            let index = (self.retune_cursor + step) % count;
            let slot = &mut self.slots[index];
            if !slot.voice.is_active() {
                // A silent string takes the settings when it is next plucked
                // (`pluck_string`).
                continue;
            }
            let mut string_settings = settings;
            string_settings.fundamental_hz = slot.tuned_hz;
            if let Some(StringKey::Drone(index)) = slot.key {
                string_settings.thread_position_m += drone_strings[index].thread_offset_m;
            }
            string_settings.thread_position_m += slot.thread_set_m;
            let mut string_settings = string_settings.clamped();
            // A voice switching tier restarts at rest (`TanpuraVoice::set_settings`), so a
            // ringing string keeps its tier; the new one applies from its next pluck.
            string_settings.quality = slot.voice.settings().quality;
            if string_settings == *slot.voice.settings() {
                continue;
            }
            // A string whose tension is remembered for these settings (the tuning plan's, once
            // the worker has handed it back: a glide's last retune) is configured at it instead
            // of tuned (`tuning_memory.rs`).
            match self.tunings.tension_n(&string_settings) {
                Some(tension) => slot.voice.set_settings_tuned(&string_settings, tension),
                None => slot.voice.set_settings(&string_settings),
            }
            self.retune_cursor = (index + 1) % count;
            self.next_retune = self.clock + RETUNE_INTERVAL;
            return;
        }
        // Every ringing string has the settings: nothing to look at until they change.
        self.retune_pending = false;
    }

    /// The bowed instrument's reading of an event (`bowed/instrument.rs` documents the mapping).
    fn handle_bowed_event(&mut self, event: EngineEvent) {
        let bowed_event = match event {
            EngineEvent::NoteOn { note, velocity } => BowedEvent::NoteOn { note, velocity },
            EngineEvent::NoteOff { note } => BowedEvent::NoteOff { note },
            EngineEvent::AllNotesOff => BowedEvent::AllNotesOff,
            EngineEvent::AllSoundOff => {
                self.bowed_mut().reset();
                return;
            }
            EngineEvent::Controller { number, value } => match number {
                1 => BowedEvent::Modulation(value),
                2 => BowedEvent::Pressure(value),
                11 => BowedEvent::Expression(value),
                74 => BowedEvent::Timbre(value),
                _ => return,
            },
            EngineEvent::ChannelPressure(value) | EngineEvent::PolyPressure { value, .. } => {
                BowedEvent::Pressure(value)
            }
            EngineEvent::PitchBend(value) => BowedEvent::PitchBend(value),
        };
        self.bowed_mut().handle(bowed_event);
    }

    fn handle_event(&mut self, event: EngineEvent) {
        let Some(event) = event.sanitised() else {
            return;
        };
        if self.target.instrument == Instrument::Bowed {
            self.handle_bowed_event(event);
            return;
        }
        match event {
            EngineEvent::NoteOn { note, velocity } if velocity > 0.0 => {
                if self.target.drone.enabled {
                    if self.target.drone.sa_note.is_none() {
                        self.drone.note_on(note, self.clock);
                    }
                } else if let Some(hz) = self.target.tuning.playable_note_hz(note) {
                    self.pluck_string(StringKey::Note(note), hz, velocity);
                }
            }
            EngineEvent::NoteOn { note, .. } | EngineEvent::NoteOff { note } => {
                self.drone.note_off(note)
            }
            EngineEvent::AllNotesOff => self.drone.all_notes_off(),
            EngineEvent::AllSoundOff => {
                self.drone.all_notes_off();
                for slot in &mut self.slots {
                    slot.voice.reset();
                    slot.delay.clear();
                    slot.key = None;
                    slot.level = 0.0;
                }
            }
            // Controllers, pressure and pitch bend do not reach a plucked string.
            EngineEvent::Controller { .. }
            | EngineEvent::ChannelPressure(_)
            | EngineEvent::PolyPressure { .. }
            | EngineEvent::PitchBend(_) => {}
        }
    }

    fn play_due_drone_pluck(&mut self) {
        if !self.target.drone.enabled {
            self.drone.all_notes_off();
            return;
        }
        let drone = self.target.drone;
        match drone.sa_note {
            // A set Sa plays whenever drone mode is on.
            Some(_) if !self.drone.is_running() => self.drone.start(self.clock),
            // Back to the held note with none held: the cycle stops.
            None if self.drone.sa_note().is_none() && self.drone.is_running() => {
                self.drone.stop();
            }
            _ => {}
        }
        let tempo = match (drone.tempo_sync, self.host_tempo_bpm) {
            (true, Some(host)) => host,
            _ => drone.free_tempo_bpm,
        };
        let Some(pluck) = self
            .drone
            .take_due_pluck(self.clock, &drone, tempo, self.sample_rate_hz)
        else {
            return;
        };
        let Some(sa_note) = drone.sa_note.or_else(|| self.drone.sa_note()) else {
            return;
        };
        self.last_drone_sa = Some(sa_note);
        let Some((hz, _)) = drone
            .string_pitches(self.target.tuning.note_hz(sa_note))
            .nth(pluck.string)
        else {
            return;
        };
        let (low, high) = VoiceSettings::FUNDAMENTAL_RANGE_HZ;
        if (low..=high).contains(&hz) {
            self.pluck_string(StringKey::Drone(pluck.string), hz, pluck.strength as f32);
        }
    }

    /// The voice a new pluck of `key` at `fundamental_hz` goes to: the same string if it is
    /// still tuned there (a real string is simply plucked again), else a silent voice, else the
    /// quietest ringing one, the oldest among equally quiet ones.
    fn choose_voice(&self, key: StringKey, fundamental_hz: f64) -> usize {
        if let Some(index) = self
            .slots
            .iter()
            .position(|slot| slot.key == Some(key) && slot.fundamental_hz == fundamental_hz)
        {
            return index;
        }
        if let Some(index) = self
            .slots
            .iter()
            .enumerate()
            .filter(|(_, slot)| !slot.voice.is_active())
            .min_by_key(|(_, slot)| slot.plucked_at)
            .map(|(index, _)| index)
        {
            return index;
        }
        self.slots
            .iter()
            .enumerate()
            .min_by(|(_, a), (_, b)| {
                a.level
                    .total_cmp(&b.level)
                    .then(a.plucked_at.cmp(&b.plucked_at))
            })
            .map_or(0, |(index, _)| index)
    }

    /// The settings of the string that plays `key` at `fundamental_hz` now (before its
    /// as-played offset): the smoothed shared settings, the note, and a drone string's thread.
    fn string_settings(&self, key: StringKey, fundamental_hz: f64) -> VoiceSettings {
        self.string_settings_from(&self.current_voice, key, fundamental_hz)
    }

    /// [`Engine::string_settings`] from the voice settings `base`.
    fn string_settings_from(
        &self,
        base: &VoiceSettings,
        key: StringKey,
        fundamental_hz: f64,
    ) -> VoiceSettings {
        let mut settings = *base;
        settings.fundamental_hz = fundamental_hz;
        if let StringKey::Drone(index) = key {
            settings.thread_position_m += self.target.drone.strings[index].thread_offset_m;
        }
        settings.clamped()
    }

    /// Remembers a string without a current calibration, for the host.
    fn want_calibration(&mut self, request: &CalibrationRequest) {
        if self.wanted.iter().flatten().any(|wanted| wanted == request) {
            return;
        }
        if let Some(free) = self.wanted.iter_mut().find(|wanted| wanted.is_none()) {
            *free = Some(*request);
        }
    }

    fn pluck_string(&mut self, key: StringKey, fundamental_hz: f64, velocity: f32) {
        let index = self.choose_voice(key, fundamental_hz);
        let mut string_settings = self.string_settings(key, fundamental_hz);
        let mut thread_set_m = 0.0;
        if self.target.tuning.as_played {
            let velocities = match key {
                StringKey::Drone(_) => drone_velocities(&self.target.drone),
                StringKey::Note(_) => NOTE_VELOCITIES,
            };
            let request = CalibrationRequest {
                settings: string_settings,
                pluck: self.target.pluck.clamped(),
                velocities,
            };
            if !self.as_played.is_current(&request, self.sample_rate_hz) {
                self.want_calibration(&request);
            }
            let as_played = self.as_played.as_played(&string_settings);
            thread_set_m = as_played.thread_offset_m;
            string_settings = as_played.applied_to(&string_settings);
        }
        let level = match key {
            StringKey::Drone(string) => self.drone_levels[string],
            StringKey::Note(_) => 1.0,
        };
        let pan = match key {
            StringKey::Drone(string) => {
                let (_, count) =
                    string_ratios(self.target.drone.first_string, self.target.drone.pattern);
                drone_string_pan(string, count)
            }
            StringKey::Note(note) => {
                ((f64::from(note) - 60.0) / NOTE_PAN_SPAN_SEMITONES).clamp(-1.0, 1.0) as f32
            }
        };
        let slot = &mut self.slots[index];
        if slot.key != Some(key) || slot.fundamental_hz != fundamental_hz {
            // A stolen string is stopped first: its old vibration belongs to another tuning (the
            // retune below solves its new rest state, so the old one is not solved again).
            slot.voice.stop();
            slot.delay.clear();
            slot.key = Some(key);
            slot.fundamental_hz = fundamental_hz;
            slot.pitch_level = pitch_level_factor(fundamental_hz);
        }
        slot.tuned_hz = string_settings.fundamental_hz;
        slot.thread_set_m = thread_set_m;
        slot.pan = pan;
        slot.level_factor = slot.pitch_level * level;
        // Also brings a re-plucked string to the current quality tier; a string tuned before
        // with these settings is configured at the tension it took then (`tuning_memory.rs`).
        match self.tunings.tension_n(&string_settings) {
            Some(tension) => slot.voice.set_settings_tuned(&string_settings, tension),
            None => {
                slot.voice.set_settings(&string_settings);
                self.tunings
                    .remember(&string_settings, slot.voice.tension_n());
            }
        }
        let padding = slot.padding_to(self.latency);
        if slot.delay.length != padding {
            slot.delay.set_length(padding);
        }
        let mut pluck = self.target.pluck;
        pluck.amplitude_m *= f64::from(velocity.clamp(0.0, 1.0));
        slot.voice.pluck(&pluck);
        slot.plucked_at = self.clock;
        // A fresh pluck counts as loud until the follower has measured it.
        slot.level = 1.0;
    }
}

#[cfg(test)]
mod tests;
