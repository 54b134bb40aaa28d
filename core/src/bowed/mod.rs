//! The bowed-string voice: the McIntyre–Schumacher–Woodhouse rounded-corner model and the STK
//! bow-table tier (`shared/notes/bowed-model.md`).
//!
//! One file per part:
//!
//! - [`delay_line`]: the mirrored power-of-two history both tiers read at fixed and fractional
//!   delays;
//! - [`reflection`]: the bridge-side and nut/finger-side reflection functions (Woodhouse 1993,
//!   section 3.1), with fractional delays and Raman's single tap as the limiting case;
//! - [`friction`]: the friction law (hyperbolic by default) returning value and slope;
//! - [`bow_point`]: the per-sample intersection of the string's line with the friction curve,
//!   with hysteresis;
//! - [`body`]: an optional body filter of a few resonances;
//! - [`bowed_string`]: [`BowedString`], the rounded-corner voice;
//! - [`bow_table`]: [`BowTableString`], the STK bow-table waveguide (seed 004), the cheap tier;
//! - [`instrument`]: [`BowedInstrument`], MIDI gestures mapped onto one bowed string.
//!
//! Both voices implement [`BowedVoice`], so the plugin can switch tiers behind one interface.

pub mod body;
pub mod bow_point;
pub mod bow_table;
pub mod bowed_string;
pub mod delay_line;
pub mod friction;
pub mod instrument;
pub mod reflection;

pub use body::{BodyFilter, BodyResonance, VIOLIN_BODY};
pub use bow_point::{BowPoint, BowPointSolution, ContactState};
pub use bow_table::{bow_table_reflection, bow_table_slope, BowTableString};
pub use bowed_string::{BowedString, StringConstants};
pub use friction::{ExponentialFriction, FrictionLaw, HyperbolicFriction};
pub use instrument::{BowTier, BowedEvent, BowedInstrument, BowedPlayerSettings};
pub use reflection::{ReflectionFunction, ReflectionPulse};

/// Capacity a voice is built for: `new()` allocates for these, `prepare()` must stay within.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BowedCapacity {
    /// Highest sample rate `prepare()` will accept, Hz.
    pub max_sample_rate_hz: f64,
    /// Lowest string pitch the delay lines can hold at that rate, Hz.
    pub lowest_pitch_hz: f64,
}

impl Default for BowedCapacity {
    /// 384 kHz and 30 Hz: every rate from 22.05 kHz up, down to below a double bass's low E
    /// (41.2 Hz).
    fn default() -> Self {
        Self {
            max_sample_rate_hz: 384_000.0,
            lowest_pitch_hz: 30.0,
        }
    }
}

impl BowedCapacity {
    /// Whether a voice built for this capacity accepts `sample_rate_hz` in `prepare()`.
    pub fn check_sample_rate(&self, sample_rate_hz: f64) -> Result<(), BowedConfigError> {
        let max_hz = self.max_sample_rate_hz;
        if (MIN_SAMPLE_RATE_HZ..=max_hz).contains(&sample_rate_hz) {
            Ok(())
        } else {
            Err(BowedConfigError::SampleRate {
                requested_hz: sample_rate_hz,
                min_hz: MIN_SAMPLE_RATE_HZ,
                max_hz,
            })
        }
    }
}

/// Lowest sample rate a voice accepts, Hz.
pub const MIN_SAMPLE_RATE_HZ: f64 = 8_000.0;

/// A configuration error from `prepare()` (never raised on the audio thread).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BowedConfigError {
    /// The sample rate is outside [`MIN_SAMPLE_RATE_HZ`, capacity.max_sample_rate_hz].
    SampleRate {
        /// The rate asked for, Hz.
        requested_hz: f64,
        /// Lowest accepted rate, Hz.
        min_hz: f64,
        /// Highest accepted rate (the capacity given to `new()`), Hz.
        max_hz: f64,
    },
}

impl core::fmt::Display for BowedConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::SampleRate {
                requested_hz,
                min_hz,
                max_hz,
            } => write!(
                f,
                "sample_rate_hz = {requested_hz} is outside the supported range {min_hz} to {max_hz} Hz \
                 (raise BowedCapacity::max_sample_rate_hz in new() for higher rates)"
            ),
        }
    }
}

impl std::error::Error for BowedConfigError {}

/// One output sample of a bowed voice.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BowedOutput {
    /// Transverse force of the string on the bridge, N (delayed by half the bridge-side round
    /// trip, see [`BowedString`]).
    pub bridge_force_n: f64,
    /// String velocity at the bow point, m/s.
    pub bow_point_velocity_m_s: f64,
    /// The bridge force through the body filter when it is enabled, else the bridge force;
    /// the signal to listen to.
    pub radiated: f64,
}

/// The interface both bowed tiers implement: the plugin sets the player's controls (SI units)
/// and pulls samples.
///
/// Setters may be called every sample; they never allocate. Out-of-range or non-finite values
/// are clamped or ignored as each setter documents, never a panic.
pub trait BowedVoice {
    /// Set the sample rate; errors if it is outside the capacity given to `new()`. Resets.
    fn prepare(&mut self, sample_rate_hz: f64) -> Result<(), BowedConfigError>;
    /// Silence: zero every state, keep parameters.
    fn reset(&mut self);
    /// Sounding pitch of the string, Hz (the finger sets the vibrating length).
    fn set_pitch_hz(&mut self, pitch_hz: f64);
    /// Bow normal force F_b, N (≥ 0; 0 is the bow lifted).
    fn set_bow_force_n(&mut self, bow_force_n: f64);
    /// Bow velocity v_b, m/s (either sign).
    fn set_bow_velocity_m_s(&mut self, bow_velocity_m_s: f64);
    /// Bow position β: distance from the bridge over vibrating length (0 to 1, sensible 0.02 to
    /// 0.3).
    fn set_bow_position(&mut self, beta: f64);
    /// Enable or bypass the body filter.
    fn set_body_enabled(&mut self, enabled: bool);
    /// Advance one sample. Allocation-free; NaN/Inf silences and resets the voice.
    fn next_sample(&mut self) -> BowedOutput;

    /// Advance `radiated.len()` samples with the controls as they are, writing the radiated
    /// signal: the same samples as that many [`Self::next_sample`] calls, bit for bit, but the
    /// voices keep their state in registers across the block instead of storing and reloading
    /// it every sample. Allocation-free.
    fn process(&mut self, radiated: &mut [f32]) {
        for sample in radiated.iter_mut() {
            *sample = self.next_sample().radiated as f32;
        }
    }
}
