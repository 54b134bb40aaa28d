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
//! **Setting the jawari.** Where the string at rest just touches the crest the two ends can
//! sound 10 cents apart (a soft pluck stays on the crest, a firm one lifts it off), and centring
//! them is all a tension can do. A player then moves the string's thread until the note speaks
//! the same at every strength, keeping the jawari's brightness, and so does the calibration
//! ([`as_played_calibration`]). If the soft end, a pluck midway and the firm end still lie more
//! than [`UNSETTLED_SPREAD_CENTS`] apart at the second centring pass (centred, one would lie
//! more than 2 cents off; the pluck midway counts because a string can be bistable between ends
//! that agree), it tries thread moves of 1 to [`THREAD_STEPS`] steps of [`THREAD_STEP_M`]
//! towards the crest, then away from it, and keeps the first that settles the string:
//!
//! - the two ends at the unmoved string's tuning lie within twice [`SETTLED_CENTS`] of each
//!   other (what a tension can then centre), and keep the level above 2 kHz within
//!   [`BRIGHTNESS_KEPT_DB`] of the unmoved string's ([`brightness_db`]);
//! - after one more centring pass the soft end, a pluck midway and the firm end lie within
//!   [`SETTLED_CENTS`] of the note, with the brightness still kept.
//!
//! Without one the thread stays where the player put it. Towards the crest first, because there
//! every pluck above the soft end lifts the string off the crest onto the grazing contact the
//! jawari's buzz comes from. A sweep of ±0.05, ±0.1 and ±0.2 mm over the reference tier's keys
//! 51–52 and the studio tier's 52–53 (the strings not settled unmoved; a throwaway tool of stop
//! 32, each move repeatable with `examples/jawari_moves.rs` and `examples/as_played.rs` with a
//! thread position such as `40.1mm`): the smallest move towards the crest that settled each
//! changed its brightness by +0.0 to +0.8 dB, the smallest away from it, which presses the
//! string onto the crest so that no pluck lifts it, by −2.8 to −5.9 dB.
//! The window of thread positions over which a string is bistable is about 0.15 mm wide and moves
//! by about 0.05 mm a semitone, so moves of 0.05–0.3 mm settle these notes; a millimetre would
//! also settle them but takes 6–13 dB off their level above 2 kHz (`examples/jawari_moves.rs`,
//! README).
//!
//! **One jawari for the instrument.** The thread's position is a setting of the instrument,
//! not of the scheme that simulates it: a musician who plays in one tier and renders in another
//! has set the jawari once. The fine and studio tiers' string (the reference's grid modes and
//! points, `modal/nodal_statics.rs`) rests where the reference's rests, so their jawari is set
//! on the reference's scheme ([`jawari_set_on`]): their calibration takes the reference's thread
//! move for the same string and pluck and centres its own tension on it
//! ([`as_played_with_jawari`]). Set on its own scheme it could differ by a step: at key 54
//! plucked at 0.20 m the window of bistable thread positions lies a fraction of a step apart in
//! two schemes, the FD studio of stops 34–56 settled at +0.25 mm and the reference at +0.30 mm,
//! and the softest touch (velocity 1) then stayed on the crest in one and not in the other,
//! 14.8 cents apart; at +0.30 mm both lay within 0.12 cents of each other at every velocity
//! 1–127 (`examples/as_played.rs`). The live tier keeps its own: its string rests
//! 7 µm above the crest (`docs/modal-tanpura.md` §8), so the reference's thread would not set
//! the same contact on it.
//!
//! The first pass costs two renders of [`CALIBRATION_SECONDS`] on the string's tier, the second
//! three, each thread move tried two more and the one kept three more again, so a calibration
//! is an offline job (the renderer's, alongside its render and before the string's first
//! pluck; a background thread's in the plugin), never the audio thread's. The studio's costs the
//! reference's calibration and four renders of its own. The first pass cannot be taken on a
//! cheaper tier: the second pass's plucks at the offset it finds are what tells a bistable string
//! (the reference's key 54 plucked at 0.20 m), and from the fine tier's first pass that string
//! keeps its thread unmoved (`docs/performance.md`, stop 58).
//! The result is a plain number of cents and a thread move per string, which the engine adds to
//! the string's target and thread position ([`AsPlayedTuning`]).

use std::cell::Cell;

use super::excitation::Pluck;
use super::quality::Quality;
use super::voice::{TanpuraVoice, VoiceSettings};
use crate::analysis::listening::{sustained_pitch_hz, SUSTAIN_WINDOW_S};
use crate::analysis::{band_power, power_spectrum};

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
/// A string is settled when its sustained pitch at the soft end, midway and the firm end of its
/// velocities lies within this of the note, cents (below the 2 cents a player hears as out of
/// tune, for the velocities between those three).
pub const SETTLED_CENTS: f64 = 1.5;
/// A string is unsettled when the sustained pitches of its soft, midway and firm plucks lie
/// more than this apart, cents: centred, one would lie more than 2 cents off the note, which a
/// player hears as out of tune.
pub const UNSETTLED_SPREAD_CENTS: f64 = 4.0;
/// The thread moves a calibration tries on an unsettled string: multiples of this, m.
pub const THREAD_STEP_M: f64 = 0.05e-3;
/// The largest move tried, in steps (±0.3 mm).
pub const THREAD_STEPS: usize = 6;
/// A thread move is kept only if the string's level above 2 kHz ([`brightness_db`]) stays within
/// this of the unmoved string's, dB.
pub const BRIGHTNESS_KEPT_DB: f64 = 3.0;

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
    let signal = render_pluck(voice, target_hz, pluck, velocity, sample_rate_hz);
    sustained_pitch_hz(&signal, sample_rate_hz, nominal_hz)
}

/// [`CALIBRATION_SECONDS`] of one pluck of `pluck` at `velocity` (0–1) on `voice`, retuned (by
/// linearisation) to `target_hz` and started from rest.
fn render_pluck(
    voice: &mut TanpuraVoice,
    target_hz: f64,
    pluck: &Pluck,
    velocity: f64,
    sample_rate_hz: f64,
) -> Vec<f64> {
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
    (0..samples)
        .map(|_| f64::from(voice.next_sample()))
        .collect()
}

/// The jawari's brightness in a pluck's first [`CALIBRATION_SECONDS`]: the level above 2 kHz
/// relative to the whole sound (to 20 kHz or 0.45 of the sample rate), dB, averaged over its
/// attack (0–0.3 s) and its sustain (0.6–1.2 s), the windows of `examples/jawari_moves.rs`.
pub fn brightness_db(signal: &[f64], sample_rate_hz: f64) -> f64 {
    let top_hz = (0.45 * sample_rate_hz).min(20_000.0);
    let level = |from_s: f64, to_s: f64| {
        let start = (from_s * sample_rate_hz) as usize;
        let length = ((to_s - from_s) * sample_rate_hz) as usize;
        let frame = (length.next_power_of_two() / 2).max(2);
        let spectrum = power_spectrum(signal, start, frame, frame);
        let bin_hz = sample_rate_hz / frame as f64;
        let high = band_power(&spectrum, bin_hz, 2000.0, top_hz);
        let all = band_power(&spectrum, bin_hz, 20.0, top_hz);
        10.0 * (high.max(f64::MIN_POSITIVE) / all.max(f64::MIN_POSITIVE)).log10()
    };
    0.5 * (level(0.0, 0.3) + level(0.6, 1.2))
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
    let mut voice = TanpuraVoice::new(&settings, sample_rate_hz);
    let mut offset = 0.0;
    for _ in 0..CALIBRATION_PASSES {
        offset += centring_pass(
            &mut voice,
            settings.fundamental_hz,
            offset,
            pluck,
            velocities,
            sample_rate_hz,
        );
    }
    within_reach(offset)
}

/// One pass of the offset correction for the string of `voice` tuned with `offset_cents` from
/// its note `nominal` (as in [`check`]): the change of offset that centres the sustained pitches
/// of its soft and firm ends on its note, cents (non-finite if a pitch was not found). One
/// render when both ends are the same strength.
fn centring_pass(
    voice: &mut TanpuraVoice,
    nominal: f64,
    offset_cents: f64,
    pluck: &Pluck,
    velocities: [f64; 2],
    sample_rate_hz: f64,
) -> f64 {
    if velocities[0] == velocities[1] {
        let one = [velocities[0]];
        return check(voice, nominal, offset_cents, pluck, one, sample_rate_hz).centring_cents();
    }
    check(
        voice,
        nominal,
        offset_cents,
        pluck,
        velocities,
        sample_rate_hz,
    )
    .centring_cents()
}

/// `offset_cents`, or 0 where it is not finite or beyond [`MAX_OFFSET_CENTS`] (a string that
/// rings too short to be measured).
fn within_reach(offset_cents: f64) -> f64 {
    if offset_cents.abs() <= MAX_OFFSET_CENTS {
        offset_cents
    } else {
        0.0
    }
}

/// A string's calibration as played: the cents added to its linearised tuning's target and the
/// distance its thread is moved (towards the bridge's crest when positive), m.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AsPlayed {
    pub offset_cents: f64,
    pub thread_offset_m: f64,
}

impl AsPlayed {
    /// `settings` as a string with this calibration is plucked: the linearisation's target
    /// raised by [`AsPlayed::offset_cents`], the thread moved by
    /// [`AsPlayed::thread_offset_m`], clamped. The engine's note-on and the tuning worker's
    /// [`Calibration::calibrated_settings`] both take it from here, so that a tension tuned off
    /// the audio thread is found by the note-on that needs it.
    pub fn applied_to(&self, settings: &VoiceSettings) -> VoiceSettings {
        VoiceSettings {
            fundamental_hz: settings.fundamental_hz * (self.offset_cents / 1200.0).exp2(),
            thread_position_m: settings.thread_position_m + self.thread_offset_m,
            ..*settings
        }
        .clamped()
    }
}

/// The velocities a calibration checks a moved thread at: the soft end, midway and the firm end.
fn check_velocities(velocities: [f64; 2]) -> [f64; 3] {
    [
        velocities[0],
        0.5 * (velocities[0] + velocities[1]),
        velocities[1],
    ]
}

/// How a string sounds at `N` velocities, the soft end first and the firm end last.
#[derive(Debug, Clone, Copy)]
struct Checked<const N: usize> {
    /// Each pluck's sustained pitch, cents from the note (non-finite where none was found).
    cents: [f64; N],
    /// [`brightness_db`] averaged over the soft and firm ends.
    brightness_db: f64,
}

impl<const N: usize> Checked<N> {
    /// The largest distance from the note, cents (infinite if a pitch was not found).
    fn worst(&self) -> f64 {
        self.cents.iter().fold(0.0, |worst: f64, &off| {
            worst.max(if off.is_finite() {
                off.abs()
            } else {
                f64::INFINITY
            })
        })
    }

    /// The largest distance between two of the plucks, cents (infinite if one was not found):
    /// what no tension can take away.
    fn spread(&self) -> f64 {
        let high = self.cents.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let low = self.cents.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let spread = high - low;
        if spread.is_finite() {
            spread
        } else {
            f64::INFINITY
        }
    }

    /// The change of offset that centres the soft and firm ends on the note, cents (one pass of
    /// [`as_played_offset_cents`]).
    fn centring_cents(&self) -> f64 {
        -0.5 * (self.cents[0] + self.cents[N - 1])
    }
}

/// Renders the string of `voice` tuned with `offset_cents` from its note `nominal` at
/// `velocities` and measures it. The note is passed in: a render leaves the voice's own settings
/// at the last render's target, not at the note.
fn check<const N: usize>(
    voice: &mut TanpuraVoice,
    nominal: f64,
    offset_cents: f64,
    pluck: &Pluck,
    velocities: [f64; N],
    sample_rate_hz: f64,
) -> Checked<N> {
    let target = nominal * (offset_cents / 1200.0).exp2();
    let mut checked = Checked {
        cents: [0.0; N],
        brightness_db: 0.0,
    };
    // The plucks are independent (each retunes the string and starts it from rest): in groups
    // of [`with_plucks_at_once`]'s number, all but the last of a group render on copies of the
    // voice on threads of their own and the last on `voice`, which it leaves as one pluck after
    // another would. Each render is that of the voice as the check found it, to the bit
    // (`a_check_renders_its_plucks_as_one_after_another`). On threads of their own, not a
    // pool's: a thread of the renderer's pool waiting in a join could otherwise take a pluck
    // and hold the render back for a whole pluck.
    let at_once = PLUCKS_AT_ONCE.with(Cell::get).clamp(1, N);
    let mut signals: Vec<Vec<f64>> = Vec::with_capacity(N);
    for group in velocities.chunks(at_once) {
        let Some((&last, others)) = group.split_last() else {
            continue;
        };
        std::thread::scope(|scope| {
            let others: Vec<_> = others
                .iter()
                .map(|&velocity| {
                    let mut copy = voice.clone();
                    scope.spawn(move || {
                        render_pluck(&mut copy, target, pluck, velocity, sample_rate_hz)
                    })
                })
                .collect();
            let last = render_pluck(voice, target, pluck, last, sample_rate_hz);
            for other in others {
                let signal = other
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
                signals.push(signal);
            }
            signals.push(last);
        });
    }
    for (index, signal) in signals.iter().enumerate() {
        let pitch = sustained_pitch_hz(signal, sample_rate_hz, nominal);
        checked.cents[index] = 1200.0 * (pitch / nominal).log2();
        if index == 0 || index == N - 1 {
            checked.brightness_db += 0.5 * brightness_db(signal, sample_rate_hz);
        }
    }
    checked
}

thread_local! {
    /// How many plucks of a check this thread's calibrations render at once
    /// ([`with_plucks_at_once`]).
    static PLUCKS_AT_ONCE: Cell<usize> = const { Cell::new(MAX_PLUCKS_AT_ONCE) };
}

/// The most plucks one check renders (the soft end, midway and the firm end), and so the most
/// it renders at once, each but one on a thread of its own: a calibration's plucks render at once
/// unless [`with_plucks_at_once`] says otherwise.
pub const MAX_PLUCKS_AT_ONCE: usize = 3;

/// Runs `work` with this thread's calibrations rendering at most `plucks` (at least 1) of a
/// check's plucks at once, e.g. 1 for a renderer asked to use one thread. The calibrations are
/// the same to the bit whatever the number.
pub fn with_plucks_at_once<R>(plucks: usize, work: impl FnOnce() -> R) -> R {
    let before = PLUCKS_AT_ONCE.with(|at_once| at_once.replace(plucks.max(1)));
    // Restored even if `work` panics, so that a caught panic leaves the thread as it was.
    struct Restore(usize);
    impl Drop for Restore {
        fn drop(&mut self) {
            PLUCKS_AT_ONCE.with(|at_once| at_once.set(self.0));
        }
    }
    let _restore = Restore(before);
    work()
}

/// The calibration of a string as a player sets it (module doc): the offset that centres its
/// soft and firm plucks on the note ([`as_played_offset_cents`]) and, where those and a pluck
/// midway lie more than [`UNSETTLED_SPREAD_CENTS`] apart at the second pass, the smallest
/// thread move of at most ±[`THREAD_STEPS`] × [`THREAD_STEP_M`], towards the crest first, that
/// settles the soft, midway and firm plucks while keeping the brightness within
/// [`BRIGHTNESS_KEPT_DB`].
/// This searches the string's own tier; [`Calibration::measure`] gives a tier whose jawari is
/// set on another's ([`jawari_set_on`]) that tier's thread move instead.
/// Allocates and renders: off the audio thread.
pub fn as_played_calibration(
    settings: &VoiceSettings,
    pluck: &Pluck,
    velocities: [f64; 2],
    sample_rate_hz: f64,
) -> AsPlayed {
    let settings = settings.clamped();
    // A string played at one strength is centred exactly.
    if velocities[0] == velocities[1] {
        return AsPlayed {
            offset_cents: as_played_offset_cents(&settings, pluck, velocities, sample_rate_hz),
            thread_offset_m: 0.0,
        };
    }
    let mut voice = TanpuraVoice::new(&settings, sample_rate_hz);
    // The two passes of [`as_played_offset_cents`] (the same renders and the same offset), the
    // second kept: what is left between the ends is what no tension can take away.
    let first_offset = centring_pass(
        &mut voice,
        settings.fundamental_hz,
        0.0,
        pluck,
        velocities,
        sample_rate_hz,
    );
    let second = check(
        &mut voice,
        settings.fundamental_hz,
        first_offset,
        pluck,
        check_velocities(velocities),
        sample_rate_hz,
    );
    let offset_cents = first_offset + second.centring_cents();
    let unmoved = AsPlayed {
        offset_cents: within_reach(offset_cents),
        thread_offset_m: 0.0,
    };
    if !offset_cents.is_finite()
        || second.spread() <= UNSETTLED_SPREAD_CENTS
        || !second.brightness_db.is_finite()
    {
        return unmoved;
    }
    let darkest_kept_db = second.brightness_db - BRIGHTNESS_KEPT_DB;
    for direction in [1.0, -1.0] {
        for step in 1..=THREAD_STEPS {
            let moved = VoiceSettings {
                thread_position_m: settings.thread_position_m
                    + direction * step as f64 * THREAD_STEP_M,
                ..settings
            }
            .clamped();
            if moved.thread_position_m == settings.thread_position_m {
                continue;
            }
            voice.set_settings(&moved);
            // The two ends at the unmoved string's tuning tell whether a tension can settle the
            // moved one, and whether it keeps its brightness.
            let screened = check(
                &mut voice,
                settings.fundamental_hz,
                unmoved.offset_cents,
                pluck,
                velocities,
                sample_rate_hz,
            );
            if screened.spread() > 2.0 * SETTLED_CENTS
                || screened.brightness_db.is_nan()
                || screened.brightness_db < darkest_kept_db
            {
                continue;
            }
            let offset_cents = unmoved.offset_cents + screened.centring_cents();
            if offset_cents.is_nan() || offset_cents.abs() > MAX_OFFSET_CENTS {
                continue;
            }
            let verified = check(
                &mut voice,
                settings.fundamental_hz,
                offset_cents,
                pluck,
                check_velocities(velocities),
                sample_rate_hz,
            );
            if verified.worst() <= SETTLED_CENTS && verified.brightness_db >= darkest_kept_db {
                return AsPlayed {
                    offset_cents,
                    thread_offset_m: moved.thread_position_m - settings.thread_position_m,
                };
            }
        }
    }
    unmoved
}

/// The tier on whose scheme a string of `quality` has its jawari set (module doc, *One jawari
/// for the instrument*): the fine and studio tiers' on the reference's (both share its grid), every
/// other tier's on its own.
pub fn jawari_set_on(quality: Quality) -> Quality {
    match quality {
        Quality::Fine | Quality::Studio => Quality::Reference,
        other => other,
    }
}

/// The calibration of a string whose jawari is set elsewhere: its thread moved by
/// `thread_offset_m` (clamped to the thread's range), then centred on its own tier by the two
/// passes of [`as_played_offset_cents`]. Allocates and renders: off the audio thread.
pub fn as_played_with_jawari(
    settings: &VoiceSettings,
    pluck: &Pluck,
    velocities: [f64; 2],
    sample_rate_hz: f64,
    thread_offset_m: f64,
) -> AsPlayed {
    let settings = settings.clamped();
    let thread_offset_m = if thread_offset_m.is_finite() {
        thread_offset_m
    } else {
        0.0
    };
    let moved = VoiceSettings {
        thread_position_m: settings.thread_position_m + thread_offset_m,
        ..settings
    }
    .clamped();
    AsPlayed {
        offset_cents: as_played_offset_cents(&moved, pluck, velocities, sample_rate_hz),
        thread_offset_m: moved.thread_position_m - settings.thread_position_m,
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

impl CalibrationRequest {
    /// The same string on the tier its jawari is set on ([`jawari_set_on`]), where that is
    /// another tier and the string is played at more than one strength (one played at one
    /// strength is only centred).
    pub fn jawari_request(&self) -> Option<Self> {
        let quality = jawari_set_on(self.settings.quality);
        let played_at_one_strength = self.velocities[0] == self.velocities[1];
        (quality != self.settings.quality && !played_at_one_strength).then_some(Self {
            settings: VoiceSettings {
                quality,
                ..self.settings
            },
            ..*self
        })
    }

    /// The request as it is measured: settings and pluck clamped to their ranges, velocities to
    /// [0, 1] (a NaN velocity taken as full).
    pub fn clamped(&self) -> Self {
        Self {
            settings: self.settings.clamped(),
            pluck: self.pluck.clamped(),
            velocities: self.velocities.map(|velocity| {
                if velocity.is_nan() {
                    1.0
                } else {
                    velocity.clamp(0.0, 1.0)
                }
            }),
        }
    }
}

/// Calibrations an engine holds at once: every string of a six-string drone and the notes of
/// a phrase several times over.
pub const AS_PLAYED_CAPACITY: usize = 48;

/// One string's calibration: what it was measured for, and its offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    pub request: CalibrationRequest,
    pub sample_rate_hz: f64,
    /// Cents added to the linearisation's target ([`as_played_calibration`]).
    pub offset_cents: f64,
    /// Distance the string's thread is moved, m ([`as_played_calibration`]).
    pub thread_offset_m: f64,
}

impl Calibration {
    /// Measures the calibration of a string (renders: off the audio thread): its own tier's
    /// [`as_played_calibration`], or, for a tier whose jawari is set on another's
    /// ([`jawari_set_on`]), that tier's thread move with its own tension centred on it
    /// ([`as_played_with_jawari`]).
    pub fn measure(request: &CalibrationRequest, sample_rate_hz: f64) -> Self {
        Self::measure_with(request, sample_rate_hz, Self::measure)
    }

    /// [`Calibration::measure`], with the calibration of the string whose jawari this one takes
    /// ([`CalibrationRequest::jawari_request`]) from `jawari` (a cache of calibrations, say).
    pub fn measure_with(
        request: &CalibrationRequest,
        sample_rate_hz: f64,
        jawari: impl FnOnce(&CalibrationRequest, f64) -> Calibration,
    ) -> Self {
        let request = request.clamped();
        let as_played = match request.jawari_request() {
            Some(jawari_request) => as_played_with_jawari(
                &request.settings,
                &request.pluck,
                request.velocities,
                sample_rate_hz,
                jawari(&jawari_request, sample_rate_hz).thread_offset_m,
            ),
            None => as_played_calibration(
                &request.settings,
                &request.pluck,
                request.velocities,
                sample_rate_hz,
            ),
        };
        Self {
            request,
            sample_rate_hz,
            offset_cents: as_played.offset_cents,
            thread_offset_m: as_played.thread_offset_m,
        }
    }

    /// The calibration as an engine holds it: its offset clamped to ±[`MAX_OFFSET_CENTS`] and
    /// its thread move to ±[`THREAD_STEPS`] × [`THREAD_STEP_M`] (what a calibration can find;
    /// a host handing back anything else is clamped), a non-finite thread move taken as none;
    /// none with a non-finite offset.
    pub fn clamped(mut self) -> Option<Self> {
        if !self.offset_cents.is_finite() {
            return None;
        }
        self.offset_cents = self.offset_cents.clamp(-MAX_OFFSET_CENTS, MAX_OFFSET_CENTS);
        let largest_move_m = THREAD_STEPS as f64 * THREAD_STEP_M;
        self.thread_offset_m = if self.thread_offset_m.is_finite() {
            self.thread_offset_m.clamp(-largest_move_m, largest_move_m)
        } else {
            0.0
        };
        Some(self)
    }

    /// The settings an engine plucks the requested string with once it holds this
    /// calibration ([`AsPlayed::applied_to`] of the clamped calibration); none when an engine
    /// would not take it.
    pub fn calibrated_settings(&self) -> Option<VoiceSettings> {
        let calibration = self.clamped()?;
        let as_played = AsPlayed {
            offset_cents: calibration.offset_cents,
            thread_offset_m: calibration.thread_offset_m,
        };
        Some(as_played.applied_to(&calibration.request.settings))
    }

    /// The tension that tunes [`Calibration::calibrated_settings`] at this calibration's sample
    /// rate, as a voice's own tuning finds it: for the tuning worker to hand the engine with
    /// the calibration ([`crate::engine::Engine::set_calibration_tuned`]), so that the string's
    /// next pluck configures it once instead of tuning it on the audio thread. Builds a scratch
    /// voice: allocates, off the audio thread only.
    pub fn calibrated_tension_n(&self) -> Option<f64> {
        let settings = self.calibrated_settings()?;
        Some(TanpuraVoice::new(&settings, self.sample_rate_hz).tension_n())
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
    /// The offset and thread move for a string of `settings` (its note and tier); none without
    /// a calibration. Allocation-free.
    pub fn as_played(&self, settings: &VoiceSettings) -> AsPlayed {
        self.entries
            .iter()
            .flatten()
            .find(|entry| same_string(&entry.request.settings, settings))
            .map_or(AsPlayed::default(), |entry| AsPlayed {
                offset_cents: entry.offset_cents,
                thread_offset_m: entry.thread_offset_m,
            })
    }

    /// True when the table holds a calibration measured for this request.
    pub fn is_current(&self, request: &CalibrationRequest, sample_rate_hz: f64) -> bool {
        self.entries
            .iter()
            .flatten()
            .any(|entry| entry.is_for(request, sample_rate_hz))
    }

    /// Adds a calibration ([`Calibration::clamped`]; one with a non-finite offset is ignored),
    /// replacing the one of the same note and tier, else a free entry, else the oldest.
    /// Allocation-free.
    pub fn insert(&mut self, calibration: Calibration) {
        let Some(calibration) = calibration.clamped() else {
            return;
        };
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

#[cfg(test)]
mod tests {
    use super::*;

    /// One check after another, each one pluck after another on one voice: what `check` renders
    /// on its threads, to the bit, at a tier of each kind (modal at the output rate, the fine
    /// string, the seed's FD) and with its plucks one, two or three at a time, with a moved
    /// thread in between as the search moves it.
    #[test]
    fn a_check_renders_its_plucks_as_one_after_another() {
        fn in_turn<const N: usize>(
            voice: &mut TanpuraVoice,
            nominal: f64,
            offset_cents: f64,
            pluck: &Pluck,
            velocities: [f64; N],
        ) -> Vec<u64> {
            let target = nominal * (offset_cents / 1200.0).exp2();
            let mut bits = Vec::new();
            for velocity in velocities {
                let signal = render_pluck(voice, target, pluck, velocity, 44_100.0);
                let pitch = sustained_pitch_hz(&signal, 44_100.0, nominal);
                bits.push((1200.0 * (pitch / nominal).log2()).to_bits());
                bits.push(brightness_db(&signal, 44_100.0).to_bits());
            }
            bits
        }
        fn threaded<const N: usize>(
            at_once: usize,
            voice: &mut TanpuraVoice,
            nominal: f64,
            offset_cents: f64,
            pluck: &Pluck,
            velocities: [f64; N],
        ) -> Vec<u64> {
            let checked = with_plucks_at_once(at_once, || {
                check(voice, nominal, offset_cents, pluck, velocities, 44_100.0)
            });
            checked.cents.iter().map(|cents| cents.to_bits()).collect()
        }
        let cases = [
            (Quality::Live, 1),
            (Quality::Live, 2),
            (Quality::Fine, 2),
            (Quality::Fine, MAX_PLUCKS_AT_ONCE),
            (Quality::Reference, MAX_PLUCKS_AT_ONCE),
        ];
        for (quality, at_once) in cases {
            let settings = VoiceSettings {
                quality,
                fundamental_hz: 146.83,
                ..VoiceSettings::default()
            };
            let pluck = Pluck::default();
            let moved = VoiceSettings {
                thread_position_m: settings.thread_position_m + THREAD_STEP_M,
                ..settings
            };
            let (mut one, mut other) = (
                TanpuraVoice::new(&settings, 44_100.0),
                TanpuraVoice::new(&settings, 44_100.0),
            );
            let nominal = settings.fundamental_hz;
            let expected = in_turn(&mut one, nominal, 2.0, &pluck, [0.3, 0.9]);
            let got = threaded(at_once, &mut other, nominal, 2.0, &pluck, [0.3, 0.9]);
            let cents: Vec<u64> = expected.iter().step_by(2).copied().collect();
            assert_eq!(
                got, cents,
                "{quality:?}, {at_once} at once: the first check"
            );
            one.set_settings(&moved);
            other.set_settings(&moved);
            let expected = in_turn(&mut one, nominal, -1.0, &pluck, [0.3, 0.6, 0.9]);
            let got = threaded(at_once, &mut other, nominal, -1.0, &pluck, [0.3, 0.6, 0.9]);
            let cents: Vec<u64> = expected.iter().step_by(2).copied().collect();
            assert_eq!(got, cents, "{quality:?}, {at_once} at once: after the move");
            // And the brightness, which `check` averages over the ends.
            let checked = check(&mut other, nominal, 0.0, &pluck, [0.3, 0.9], 44_100.0);
            let ends = in_turn(&mut one, nominal, 0.0, &pluck, [0.3, 0.9]);
            let brightness = 0.5 * f64::from_bits(ends[1]) + 0.5 * f64::from_bits(ends[3]);
            assert_eq!(
                checked.brightness_db.to_bits(),
                brightness.to_bits(),
                "{quality:?}"
            );
        }
    }

    /// Stop 32's calibration read the note from the voice's settings, which each render leaves at
    /// its own target: the check of a moved thread then rendered the string tuned by the
    /// unmoved offset on top of its own.
    #[test]
    fn a_check_tunes_from_the_note_whatever_the_voice_last_rendered() {
        let settings = VoiceSettings {
            quality: Quality::Live,
            ..VoiceSettings::default()
        };
        let nominal = settings.fundamental_hz;
        let mut voice = TanpuraVoice::new(&settings, 44_100.0);
        let pluck = Pluck::default();
        check(&mut voice, nominal, 30.0, &pluck, [0.5], 44_100.0);
        check(&mut voice, nominal, -3.0, &pluck, [0.5], 44_100.0);
        let tuned = voice.settings().fundamental_hz;
        let expected = nominal * (-3.0f64 / 1200.0).exp2();
        assert!(
            (tuned / expected - 1.0).abs() < 1e-12,
            "tuned to {tuned} Hz, expected {expected} Hz"
        );
    }
}
