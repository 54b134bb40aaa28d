//! The tanpura voice: one string, its tuning, its quality tier and its sleep.
//!
//! A voice holds one string per quality tier (`quality.rs`), all built up front, so switching
//! tiers never allocates; only the selected tier's string is computed, and switching starts it
//! at rest.
//!
//! A voice maps musician-facing settings in SI units onto [`FdString`]: the tension follows
//! the pitch, `T = ρA (2 L_s f)² / (1 + B)` with the speaking length `L_s` from the thread (or the
//! bridge crest) to the nut and the stiff-string correction `B = π² EI / (T L_s²)` (solved by a
//! fixed-point pass); the scheme runs at `oversample ×` the output rate (seed 000: 4 × 44.1 kHz)
//! and a Kaiser-windowed FIR (`decimator.rs`) brings it down. The output is the pickup mix of the
//! nut force (eq. 13) and the bridge force (eq. 12) minus their values at rest, so a silent string
//! outputs exactly 0 and carries no DC.
//!
//! A voice whose vibration energy has fallen below [`SLEEP_ENERGY_J`] (−86 dB below a typical
//! pluck) is put exactly at rest and sleeps: no computation at all until its next pluck, once the
//! decimator's tail has been flushed.

use super::excitation::Pluck;
use super::fd::decimator::Decimator;
use super::fd::{FdString, FdStringConfig};
use super::geometry::ThreadSettings;
use super::quality::Quality;
use super::string::StringParameters;
use crate::newton::NewtonStats;
use std::fmt;

/// Vibration energy below which a string sleeps, J. A 2 mm pluck holds about 4e-4 J.
pub const SLEEP_ENERGY_J: f64 = 1e-12;
/// How often (in output samples) a voice checks whether it may sleep.
const SLEEP_CHECK_INTERVAL: u32 = 256;
/// Passes of the tension correction that tunes a string (see `configure_string`).
const TUNING_PASSES: usize = 2;
/// Largest internal oversampling factor.
pub const MAX_OVERSAMPLE: usize = 8;

/// What a musician sets on one tanpura string, in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoiceSettings {
    /// String pitch, Hz (20–2000).
    pub fundamental_hz: f64,
    /// k_b, N/m² (0–1e12; seed 1e8).
    pub bridge_stiffness_n_m2: f64,
    pub thread_enabled: bool,
    /// x_c, m from the tuning bead (0.030–0.045; seed 0.040).
    pub thread_position_m: f64,
    /// False sets k_b = 0 beyond the thread.
    pub bridge_beyond_thread: bool,
    /// γ, 1/s (0–20; seed 0.6).
    pub gamma_per_s: f64,
    /// η, s (0–1e-6; seed 7e-9).
    pub eta_s: f64,
    /// Output = w · nut force + (1 − w) · bridge force (0–1).
    pub nut_pickup_weight: f64,
    /// Speed against accuracy: oversampling, grids, Newton tolerance and cap (`quality.rs`).
    pub quality: Quality,
}

/// The string pitch at which the seed's tension (31.47 N) is reached with the default thread.
pub fn reference_fundamental_hz() -> f64 {
    let config = FdStringConfig::REFERENCE;
    let speaking = config.string.length_m - config.speaking_start_m();
    let p = config.string;
    let stiffness_factor = 1.0
        + std::f64::consts::PI.powi(2) * p.bending_stiffness_n_m2
            / (p.tension_n * speaking * speaking);
    p.wave_speed_m_s() / (2.0 * speaking) * stiffness_factor.sqrt()
}

impl Default for VoiceSettings {
    /// The seed's reference string and configuration.
    fn default() -> Self {
        Self {
            fundamental_hz: reference_fundamental_hz(),
            bridge_stiffness_n_m2: 1e8,
            thread_enabled: true,
            thread_position_m: ThreadSettings::SEED.position_m,
            bridge_beyond_thread: true,
            gamma_per_s: StringParameters::SEED.gamma_per_s,
            eta_s: StringParameters::SEED.eta_s,
            nut_pickup_weight: 1.0,
            quality: Quality::Reference,
        }
    }
}

/// A setting outside its valid range.
#[derive(Debug, Clone, PartialEq)]
pub struct SettingsError {
    pub field: &'static str,
    pub value: f64,
    pub min: f64,
    pub max: f64,
}

impl fmt::Display for SettingsError {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            formatter,
            "`{}` = {} is out of range, expected {} to {}",
            self.field, self.value, self.min, self.max
        )
    }
}

impl std::error::Error for SettingsError {}

impl VoiceSettings {
    pub const FUNDAMENTAL_RANGE_HZ: (f64, f64) = (20.0, 2000.0);
    pub const BRIDGE_STIFFNESS_RANGE: (f64, f64) = (0.0, 1e12);
    pub const GAMMA_RANGE: (f64, f64) = (0.0, 20.0);
    pub const ETA_RANGE: (f64, f64) = (0.0, 1e-6);

    fn ranges(&self) -> [(&'static str, f64, (f64, f64)); 6] {
        [
            (
                "fundamental_hz",
                self.fundamental_hz,
                Self::FUNDAMENTAL_RANGE_HZ,
            ),
            (
                "bridge_stiffness_n_m2",
                self.bridge_stiffness_n_m2,
                Self::BRIDGE_STIFFNESS_RANGE,
            ),
            (
                "thread_position_m",
                self.thread_position_m,
                ThreadSettings::POSITION_RANGE_M,
            ),
            ("gamma_per_s", self.gamma_per_s, Self::GAMMA_RANGE),
            ("eta_s", self.eta_s, Self::ETA_RANGE),
            ("nut_pickup_weight", self.nut_pickup_weight, (0.0, 1.0)),
        ]
    }

    /// Checks every field; the error names the first one out of range (NaN is out of range).
    pub fn validate(&self) -> Result<(), SettingsError> {
        for (field, value, (min, max)) in self.ranges() {
            if !(min <= value && value <= max) {
                return Err(SettingsError {
                    field,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }

    /// The nearest valid settings (NaN becomes the default). For the audio thread.
    pub fn clamped(&self) -> Self {
        let default = Self::default();
        let clamp = |value: f64, (min, max): (f64, f64), fallback: f64| {
            if value.is_nan() {
                fallback
            } else {
                value.clamp(min, max)
            }
        };
        Self {
            fundamental_hz: clamp(
                self.fundamental_hz,
                Self::FUNDAMENTAL_RANGE_HZ,
                default.fundamental_hz,
            ),
            bridge_stiffness_n_m2: clamp(
                self.bridge_stiffness_n_m2,
                Self::BRIDGE_STIFFNESS_RANGE,
                default.bridge_stiffness_n_m2,
            ),
            thread_enabled: self.thread_enabled,
            thread_position_m: clamp(
                self.thread_position_m,
                ThreadSettings::POSITION_RANGE_M,
                default.thread_position_m,
            ),
            bridge_beyond_thread: self.bridge_beyond_thread,
            gamma_per_s: clamp(self.gamma_per_s, Self::GAMMA_RANGE, default.gamma_per_s),
            eta_s: clamp(self.eta_s, Self::ETA_RANGE, default.eta_s),
            nut_pickup_weight: clamp(self.nut_pickup_weight, (0.0, 1.0), 1.0),
            quality: self.quality,
        }
    }

    /// The string configuration these settings describe at `output_sample_rate_hz`, at the
    /// settings' own quality tier.
    pub fn string_config(&self, output_sample_rate_hz: f64) -> FdStringConfig {
        self.string_config_at(self.quality, output_sample_rate_hz)
    }

    /// The string configuration at a given quality tier.
    pub fn string_config_at(&self, quality: Quality, output_sample_rate_hz: f64) -> FdStringConfig {
        let tier = quality.tier();
        let mut config = FdStringConfig::REFERENCE;
        config.intervals = tier.intervals;
        config.time_step_s = 1.0 / (output_sample_rate_hz * tier.oversample as f64);
        config.bridge.spacing_m *= tier.barrier_spacing_scale;
        config.bridge.stiffness_n_m2 = self.bridge_stiffness_n_m2;
        config.bridge.beyond_thread = self.bridge_beyond_thread;
        config.thread = self.thread_enabled.then_some(ThreadSettings {
            position_m: self.thread_position_m,
            spacing_m: ThreadSettings::SEED.spacing_m * tier.barrier_spacing_scale,
            ..ThreadSettings::SEED
        });
        config.string.gamma_per_s = self.gamma_per_s;
        config.string.eta_s = self.eta_s;
        config.string.tension_n =
            tension_for_pitch_n(&config, config.speaking_start_m(), self.fundamental_hz);
        config.string.bending_stiffness_n_m2 = dispersion_compensated_stiffness(
            &config,
            quality,
            self.fundamental_hz,
            output_sample_rate_hz,
        );
        config.newton = tier.newton;
        config.solver = tier.solver;
        config
    }
}

/// The tension that tunes the speaking length from `speaking_start_m` to the nut to
/// `fundamental_hz`: `f = (1/2L_s) √(T/ρA) √(1 + B)`, `B = π² EI/(T L_s²)`, solved for T by
/// fixed point.
pub fn tension_for_pitch_n(
    config: &FdStringConfig,
    speaking_start_m: f64,
    fundamental_hz: f64,
) -> f64 {
    let p = config.string;
    let speaking = p.length_m - speaking_start_m;
    let ideal = p.linear_density_kg_m * (2.0 * speaking * fundamental_hz).powi(2);
    let mut tension = ideal;
    for _ in 0..8 {
        let b = std::f64::consts::PI.powi(2) * p.bending_stiffness_n_m2
            / (tension * speaking * speaking);
        tension = ideal / (1.0 + b);
    }
    tension
}

/// Relative flattening of partial n, per n², that the scheme's discretisation causes at a
/// fundamental `fundamental_hz` over the speaking length `speaking_m`: `(πΔx/L_s)²/24` from the
/// second difference in space and `(2πf₀Δt)²/12` from the trapezoidal rule in time (both
/// lower the frequencies; the leading terms of their Taylor series).
fn dispersion_per_n_squared(
    spacing_m: f64,
    time_step_s: f64,
    speaking_m: f64,
    fundamental_hz: f64,
) -> f64 {
    let space = (std::f64::consts::PI * spacing_m / speaking_m).powi(2) / 24.0;
    let time = (2.0 * std::f64::consts::PI * fundamental_hz * time_step_s).powi(2) / 12.0;
    space + time
}

/// The bending stiffness that gives a tier the same n² inharmonicity as the reference tier.
///
/// Stiffness raises partial n by `B n²/2` (relative, `B = π² EI/(T L_s²)`), the discretisation
/// lowers it by `c n²` (see [`dispersion_per_n_squared`]). A coarser tier has a larger `c`; raising
/// its `B` by `2(c_tier − c_reference)` cancels the difference to leading order, so the first ten
/// partials of every tier stay close to the reference's. The reference keeps the seed's EI.
fn dispersion_compensated_stiffness(
    config: &FdStringConfig,
    quality: Quality,
    fundamental_hz: f64,
    output_sample_rate_hz: f64,
) -> f64 {
    let p = config.string;
    let speaking = p.length_m - config.speaking_start_m();
    let tier_dispersion = dispersion_per_n_squared(
        p.length_m / config.intervals as f64,
        config.time_step_s,
        speaking,
        fundamental_hz,
    );
    let reference = Quality::Reference.tier();
    let reference_dispersion = dispersion_per_n_squared(
        p.length_m / reference.intervals as f64,
        1.0 / (output_sample_rate_hz * reference.oversample as f64),
        speaking,
        fundamental_hz,
    );
    if quality == Quality::Reference {
        return p.bending_stiffness_n_m2;
    }
    let pi2 = std::f64::consts::PI.powi(2);
    let inharmonicity = pi2 * p.bending_stiffness_n_m2 / (p.tension_n * speaking * speaking)
        + 2.0 * (tier_dispersion - reference_dispersion);
    inharmonicity * p.tension_n * speaking * speaking / pi2
}

/// One tanpura string with its oversampling and decimation; allocation-free after `new`.
#[derive(Debug, Clone)]
pub struct TanpuraVoice {
    settings: VoiceSettings,
    output_sample_rate_hz: f64,
    /// One string per quality tier, indexed by [`Quality::index`].
    strings: Vec<FdString>,
    /// The settings each tier's string was last configured for.
    configured: Vec<Option<VoiceSettings>>,
    /// One decimator per oversampling factor, built up front.
    decimators: Vec<Decimator>,
    sleeping: bool,
    /// Output samples of zeros still to push through the decimator after falling asleep.
    tail_remaining: usize,
    samples_since_sleep_check: u32,
}

impl TanpuraVoice {
    /// A silent voice at rest. Invalid settings are clamped. Allocates every tier's string.
    pub fn new(settings: &VoiceSettings, output_sample_rate_hz: f64) -> Self {
        let settings = settings.clamped();
        let strings = Quality::ALL
            .iter()
            .map(|&quality| {
                // Built with a thread so that its grid exists if it is switched on later.
                let mut build = settings;
                build.thread_enabled = true;
                FdString::new(build.string_config_at(quality, output_sample_rate_hz))
            })
            .collect();
        let decimators = (1..=MAX_OVERSAMPLE).map(Decimator::new).collect();
        let mut voice = Self {
            settings,
            output_sample_rate_hz,
            strings,
            configured: vec![None; Quality::ALL.len()],
            decimators,
            sleeping: true,
            tail_remaining: 0,
            samples_since_sleep_check: 0,
        };
        voice.configure_string();
        voice.string_mut().reset();
        voice
    }

    fn string_mut(&mut self) -> &mut FdString {
        &mut self.strings[self.settings.quality.index()]
    }

    /// The string of the selected tier.
    pub fn string(&self) -> &FdString {
        &self.strings[self.settings.quality.index()]
    }

    fn oversample(&self) -> usize {
        self.settings.quality.tier().oversample
    }

    /// Configures the selected tier's string for the settings and tunes it: the tension is
    /// scaled until the linearised fundamental of the string resting on bridge and thread
    /// ([`FdString::linearised_fundamental_hz`]) is the requested pitch. The contact
    /// geometry makes the speaking length differ from "thread to nut" by up to 1 %, which
    /// would be 18 cents; two passes of `T ← T (f / f_lin)²` bring it under 0.1 cent.
    fn configure_string(&mut self) {
        let settings = self.settings;
        let index = settings.quality.index();
        if self.configured[index] == Some(settings) {
            return;
        }
        let mut config = settings.string_config(self.output_sample_rate_hz);
        let string = &mut self.strings[index];
        if let Some(previous) = self.configured[index] {
            // The pickup mix does not touch the string at all.
            let pickup_only = VoiceSettings {
                nut_pickup_weight: settings.nut_pickup_weight,
                ..previous
            };
            if pickup_only == settings {
                self.configured[index] = Some(settings);
                return;
            }
            // The losses change the step matrix but not the rest state the tuning is computed
            // on: keep the tuned tension and skip the inverse iterations (the engine moves γ
            // and η every control tick while they glide).
            let losses_and_pickup = VoiceSettings {
                gamma_per_s: settings.gamma_per_s,
                eta_s: settings.eta_s,
                nut_pickup_weight: settings.nut_pickup_weight,
                ..previous
            };
            if losses_and_pickup == settings {
                config.string.tension_n = string.config().string.tension_n;
                string.set_config(config);
                self.configured[index] = Some(settings);
                return;
            }
        }
        string.set_config(config);
        for _ in 0..TUNING_PASSES {
            let linearised = string.linearised_fundamental_hz();
            if !(linearised.is_finite() && linearised > 0.0) {
                break;
            }
            let ratio = settings.fundamental_hz / linearised;
            config.string.tension_n *= ratio * ratio;
            string.set_config(config);
        }
        self.configured[index] = Some(settings);
    }

    /// Applies new settings (clamped) without allocating. The string keeps ringing, unless
    /// the quality tier changes: the new tier's string then starts at rest.
    pub fn set_settings(&mut self, settings: &VoiceSettings) {
        let settings = settings.clamped();
        if settings == self.settings {
            return;
        }
        let tier_changed = settings.quality != self.settings.quality;
        self.settings = settings;
        self.configure_string();
        if tier_changed {
            let oversample = self.oversample();
            self.decimators[oversample - 1].reset();
            self.string_mut().settle_to_rest();
            self.sleeping = true;
            self.tail_remaining = 0;
        } else if self.sleeping {
            self.string_mut().settle_to_rest();
        }
    }

    pub fn settings(&self) -> &VoiceSettings {
        &self.settings
    }

    /// Plucks the string (and wakes it). Allocation-free.
    pub fn pluck(&mut self, pluck: &Pluck) {
        self.string_mut().pluck(pluck);
        self.sleeping = false;
        self.tail_remaining = 0;
        self.samples_since_sleep_check = 0;
    }

    /// The seed's "first mode" excitation (and wakes the string).
    pub fn excite_first_mode(&mut self, amplitude_m: f64) {
        self.string_mut().excite_first_mode(amplitude_m);
        self.sleeping = false;
        self.tail_remaining = 0;
        self.samples_since_sleep_check = 0;
    }

    /// The pickup at the internal rate, N: the nut/bridge mix minus its value at rest.
    pub fn pickup_internal_n(&self) -> f64 {
        let string = self.string();
        let w = self.settings.nut_pickup_weight;
        let nut = string.nut_force_n() - string.rest_nut_force_n();
        let bridge = string.bridge_force_n() - string.rest_bridge_force_n();
        w * nut + (1.0 - w) * bridge
    }

    /// One output-rate sample of the pickup signal, N.
    pub fn next_sample(&mut self) -> f32 {
        let oversample = self.oversample();
        if self.sleeping {
            if self.tail_remaining == 0 {
                return 0.0;
            }
            self.tail_remaining -= 1;
            let decimator = &mut self.decimators[oversample - 1];
            let mut output = 0.0;
            for _ in 0..oversample {
                if let Some(y) = decimator.push(0.0) {
                    output = y;
                }
            }
            return output as f32;
        }
        let mut output = 0.0;
        for _ in 0..oversample {
            self.string_mut().step();
            let pickup = self.pickup_internal_n();
            if let Some(y) = self.decimators[oversample - 1].push(pickup) {
                output = y;
            }
        }
        self.samples_since_sleep_check += 1;
        if self.samples_since_sleep_check >= SLEEP_CHECK_INTERVAL {
            self.samples_since_sleep_check = 0;
            if self.string().vibration_energy_j() < SLEEP_ENERGY_J {
                self.string_mut().settle_to_rest();
                self.sleeping = true;
                let decimator = &self.decimators[oversample - 1];
                self.tail_remaining = decimator.taps().len() / oversample + 1;
            }
        }
        output as f32
    }

    /// Fills `output` with consecutive samples (overwrites).
    pub fn process(&mut self, output: &mut [f32]) {
        for sample in output {
            *sample = self.next_sample();
        }
    }

    /// False once the string has decayed and sleeps (no computation until the next pluck).
    pub fn is_active(&self) -> bool {
        !self.sleeping || self.tail_remaining > 0
    }

    /// Silences the voice: string at rest, decimators cleared.
    pub fn reset(&mut self) {
        self.string_mut().reset();
        for decimator in &mut self.decimators {
            decimator.reset();
        }
        self.sleeping = true;
        self.tail_remaining = 0;
    }

    pub fn newton_stats(&self) -> &NewtonStats {
        self.string().newton_stats()
    }

    /// Output latency of the decimation filter, samples at the output rate.
    pub fn latency_samples(&self) -> f64 {
        self.decimators[self.oversample() - 1].delay_output_samples()
    }
}
