//! Woodhouse's linearised stability analysis of Helmholtz motion (seed 001, sections 2–3).
//!
//! Source: J. Woodhouse, "On the stability of bowed string motion", Acustica 79 (1993)
//! (`shared/seeds/001_4b0eeabaed1af63b.txt`, restated in `shared/notes/bowed-model.md`).
//!
//! A small perturbation of a periodic bowed-string motion travels as velocity waves. Each time
//! step is a linear map of the perturbation's state; the bow scatters the two incident waves with
//! transmission `1 + r` and reflection `r`, where `r = ζ` while the underlying motion slips
//! (eq. 2–4) and `r = −γ` while it sticks (eq. 5–7; γ = 1 without torsion). The product of the
//! step matrices over one period of the motion is the transfer matrix; the motion is stable while
//! all its eigenvalues lie inside the unit circle.
//!
//! - [`spacetime`]: the space-time state vector of size 2(p + q) (eq. 14), whose time step is one
//!   segment's travel time; the Helmholtz motion is `M₁^{2p} M₂^{2q}` (eq. 15), the single-slip
//!   regimes of Fig. 8 `M₁^p M₂^{2q+p}` (eq. 16).
//! - [`compact`]: the history of outgoing waves (eq. 21–22), carrying any discrete reflection
//!   functions; its time step is two space-time steps, so the Helmholtz motion slips for p of its
//!   p + q steps.
//! - [`pattern`]: stick/slip sequences and the per-step bow reflection coefficients.
//! - [`spectrum`]: eigenvalues (with `faer`), moduli, phases and subharmonic orders.
//! - [`threshold`]: the smallest ζ at which an eigenvalue leaves the unit circle.
//! - [`transient`]: the time-domain Raman simulation of section 2.5, the cross-check.
//! - [`margin`]: the stability margin of a bowed setting, for warnings on unstable presets.
//!
//! Why the two formulations agree: the space-time grid is a checkerboard. A wave in segment k at
//! step n only ever meets waves of the same parity of `k + n` (a "u" wave) or `k − n + 1` (a "d"
//! wave), so the 2(p + q) amplitudes split into two interleaved, uncoupled halves, each of which
//! meets the bow every other step. Each half is one copy of the compact formulation; this is why
//! every eigenvalue of Table I appears twice. With an odd number N of slipping steps the halves see
//! ⌈N/2⌉ and ⌊N/2⌋ slips, and the space-time spectrum is the union of the two compact spectra
//! (tested in `tests/stability_tables.rs`).

pub mod compact;
pub mod margin;
pub mod pattern;
pub mod spacetime;
pub mod spectrum;
pub mod threshold;
pub mod transient;
pub mod voice_link;

pub use compact::{CompactModel, ReflectionFunction};
pub use margin::{stability_margin, BowedSetting, StabilityMargin};
pub use pattern::{BowContact, ContactPattern};
pub use spacetime::SpaceTimeModel;
pub use spectrum::{subharmonic_order, Eigenvalue};
pub use threshold::{PeriodicMotion, Threshold, ThresholdOutcome, ThresholdSearch};
pub use transient::{RamanTransient, RamanTransientConfig};
pub use voice_link::{voice_stability_margin, VoiceSetting};

use std::fmt;

/// Why a stability computation could not be carried out.
#[derive(Debug, Clone, PartialEq)]
pub enum StabilityError {
    /// A model or search parameter is outside its valid range; the message names it.
    InvalidParameter(String),
    /// The eigenvalue solver did not converge.
    EigenSolver(String),
}

impl fmt::Display for StabilityError {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StabilityError::InvalidParameter(message) => formatter.write_str(message),
            StabilityError::EigenSolver(message) => {
                write!(formatter, "eigenvalue solver failed: {message}")
            }
        }
    }
}

impl std::error::Error for StabilityError {}

/// A linear model of the perturbation's state whose one-step map depends only on the bow's
/// reflection coefficient `r` in that step (transmission `1 + r`).
pub trait TransferModel {
    /// Length of the state vector.
    fn state_len(&self) -> usize;

    /// Applies one time step to every column of `rows`, a row-major `state_len × columns`
    /// matrix: `rows ← S(r) · rows`. `scratch` has the same size and is overwritten.
    fn apply_step(&self, bow_reflection: f64, rows: &mut [f64], scratch: &mut [f64]);

    /// The explicit step matrix `S(r)` (the plain reference path, eq. 14 / 21 / 22).
    fn step_matrix(&self, bow_reflection: f64) -> faer::Mat<f64>;

    /// The transfer matrix over `bow_reflections.len()` steps, the first step applied first:
    /// `S(r_N) ··· S(r_2) S(r_1)`.
    fn transfer_matrix(&self, bow_reflections: &[f64]) -> faer::Mat<f64> {
        let size = self.state_len();
        let mut rows = vec![0.0; size * size];
        for index in 0..size {
            rows[index * size + index] = 1.0;
        }
        let mut scratch = vec![0.0; size * size];
        for &bow_reflection in bow_reflections {
            self.apply_step(bow_reflection, &mut rows, &mut scratch);
        }
        faer::Mat::from_fn(size, size, |row, column| rows[row * size + column])
    }

    /// The same product formed from explicit dense step matrices (reference path for tests).
    fn transfer_matrix_reference(&self, bow_reflections: &[f64]) -> faer::Mat<f64> {
        let size = self.state_len();
        let mut product = faer::Mat::<f64>::identity(size, size);
        for &bow_reflection in bow_reflections {
            product = self.step_matrix(bow_reflection) * &product;
        }
        product
    }
}

/// ζ of eq. 3 from the linearised friction slope: `ζ = k F_b Y₀ / (2 − k F_b Y₀)`.
///
/// `friction_slope_s_per_m` is k = dμ/dv at the operating point (f = F_b μ(v)),
/// `bow_force_n` is F_b and `admittance_s_per_kg` is Y₀ = 1/Z₀. Returns `None` when
/// `k F_b Y₀ ≥ 2`, where the linearised bow no longer has a finite transmission (eq. 2).
pub fn zeta_from_friction_slope(
    friction_slope_s_per_m: f64,
    bow_force_n: f64,
    admittance_s_per_kg: f64,
) -> Option<f64> {
    let loop_gain = friction_slope_s_per_m * bow_force_n * admittance_s_per_kg;
    (loop_gain < 2.0).then(|| loop_gain / (2.0 - loop_gain))
}

/// The approximate, linear form of eq. 3: `ζ ≈ k F_b Y₀ / 2`.
pub fn zeta_linear_approximation(
    friction_slope_s_per_m: f64,
    bow_force_n: f64,
    admittance_s_per_kg: f64,
) -> f64 {
    0.5 * friction_slope_s_per_m * bow_force_n * admittance_s_per_kg
}

/// Inverse of [`zeta_from_friction_slope`]: the bow force at which eq. 3 gives `zeta`.
pub fn bow_force_from_zeta(
    zeta: f64,
    friction_slope_s_per_m: f64,
    admittance_s_per_kg: f64,
) -> f64 {
    // ζ (2 − x) = x  ⇒  x = 2ζ / (1 + ζ), x = k F_b Y₀.
    2.0 * zeta / ((1.0 + zeta) * friction_slope_s_per_m * admittance_s_per_kg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeta_relation_round_trips_and_matches_its_linearisation() {
        let zeta = zeta_from_friction_slope(0.01, 1.75, 2.0).unwrap();
        assert!((zeta - 0.035 / 1.965).abs() < 1e-15);
        assert!((bow_force_from_zeta(zeta, 0.01, 2.0) - 1.75).abs() < 1e-12);
        assert!((zeta_linear_approximation(0.01, 1.75, 2.0) - 0.0175).abs() < 1e-15);
        assert_eq!(zeta_from_friction_slope(1.0, 1.0, 2.0), None);
    }
}
