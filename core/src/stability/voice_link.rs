//! From a bowed voice's controls to the stability margin of its Helmholtz motion.
//!
//! The voice (`bowed/bowed_string.rs`) is described in physical units: string constants, pitch,
//! bow position β, bow force and velocity, and raised-cosine reflection pulses of a given width
//! (s) and area. Woodhouse's analysis (seed 001, section 3) works on a grid of `steps` time steps
//! per period. This module puts the voice on that grid:
//!
//! - p = round(β · steps) steps on the bridge side (at least 1), q = steps − p on the finger side;
//! - each reflection pulse sampled on the grid around its round-trip delay, normalised to the
//!   pulse's area, sign inverted (a pulse narrower than one step is Raman's single tap);
//! - the friction slope at the Helmholtz operating point: while slipping, the string moves at
//!   −v_b(1/β − 1), i.e. |Δv| = v_b/β relative to the bow, where the hyperbolic law
//!   μ = μ_d + (μ_s − μ_d) v₀/(v₀ + |Δv|) falls with slope k = (μ_s − μ_d) v₀/(v₀ + v_b/β)²;
//! - Y₀ = 1/Z₀ and the bow force as they are; γ = 1 (no torsion in the voice).
//!
//! [`stability_margin`] then gives the critical bow force and the margin F_crit/F_b.

use super::compact::ReflectionFunction;
use super::margin::{stability_margin, BowedSetting, StabilityMargin};
use super::StabilityError;
use crate::bowed::{ReflectionPulse, StringConstants};

/// A bowed voice's setting in physical units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoiceSetting {
    pub constants: StringConstants,
    pub pitch_hz: f64,
    /// β, bow distance from the bridge over the vibrating length.
    pub beta: f64,
    pub bow_force_n: f64,
    pub bow_velocity_m_s: f64,
    /// Hyperbolic friction law: μ_s, μ_d, v₀ (m/s).
    pub static_friction: f64,
    pub dynamic_friction: f64,
    pub friction_velocity_m_s: f64,
}

impl VoiceSetting {
    /// The voice's default friction law (μ_s = 0.8, μ_d = 0.3, v₀ = 0.1 m/s).
    pub fn with_default_friction(
        constants: StringConstants,
        pitch_hz: f64,
        beta: f64,
        bow_force_n: f64,
        bow_velocity_m_s: f64,
    ) -> Self {
        Self {
            constants,
            pitch_hz,
            beta,
            bow_force_n,
            bow_velocity_m_s,
            static_friction: 0.8,
            dynamic_friction: 0.3,
            friction_velocity_m_s: 0.1,
        }
    }

    /// k = −dμ/d|Δv| at the Helmholtz slipping velocity, s/m.
    pub fn friction_slope_s_per_m(&self) -> f64 {
        let relative = self.bow_velocity_m_s.abs() / self.beta;
        let v0 = self.friction_velocity_m_s;
        (self.static_friction - self.dynamic_friction) * v0 / ((v0 + relative) * (v0 + relative))
    }
}

/// The pulse `pulse` (width in s, area) centred on `delay_steps`, on a grid of `step_s`.
fn pulse_on_grid(
    pulse: ReflectionPulse,
    delay_steps: usize,
    step_s: f64,
) -> Result<ReflectionFunction, StabilityError> {
    let half_width_steps = 0.5 * pulse.width_s / step_s;
    if half_width_steps < 1.0 {
        return ReflectionFunction::raman(delay_steps, pulse.area);
    }
    // Samples strictly inside the pulse (its ends are zeros of the raised cosine).
    let reach = (half_width_steps.ceil() as usize - 1).min(delay_steps - 1);
    let first = delay_steps - reach;
    // Raised cosine 1 + cos(π t / half width), sampled at integer offsets, scaled to the area.
    let mut taps: Vec<f64> = (0..=2 * reach)
        .map(|i| {
            let offset = i as f64 - reach as f64;
            1.0 + (std::f64::consts::PI * offset / half_width_steps).cos()
        })
        .collect();
    let sum: f64 = taps.iter().sum();
    for tap in &mut taps {
        *tap *= -pulse.area / sum;
    }
    ReflectionFunction::new(first, taps)
}

/// The analysis-grid model of a voice setting, with `steps` steps per period.
pub fn analysis_setting(
    setting: &VoiceSetting,
    steps: usize,
) -> Result<BowedSetting, StabilityError> {
    if !(setting.beta > 0.0 && setting.beta < 1.0 && setting.pitch_hz > 0.0 && steps >= 4) {
        return Err(StabilityError::InvalidParameter(format!(
            "voice setting: β = {} must lie in (0, 1), pitch = {} Hz must be positive and the \
             grid needs at least 4 steps (got {steps})",
            setting.beta, setting.pitch_hz
        )));
    }
    let p = ((setting.beta * steps as f64).round() as usize).clamp(1, steps - 1);
    let q = steps - p;
    let step_s = 1.0 / (setting.pitch_hz * steps as f64);
    Ok(BowedSetting {
        p,
        q,
        bridge_reflection: pulse_on_grid(setting.constants.bridge_pulse, p, step_s)?,
        finger_reflection: pulse_on_grid(setting.constants.nut_pulse, q, step_s)?,
        sticking_gamma: 1.0,
        friction_slope_s_per_m: setting.friction_slope_s_per_m(),
        bow_force_n: setting.bow_force_n,
        admittance_s_per_kg: 1.0 / setting.constants.wave_impedance_n_s_m(),
        slip_steps: None,
    })
}

/// Grid steps per period used for voice margins: fine enough that β = 0.05 gets 3 bridge-side
/// steps, coarse enough that a margin takes milliseconds.
pub const VOICE_GRID_STEPS: usize = 60;

/// The stability margin of a voice setting's Helmholtz motion.
pub fn voice_stability_margin(setting: &VoiceSetting) -> Result<StabilityMargin, StabilityError> {
    stability_margin(&analysis_setting(setting, VOICE_GRID_STEPS)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulses_keep_their_area_and_narrow_ones_become_raman_taps() {
        let wide = ReflectionPulse {
            width_s: 400e-6,
            area: 0.96,
        };
        let function = pulse_on_grid(wide, 20, 50e-6).unwrap();
        assert!((function.area() + 0.96).abs() < 1e-12);
        assert_eq!(function.taps().len(), 7);
        let narrow = ReflectionPulse {
            width_s: 40e-6,
            area: 0.98,
        };
        let function = pulse_on_grid(narrow, 6, 75e-6).unwrap();
        assert_eq!(function.taps(), &[-0.98]);
        assert_eq!(function.first_delay(), 6);
    }

    #[test]
    fn friction_slope_is_the_hyperbola_derivative_at_v_b_over_beta() {
        let setting =
            VoiceSetting::with_default_friction(StringConstants::violin_a(), 220.0, 0.1, 0.3, 0.1);
        // |Δv| = 1 m/s: 0.5 · 0.1 / 1.1² = 0.0413.
        assert!((setting.friction_slope_s_per_m() - 0.05 / 1.21).abs() < 1e-15);
    }
}
