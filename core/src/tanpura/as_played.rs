//! Tuning a string by its sustained pitch as played, as a player tunes by ear.
//!
//! A voice (`voice.rs`) tunes its string by linearising it about its rest state: the tension
//! is set so that the small-amplitude fundamental of the string resting on bridge and thread is
//! the requested pitch. A pluck moves the string away from that rest state. Where the string
//! at rest just touches the bridge's crest (around C♯3–E3 with the seed's bridge and thread, FD
//! tiers), a pluck lifts it off the crest, its speaking length grows by the ≈ 7 mm between thread
//! and crest, and the note sounds 10 cents flat for seconds; elsewhere the jawari's contact
//! raises the pitch of a hard pluck by a few cents. A player does not hear the linearisation:
//! they tune the note they hear after the pluck.
//!
//! This module measures that note and retunes for it. For a string at `f₀` it renders plucks at
//! the soft and firm ends of how the string is played (a played note: MIDI velocities 40 and 110,
//! [`NOTE_VELOCITIES`]; a drone string: its plucks' strength range, full strength less the
//! humanisation) on the string's own tier, measures each pluck's sustained pitch `f_v` (the fundamental over 0.3–1.5 s,
//! [`sustained_pitch_hz`]), and shifts the linearisation's target by the offset that centres
//! them on `f₀`:
//!
//! `c ← c + 1200 log₂(f₀ / √(f_soft f_firm))` (cents), [`CALIBRATION_PASSES`] times,
//!
//! starting from `c = 0`. Centring the geometric mean minimises the largest deviation of the two
//! ends when the pitch changes monotonically with velocity between them. One pass is exact when
//! the pitch scales with the target (`f ∝ √T` with the contact state unchanged); the second
//! pass catches the contact state that the retuning itself moves.
//!
//! Where the string at rest just touches the crest the two ends can sound 10 cents apart (a soft
//! pluck stays on the crest, a firm one lifts it off), and centring them is all a tension can do.
//! Moving the thread 1 mm settles those notes, but they sit at the jawari's sweet spot and the
//! move takes 6–13 dB off their level above 2 kHz (`examples/jawari_moves.rs`, README), so the
//! calibration leaves the thread where the player put it.
//!
//! Each pass costs two renders of [`CALIBRATION_SECONDS`] on the
//! string's tier, so a calibration is an offline job (the renderer before it renders, a
//! background thread in the plugin), never the audio thread's. The result is a plain number of
//! cents per string that the engine adds to the string's target ([`AsPlayedTuning`]).

use super::excitation::Pluck;
use super::voice::{TanpuraVoice, VoiceSettings};
use crate::analysis::listening::{sustained_pitch_hz, SUSTAIN_WINDOW_S};

/// The soft and firm ends of a played note's velocities (MIDI 40 and 110, as fractions of full),
/// whose sustained pitches a note's calibration centres.
pub const NOTE_VELOCITIES: [f64; 2] = [40.0 / 127.0, 110.0 / 127.0];
/// Passes of the offset correction.
pub const CALIBRATION_PASSES: usize = 2;
/// Length of each calibration render, s: to the end of the sustain window.
pub const CALIBRATION_SECONDS: f64 = SUSTAIN_WINDOW_S.1;
/// Largest offset a calibration may find, cents: beyond it the measurement is not a
/// fundamental (a string that rings too short to be measured is left at 0).
pub const MAX_OFFSET_CENTS: f64 = 50.0;

/// The sustained pitch of one pluck of `pluck` at `velocity` (0–1) on `voice`, retuned (by
/// linearisation) to `target_hz` and started from rest, Hz; `nominal_hz` centres the pitch
/// search.
pub fn sustained_pitch_of_pluck_hz(
    voice: &mut TanpuraVoice,
    target_hz: f64,
    nominal_hz: f64,
    pluck: &Pluck,
    velocity: f64,
    sample_rate_hz: f64,
) -> f64 {
    let settings = VoiceSettings {
        fundamental_hz: target_hz,
        ..*voice.settings()
    };
    voice.set_settings(&settings);
    voice.reset();
    let pluck = Pluck {
        amplitude_m: pluck.amplitude_m * velocity.clamp(0.0, 1.0),
        ..*pluck
    };
    voice.pluck(&pluck);
    let samples = (CALIBRATION_SECONDS * sample_rate_hz).round() as usize;
    let signal: Vec<f64> = (0..samples)
        .map(|_| f64::from(voice.next_sample()))
        .collect();
    sustained_pitch_hz(&signal, sample_rate_hz, nominal_hz)
}

/// The offset, cents, to add to `settings.fundamental_hz` before the voice's linearised tuning
/// so that plucks of `pluck` at `velocities` (the soft and firm ends, fractions of full) sound
/// centred on `settings.fundamental_hz` (see the module doc). Allocates and renders: off the
/// audio thread.
pub fn as_played_offset_cents(
    settings: &VoiceSettings,
    pluck: &Pluck,
    velocities: [f64; 2],
    sample_rate_hz: f64,
) -> f64 {
    let settings = settings.clamped();
    let nominal = settings.fundamental_hz;
    let mut voice = TanpuraVoice::new(&settings, sample_rate_hz);
    // One render when both ends are the same strength.
    let ends = if velocities[0] == velocities[1] { 1 } else { 2 };
    let mut offset = 0.0;
    for _ in 0..CALIBRATION_PASSES {
        let target = nominal * (offset / 1200.0f64).exp2();
        let log_mean = velocities[..ends]
            .iter()
            .map(|&velocity| {
                sustained_pitch_of_pluck_hz(
                    &mut voice,
                    target,
                    nominal,
                    pluck,
                    velocity,
                    sample_rate_hz,
                )
                .log2()
            })
            .sum::<f64>()
            / ends as f64;
        let correction = 1200.0 * (nominal.log2() - log_mean);
        if !correction.is_finite() {
            return 0.0;
        }
        offset += correction;
    }
    if offset.abs() > MAX_OFFSET_CENTS {
        0.0
    } else {
        offset
    }
}

/// What to calibrate: a string, the pluck it is played with at full velocity, and the soft and
/// firm ends of its velocities (fractions of full).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationRequest {
    /// The string's settings; `fundamental_hz` is the note it sounds.
    pub settings: VoiceSettings,
    pub pluck: Pluck,
    pub velocities: [f64; 2],
}

/// Calibrations an engine holds at once: every string of a six-string drone and the notes of
/// a phrase several times over.
pub const AS_PLAYED_CAPACITY: usize = 48;

/// One string's calibration: what it was measured for, and its offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    pub request: CalibrationRequest,
    pub sample_rate_hz: f64,
    /// Cents added to the linearisation's target ([`as_played_offset_cents`]).
    pub offset_cents: f64,
}

impl Calibration {
    /// Measures the calibration of a string (renders: off the audio thread).
    pub fn measure(request: &CalibrationRequest, sample_rate_hz: f64) -> Self {
        let request = CalibrationRequest {
            settings: request.settings.clamped(),
            pluck: request.pluck.clamped(),
            velocities: request.velocities.map(|velocity| {
                if velocity.is_nan() {
                    1.0
                } else {
                    velocity.clamp(0.0, 1.0)
                }
            }),
        };
        Self {
            request,
            sample_rate_hz,
            offset_cents: as_played_offset_cents(
                &request.settings,
                &request.pluck,
                request.velocities,
                sample_rate_hz,
            ),
        }
    }

    /// True when it was measured for this string and pluck (what the pickup mix does not touch
    /// aside; numbers equal to 1e-9, so that a setting that went through a glide's arithmetic
    /// still counts as the same).
    pub fn is_for(&self, request: &CalibrationRequest, sample_rate_hz: f64) -> bool {
        let (a, b) = (&self.request.settings, &request.settings);
        let (mine, pluck) = (&self.request.pluck, &request.pluck);
        let numbers = [
            (a.fundamental_hz, b.fundamental_hz),
            (a.bridge_stiffness_n_m2, b.bridge_stiffness_n_m2),
            (a.thread_position_m, b.thread_position_m),
            (a.gamma_per_s, b.gamma_per_s),
            (a.eta_s, b.eta_s),
            (mine.position_m, pluck.position_m),
            (mine.width_m, pluck.width_m),
            (mine.amplitude_m, pluck.amplitude_m),
            (self.request.velocities[0], request.velocities[0]),
            (self.request.velocities[1], request.velocities[1]),
            (self.sample_rate_hz, sample_rate_hz),
        ];
        numbers
            .iter()
            .all(|&(x, y)| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()))
            && a.thread_enabled == b.thread_enabled
            && a.bridge_beyond_thread == b.bridge_beyond_thread
            && a.quality == b.quality
    }
}

/// The calibrations an engine tunes its strings with, in a fixed-size table (the audio thread
/// looks them up and inserts new ones without allocating). A string whose note and tier have
/// a calibration takes its offset even if other settings have moved since (a glide of the
/// bridge's stiffness does not make the drone jump back to its linearised tuning); a host or
/// renderer asks for fresh calibrations with [`AsPlayedTuning::is_current`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AsPlayedTuning {
    entries: [Option<Calibration>; AS_PLAYED_CAPACITY],
    /// Insertion stamps, to replace the oldest entry when the table is full.
    stamps: [u64; AS_PLAYED_CAPACITY],
    next_stamp: u64,
}

impl Default for AsPlayedTuning {
    fn default() -> Self {
        Self {
            entries: [None; AS_PLAYED_CAPACITY],
            stamps: [0; AS_PLAYED_CAPACITY],
            next_stamp: 1,
        }
    }
}

/// Two pitches are the same note when they differ by less than this ratio (1e-9 ≈ 2e-6 cents).
const SAME_PITCH: f64 = 1e-9;

fn same_string(a: &VoiceSettings, b: &VoiceSettings) -> bool {
    a.quality == b.quality && (a.fundamental_hz / b.fundamental_hz - 1.0).abs() < SAME_PITCH
}

impl AsPlayedTuning {
    /// The offset, cents, for a string of `settings` (its note and tier); 0 without one.
    pub fn offset_cents(&self, settings: &VoiceSettings) -> f64 {
        self.entries
            .iter()
            .flatten()
            .find(|entry| same_string(&entry.request.settings, settings))
            .map_or(0.0, |entry| entry.offset_cents)
    }

    /// True when the table holds a calibration measured for this request.
    pub fn is_current(&self, request: &CalibrationRequest, sample_rate_hz: f64) -> bool {
        self.entries
            .iter()
            .flatten()
            .any(|entry| entry.is_for(request, sample_rate_hz))
    }

    /// Adds a calibration (its offset clamped to ±[`MAX_OFFSET_CENTS`], a non-finite one
    /// ignored), replacing the one of the same note and tier, else a free entry, else the
    /// oldest. Allocation-free.
    pub fn insert(&mut self, mut calibration: Calibration) {
        if !calibration.offset_cents.is_finite() {
            return;
        }
        // What a calibration can find (a host handing back anything else is clamped).
        calibration.offset_cents = calibration
            .offset_cents
            .clamp(-MAX_OFFSET_CENTS, MAX_OFFSET_CENTS);
        let slot = self
            .entries
            .iter()
            .position(|entry| {
                entry.is_some_and(|entry| {
                    same_string(&entry.request.settings, &calibration.request.settings)
                })
            })
            .or_else(|| self.entries.iter().position(Option::is_none))
            .unwrap_or_else(|| {
                (0..AS_PLAYED_CAPACITY)
                    .min_by_key(|&index| self.stamps[index])
                    .unwrap_or(0)
            });
        self.entries[slot] = Some(calibration);
        self.stamps[slot] = self.next_stamp;
        self.next_stamp += 1;
    }

    /// Forgets every calibration.
    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// The calibrations held.
    pub fn calibrations(&self) -> impl Iterator<Item = &Calibration> {
        self.entries.iter().flatten()
    }
}
