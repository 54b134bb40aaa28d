//! The tanpura voice: one string, its tuning, its quality tier and its sleep.
//!
//! A voice holds one string per quality tier (`quality.rs`), all built up front, so switching
//! tiers never allocates; only the selected tier's string is computed, and switching starts it
//! at rest. The live and fine tiers run the modal scheme ([`ModalString`], at the output
//! rate, no latency), the studio tier the fine tier's modal string at the reference's step, and
//! the reference the seed's FD scheme ([`FdString`]), both at 4 × the output rate (seed 000:
//! 4 × 44.1 kHz); an oversampled tier is brought down by a Kaiser-windowed FIR (`decimator.rs`).
//!
//! A voice maps musician-facing settings in SI units onto either string: the tension follows the
//! pitch, `T = ρA (2 L_s f)² / (1 + B)` with the speaking length `L_s` from the thread (or the
//! bridge crest) to the nut and the stiff-string correction `B = π² EI / (T L_s²)` (solved by a
//! fixed-point pass), then two passes on the linearised fundamental of the string resting on bridge
//! and thread. The reference keeps the seed's EI with its grid's dispersion, which the fine and
//! studio tiers' grid modes share; the other modal tiers have none. The output is the pickup mix of
//! the nut force (eq. 13) and the bridge force (eq. 12) minus their values at rest, so a silent
//! string outputs exactly 0 and carries no DC.
//!
//! A voice whose vibration energy has fallen below [`SLEEP_ENERGY_J`] (−86 dB below a typical
//! pluck) is put exactly at rest and sleeps: no computation at all until its next pluck, once the
//! decimator's tail (oversampled tiers) has been flushed.

use super::excitation::Pluck;
use super::fd::decimator::Decimator;
use super::fd::{FdString, FdStringConfig};
use super::geometry::ThreadSettings;
use super::modal::{ModalString, ModalStringConfig};
use super::quality::{reference_grid_modes, Quality};
use super::string::StringParameters;
use super::tier_string::TierString;
use crate::newton::NewtonStats;
use std::fmt;

/// Vibration energy below which a string sleeps, J. A 2 mm pluck holds about 4e-4 J.
pub const SLEEP_ENERGY_J: f64 = 1e-12;
/// How often (in output samples) a voice checks whether it may sleep.
const SLEEP_CHECK_INTERVAL: u32 = 256;
/// Passes of the tension correction `T ← T (f / f_lin)²` that tunes a string by its linearised
/// fundamental (see `TanpuraVoice::configure_string`).
pub const TUNING_PASSES: usize = 2;

/// The tuning of every tier's string: [`TUNING_PASSES`] of `T ← T (f / f_lin)²` on `string`,
/// whose linearised fundamental `linearised_hz` gives, whose tension `tension_n` reads and
/// `set_tension` sets, towards `target_hz`. Stops (returning `None`) when no fundamental is
/// found. The voice tunes its strings with it, and `analysis::refined` tunes the offline
/// strings with it, so the two agree bit for bit. Allocation-free.
pub fn tune_tension<S>(
    string: &mut S,
    target_hz: f64,
    mut linearised_hz: impl FnMut(&mut S) -> f64,
    tension_n: impl Fn(&S) -> f64,
    mut set_tension: impl FnMut(&mut S, f64),
) -> Option<()> {
    for _ in 0..TUNING_PASSES {
        let linearised = linearised_hz(string);
        if !(linearised.is_finite() && linearised > 0.0) {
            return None;
        }
        let ratio = target_hz / linearised;
        let tension = tension_n(string) * ratio * ratio;
        set_tension(string, tension);
    }
    Some(())
}

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

    /// The FD string configuration these settings describe at an FD tier and
    /// `output_sample_rate_hz`; `None` for a modal tier.
    pub fn fd_config_at(
        &self,
        quality: Quality,
        output_sample_rate_hz: f64,
    ) -> Option<FdStringConfig> {
        let tier = quality.fd_tier()?;
        let mut config = FdStringConfig::REFERENCE;
        config.intervals = tier.intervals;
        config.time_step_s = 1.0 / (output_sample_rate_hz * tier.oversample as f64);
        config.bridge.stiffness_n_m2 = self.bridge_stiffness_n_m2;
        config.bridge.beyond_thread = self.bridge_beyond_thread;
        config.thread = self.thread_enabled.then_some(ThreadSettings {
            position_m: self.thread_position_m,
            ..ThreadSettings::SEED
        });
        config.string = self.string_parameters(config.speaking_start_m());
        config.newton = tier.newton;
        config.solver = tier.solver;
        Some(config)
    }

    /// The modal string configuration these settings describe at a modal tier and
    /// `output_sample_rate_hz`; `None` for an FD tier. The modal scheme has no dispersion, so the
    /// string keeps its own EI. A tier stepped at a multiple of the output rate keeps the grid
    /// modes of the output rate's reference (their poles are those of the reference's own time
    /// step, whatever the modal step).
    pub fn modal_config_at(
        &self,
        quality: Quality,
        output_sample_rate_hz: f64,
    ) -> Option<ModalStringConfig> {
        let tier = quality.modal_tier()?;
        let mut config = ModalStringConfig::REFERENCE;
        config.time_step_s = 1.0 / (output_sample_rate_hz * tier.oversample as f64);
        config.highest_mode_hz = tier.highest_mode_hz;
        config.bridge_point_spacing_m = tier.bridge_point_spacing_m;
        config.thread_point_spacing_m = tier.thread_point_spacing_m;
        config.bridge.stiffness_n_m2 = self.bridge_stiffness_n_m2;
        config.bridge.beyond_thread = self.bridge_beyond_thread;
        config.thread = self.thread_enabled.then_some(ThreadSettings {
            position_m: self.thread_position_m,
            ..ThreadSettings::SEED
        });
        config.string = self.string_parameters(config.speaking_start_m());
        config.newton = tier.newton;
        config.grid_modes = tier
            .grid_modes
            .then(|| reference_grid_modes(output_sample_rate_hz));
        Some(config)
    }

    /// The seed's string with these settings' losses and the tension that puts the speaking
    /// length from `speaking_start_m` at the pitch (before the contact-aware tuning of the voice).
    fn string_parameters(&self, speaking_start_m: f64) -> StringParameters {
        let mut string = StringParameters::SEED;
        string.gamma_per_s = self.gamma_per_s;
        string.eta_s = self.eta_s;
        string.tension_n = tension_for_pitch_n(&string, speaking_start_m, self.fundamental_hz);
        string
    }
}

/// The tension that tunes the speaking length from `speaking_start_m` to the nut to
/// `fundamental_hz`: `f = (1/2L_s) √(T/ρA) √(1 + B)`, `B = π² EI/(T L_s²)`, solved for T by
/// fixed point.
pub fn tension_for_pitch_n(
    string: &StringParameters,
    speaking_start_m: f64,
    fundamental_hz: f64,
) -> f64 {
    let speaking = string.length_m - speaking_start_m;
    let ideal = string.linear_density_kg_m * (2.0 * speaking * fundamental_hz).powi(2);
    let mut tension = ideal;
    for _ in 0..8 {
        let b = std::f64::consts::PI.powi(2) * string.bending_stiffness_n_m2
            / (tension * speaking * speaking);
        tension = ideal / (1.0 + b);
    }
    tension
}

/// One tanpura string with its tier's discretisation (and the oversampled tiers' decimation);
/// allocation-free after `new`.
#[derive(Debug, Clone)]
pub struct TanpuraVoice {
    settings: VoiceSettings,
    output_sample_rate_hz: f64,
    /// One string per quality tier, indexed by [`Quality::index`].
    strings: Vec<TierString>,
    /// The settings each tier's string was last configured for.
    configured: Vec<Option<VoiceSettings>>,
    /// How many times a string of this voice was tuned (the tension scaled to the pitch).
    tunings: u64,
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
        // Built with a thread so that its points exist if it is switched on later.
        let mut build = settings;
        build.thread_enabled = true;
        let strings = Quality::ALL
            .iter()
            .map(|&quality| {
                match build.modal_config_at(quality, output_sample_rate_hz) {
                    Some(config) => TierString::Modal(Box::new(ModalString::new(config))),
                    // Every tier that is not modal is FD.
                    None => TierString::FiniteDifference(Box::new(FdString::new(
                        build
                            .fd_config_at(quality, output_sample_rate_hz)
                            .unwrap_or_default(),
                    ))),
                }
            })
            .collect();
        let decimators = (1..=MAX_OVERSAMPLE).map(Decimator::new).collect();
        let mut voice = Self {
            settings,
            output_sample_rate_hz,
            strings,
            configured: vec![None; Quality::ALL.len()],
            tunings: 0,
            decimators,
            sleeping: true,
            tail_remaining: 0,
            samples_since_sleep_check: 0,
        };
        voice.configure_string(None);
        voice.string_mut().reset();
        voice
    }

    fn string_mut(&mut self) -> &mut TierString {
        &mut self.strings[self.settings.quality.index()]
    }

    /// The string of the selected tier.
    pub fn string(&self) -> &TierString {
        &self.strings[self.settings.quality.index()]
    }

    fn oversample(&self) -> usize {
        self.settings.quality.oversample()
    }

    /// Applies a configuration with the given tension to the selected tier's string.
    fn apply_config(&mut self, tension_n: Option<f64>) {
        let settings = self.settings;
        let rate = self.output_sample_rate_hz;
        match &mut self.strings[settings.quality.index()] {
            TierString::FiniteDifference(string) => {
                if let Some(mut config) = settings.fd_config_at(settings.quality, rate) {
                    if let Some(tension) = tension_n {
                        config.string.tension_n = tension;
                    }
                    string.set_config(config);
                }
            }
            TierString::Modal(string) => {
                if let Some(mut config) = settings.modal_config_at(settings.quality, rate) {
                    if let Some(tension) = tension_n {
                        config.string.tension_n = tension;
                    }
                    string.set_config(config);
                }
            }
        }
    }

    /// Configures the selected tier's string for the settings and tunes it: the tension is
    /// scaled until the linearised fundamental of the string resting on bridge and thread
    /// (`linearised_fundamental_hz` of either discretisation) is the requested pitch. The
    /// contact geometry makes the speaking length differ from "thread to nut" by up to 1 %,
    /// which would be 18 cents; two passes of `T ← T (f / f_lin)²` bring it under 0.1 cent.
    ///
    /// With `known_tension_n` (the tension these settings were tuned to before, by
    /// [`TanpuraVoice::tension_n`]), a change that needs the tuning configures the string once
    /// at that tension instead.
    fn configure_string(&mut self, known_tension_n: Option<f64>) {
        let settings = self.settings;
        let index = settings.quality.index();
        if self.configured[index] == Some(settings) {
            return;
        }
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
            // The losses change the step but not the rest state the tuning is computed on:
            // keep the tuned tension and skip the inverse iterations (the engine moves γ and η
            // every control tick while they glide).
            let losses_and_pickup = VoiceSettings {
                gamma_per_s: settings.gamma_per_s,
                eta_s: settings.eta_s,
                nut_pickup_weight: settings.nut_pickup_weight,
                ..previous
            };
            if losses_and_pickup == settings {
                let tension = self.strings[index].parameters().tension_n;
                self.apply_config(Some(tension));
                self.configured[index] = Some(settings);
                return;
            }
        }
        if let Some(tension) = known_tension_n.filter(|t| t.is_finite() && *t > 0.0) {
            self.apply_config(Some(tension));
            self.configured[index] = Some(settings);
            return;
        }
        self.tunings += 1;
        self.apply_config(None);
        // A string with no fundamental keeps the tension reached so far.
        let _ = tune_tension(
            self,
            settings.fundamental_hz,
            |voice| voice.strings[index].linearised_fundamental_hz(),
            |voice| voice.strings[index].parameters().tension_n,
            |voice, tension| voice.apply_config(Some(tension)),
        );
        self.configured[index] = Some(settings);
    }

    /// Applies new settings (clamped) without allocating. The string keeps ringing, unless
    /// the quality tier changes: the new tier's string then starts at rest.
    pub fn set_settings(&mut self, settings: &VoiceSettings) {
        self.apply_settings(settings, None);
    }

    /// [`TanpuraVoice::set_settings`] where the tension that tunes the string for `settings` is
    /// known: `tension_n` is [`TanpuraVoice::tension_n`] of a voice set to the same settings
    /// (their losses and pickup mix aside, which the tuning does not see). A retune then
    /// configures the string once at that tension, where [`TanpuraVoice::set_settings`] tunes it
    /// (three configurations and two linearised fundamentals; at the fine tier 235–237 µs against
    /// 67–68 µs, `--example note_on_cost`). Allocation-free.
    pub fn set_settings_tuned(&mut self, settings: &VoiceSettings, tension_n: f64) {
        self.apply_settings(settings, Some(tension_n));
    }

    /// The tension of the current tier's string, N: after a retune, what tunes it to the
    /// settings' pitch.
    pub fn tension_n(&self) -> f64 {
        self.strings[self.settings.quality.index()]
            .parameters()
            .tension_n
    }

    /// How many times this voice tuned a string (scaled its tension to the pitch) since it
    /// was made: a retune by [`TanpuraVoice::set_settings_tuned`] does not count.
    pub fn tunings(&self) -> u64 {
        self.tunings
    }

    fn apply_settings(&mut self, settings: &VoiceSettings, known_tension_n: Option<f64>) {
        let settings = settings.clamped();
        if settings == self.settings {
            return;
        }
        let tier_changed = settings.quality != self.settings.quality;
        self.settings = settings;
        self.configure_string(known_tension_n);
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
        self.string_mut().pluck(&pluck.clamped());
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
        self.string().pickup_n(self.settings.nut_pickup_weight)
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
        let output = if oversample == 1 {
            // A tier at the output rate: no decimator, no latency.
            self.string_mut().step();
            self.pickup_internal_n()
        } else {
            let mut output = 0.0;
            for _ in 0..oversample {
                self.string_mut().step();
                let pickup = self.pickup_internal_n();
                if let Some(y) = self.decimators[oversample - 1].push(pickup) {
                    output = y;
                }
            }
            output
        };
        self.samples_since_sleep_check += 1;
        if self.samples_since_sleep_check >= SLEEP_CHECK_INTERVAL {
            self.check_sleep();
        }
        output as f32
    }

    /// Every [`SLEEP_CHECK_INTERVAL`] samples: puts a decayed string to sleep.
    fn check_sleep(&mut self) {
        self.samples_since_sleep_check = 0;
        if self.string().vibration_energy_j() < SLEEP_ENERGY_J {
            self.string_mut().settle_to_rest();
            self.sleeping = true;
            let oversample = self.oversample();
            if oversample > 1 {
                let decimator = &self.decimators[oversample - 1];
                self.tail_remaining = decimator.taps().len() / oversample + 1;
            }
        }
    }

    /// Fills `output` with consecutive samples (overwrites): [`TanpuraVoice::next_sample`]'s
    /// samples bit for bit. A ringing modal string at the output rate runs its steps between sleep
    /// checks as one call ([`ModalString::step_into`]: one dispatch to the vector unit for the run,
    /// not one a sample).
    pub fn process(&mut self, output: &mut [f32]) {
        let nut_weight = self.settings.nut_pickup_weight;
        let mut done = 0;
        while done < output.len() {
            let until_check = SLEEP_CHECK_INTERVAL.saturating_sub(self.samples_since_sleep_check);
            let at_output_rate = !self.sleeping && self.oversample() == 1;
            if let (true, TierString::Modal(string)) = (at_output_rate, self.string_mut()) {
                let run = (until_check.max(1) as usize).min(output.len() - done);
                string.step_into(&mut output[done..done + run], nut_weight);
                done += run;
                self.samples_since_sleep_check += run as u32;
                if self.samples_since_sleep_check >= SLEEP_CHECK_INTERVAL {
                    self.check_sleep();
                }
                continue;
            }
            output[done] = self.next_sample();
            done += 1;
        }
    }

    /// False once the string has decayed and sleeps (no computation until the next pluck).
    pub fn is_active(&self) -> bool {
        !self.sleeping || self.tail_remaining > 0
    }

    /// Stops the string at its rest state, asleep, as [`TanpuraVoice::reset`] does, without
    /// solving that rest state again and keeping the string's statistics and ledgers: for a
    /// voice about to be retuned and plucked (a stolen voice), whose retune solves the new rest
    /// state. A modal string's reset re-solves the rest state it is about to leave: 17–23 µs
    /// at the fine tier when its memory is in cache, 35–593 µs when it is not; the retune's own
    /// solve then reads that memory, so the cold part moves to it and this saves the warm
    /// solve, with the output the same to the bit (`docs/performance.md`, "Stop 52").
    /// Allocation-free.
    pub fn stop(&mut self) {
        self.string_mut().settle_to_rest();
        self.fall_silent();
    }

    /// Silences the voice: string at rest (its rest state solved again, its statistics and
    /// ledgers cleared), decimators cleared.
    pub fn reset(&mut self) {
        self.string_mut().reset();
        self.fall_silent();
    }

    /// Clears the decimators and puts the voice to sleep with no tail left to play.
    fn fall_silent(&mut self) {
        for decimator in &mut self.decimators {
            decimator.reset();
        }
        self.sleeping = true;
        self.tail_remaining = 0;
    }

    pub fn newton_stats(&self) -> &NewtonStats {
        self.string().newton_stats()
    }

    /// Output latency, samples at the output rate: the decimation filter's delay for the
    /// oversampled tiers (studio and reference), none for the tiers at the output rate.
    pub fn latency_samples(&self) -> f64 {
        self.latency_samples_at(self.settings.quality)
    }

    /// The output latency this voice has at `quality` (its decimators are built for every
    /// oversampling factor up front), samples at the output rate.
    pub fn latency_samples_at(&self, quality: Quality) -> f64 {
        match quality.oversample() {
            1 => 0.0,
            oversample => self.decimators[oversample - 1].delay_output_samples(),
        }
    }
}
