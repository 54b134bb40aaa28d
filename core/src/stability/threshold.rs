//! The stability threshold: the smallest ζ at which an eigenvalue of the transfer matrix leaves
//! the unit circle (seed 001, section 2.4: "a simple iteration based on linear interpolation may
//! now be used to vary ζ and search for the condition at which the most unstable eigenvector
//! crosses the unit circle").
//!
//! The spectral radius ρ(ζ) is continuous but need not be monotonic, and it has kinks where the
//! dominant eigenvalue changes. The search therefore first walks a geometric grid upwards from
//! `zeta_min` (ratio `grid_ratio`) until ρ exceeds 1, which brackets the first crossing the grid
//! can resolve, and then refines the bracket by regula falsi with the Illinois modification and a
//! bisection safeguard until it is narrower than `tolerance`. An unstable window narrower than
//! one grid ratio below the first crossing found would be missed; the default ratio 1.25 is far
//! finer than any feature of Figs. 7–16.
//!
//! For Raman's model the threshold is reported as α = ζ/ε with ε = 1 − λ (eq. 13).

use super::pattern::ContactPattern;
use super::spectrum::{spectrum, Eigenvalue};
use super::{StabilityError, TransferModel};

/// ρ must exceed 1 by this much to count as outside the unit circle. It keeps the exactly neutral
/// eigenvalue 1 of the Friedlander model (λ = 1, eq. 18–19) from being read as unstable through
/// rounding, and shifts a threshold by only about 1e-12 / (dρ/dζ).
pub const UNIT_CIRCLE_SLACK: f64 = 1e-12;

/// A periodic motion to analyse: a transfer model, its stick/slip pattern and the sticking γ.
#[derive(Debug, Clone)]
pub struct PeriodicMotion<M: TransferModel> {
    /// The state-vector formulation.
    pub model: M,
    /// Contact states over one period, in the model's time steps.
    pub pattern: ContactPattern,
    /// Sticking reflection magnitude γ (eq. 6), 0 ≤ γ ≤ 1; 1 without torsion.
    pub gamma: f64,
}

impl<M: TransferModel> PeriodicMotion<M> {
    /// Checks that γ lies in [0, 1].
    pub fn new(model: M, pattern: ContactPattern, gamma: f64) -> Result<Self, StabilityError> {
        if !(0.0..=1.0).contains(&gamma) {
            return Err(StabilityError::InvalidParameter(format!(
                "gamma: {gamma} is out of range, expected 0 <= gamma <= 1"
            )));
        }
        Ok(Self {
            model,
            pattern,
            gamma,
        })
    }

    /// The transfer matrix over one period with a uniform ζ while slipping.
    pub fn transfer_matrix(&self, zeta: f64) -> faer::Mat<f64> {
        self.model
            .transfer_matrix(&self.pattern.bow_reflections(zeta, self.gamma))
    }

    /// Its eigenvalues, by decreasing modulus.
    pub fn spectrum(&self, zeta: f64) -> Result<Vec<Eigenvalue>, StabilityError> {
        spectrum(&self.transfer_matrix(zeta))
    }

    /// Its spectral radius.
    pub fn spectral_radius(&self, zeta: f64) -> Result<f64, StabilityError> {
        Ok(self
            .spectrum(zeta)?
            .first()
            .map_or(0.0, |eigenvalue| eigenvalue.modulus))
    }
}

/// How the threshold is searched for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThresholdSearch {
    /// Smallest ζ examined (> 0).
    pub zeta_min: f64,
    /// Largest ζ examined.
    pub zeta_max: f64,
    /// Ratio between successive ζ of the bracketing grid (> 1).
    pub grid_ratio: f64,
    /// Width of the final bracket in ζ.
    pub tolerance: f64,
}

impl Default for ThresholdSearch {
    fn default() -> Self {
        Self {
            zeta_min: 1e-6,
            zeta_max: 1e3,
            grid_ratio: 1.25,
            tolerance: 1e-10,
        }
    }
}

/// The threshold found.
#[derive(Debug, Clone, PartialEq)]
pub struct Threshold {
    /// Critical ζ: midpoint of the final bracket, within `tolerance / 2` of the crossing.
    pub zeta: f64,
    /// The eigenvalue on the unit circle at the threshold (largest modulus there).
    pub critical: Eigenvalue,
    /// The whole spectrum at the threshold, by decreasing modulus.
    pub spectrum: Vec<Eigenvalue>,
    /// Number of eigenvalue problems solved.
    pub evaluations: usize,
}

impl Threshold {
    /// α = ζ/ε for Raman's model with termination reflection −λ, ε = 1 − λ (eq. 13).
    pub fn alpha(&self, lambda: f64) -> f64 {
        self.zeta / (1.0 - lambda)
    }
}

/// The result of a threshold search.
#[derive(Debug, Clone, PartialEq)]
pub enum ThresholdOutcome {
    /// An eigenvalue leaves the unit circle at this ζ.
    Crossing(Threshold),
    /// Every eigenvalue stays inside the unit circle up to `zeta_max`.
    StableUpTo {
        /// The largest ζ examined.
        zeta_max: f64,
    },
    /// Already unstable at `zeta_min` (e.g. λ = 1 with a "between-the-raindrops" pattern).
    UnstableFrom {
        /// The smallest ζ examined.
        zeta_min: f64,
        /// The spectrum there.
        spectrum: Vec<Eigenvalue>,
    },
}

impl ThresholdOutcome {
    /// The threshold, when there is a crossing.
    pub fn crossing(&self) -> Option<&Threshold> {
        match self {
            ThresholdOutcome::Crossing(threshold) => Some(threshold),
            _ => None,
        }
    }
}

impl ThresholdSearch {
    fn validate(&self) -> Result<(), StabilityError> {
        let valid = self.zeta_min > 0.0
            && self.zeta_max > self.zeta_min
            && self.zeta_max.is_finite()
            && self.grid_ratio > 1.0
            && self.grid_ratio.is_finite()
            && self.tolerance > 0.0;
        if valid {
            Ok(())
        } else {
            Err(StabilityError::InvalidParameter(format!(
                "threshold search: need 0 < zeta_min < zeta_max, grid_ratio > 1, tolerance > 0 \
                 (got {self:?})"
            )))
        }
    }

    /// The smallest ζ in `[zeta_min, zeta_max]` at which `motion` becomes unstable.
    pub fn run<M: TransferModel>(
        &self,
        motion: &PeriodicMotion<M>,
    ) -> Result<ThresholdOutcome, StabilityError> {
        self.run_on(|zeta| motion.spectrum(zeta))
    }

    /// The same search on any ζ ↦ spectrum map (sorted by decreasing modulus).
    pub fn run_on(
        &self,
        mut spectrum_at: impl FnMut(f64) -> Result<Vec<Eigenvalue>, StabilityError>,
    ) -> Result<ThresholdOutcome, StabilityError> {
        self.validate()?;
        let mut evaluations = 0;
        let mut excess = |zeta: f64| -> Result<f64, StabilityError> {
            evaluations += 1;
            let radius = spectrum_at(zeta)?
                .first()
                .map_or(0.0, |eigenvalue| eigenvalue.modulus);
            Ok(radius - 1.0 - UNIT_CIRCLE_SLACK)
        };

        // Bracket: walk the geometric grid until the spectral radius exceeds 1.
        let mut stable_zeta = self.zeta_min;
        let mut stable_excess = excess(stable_zeta)?;
        if stable_excess > 0.0 {
            return Ok(ThresholdOutcome::UnstableFrom {
                zeta_min: self.zeta_min,
                spectrum: spectrum_at(self.zeta_min)?,
            });
        }
        let (mut unstable_zeta, mut unstable_excess) = loop {
            if stable_zeta >= self.zeta_max {
                return Ok(ThresholdOutcome::StableUpTo {
                    zeta_max: self.zeta_max,
                });
            }
            let zeta = (stable_zeta * self.grid_ratio).min(self.zeta_max);
            let value = excess(zeta)?;
            if value > 0.0 {
                break (zeta, value);
            }
            stable_zeta = zeta;
            stable_excess = value;
        };

        // Refine: Illinois regula falsi; bisect whenever the bracket fails to halve in two steps.
        let mut width_two_steps_ago = f64::INFINITY;
        let mut width_one_step_ago = unstable_zeta - stable_zeta;
        // Which end the previous trial replaced (true: the unstable end). When the same end is
        // replaced twice running, the Illinois rule halves the value kept at the other end.
        let mut last_replaced_unstable: Option<bool> = None;
        while unstable_zeta - stable_zeta > self.tolerance {
            let width = unstable_zeta - stable_zeta;
            let zeta = if width > 0.5 * width_two_steps_ago {
                0.5 * (stable_zeta + unstable_zeta)
            } else {
                let secant = stable_zeta
                    - stable_excess * (unstable_zeta - stable_zeta)
                        / (unstable_excess - stable_excess);
                // Keep the trial strictly inside the bracket.
                secant.clamp(
                    stable_zeta + 0.01 * width.min(self.tolerance),
                    unstable_zeta - 0.01 * width.min(self.tolerance),
                )
            };
            width_two_steps_ago = width_one_step_ago;
            width_one_step_ago = width;
            let value = excess(zeta)?;
            if value > 0.0 {
                unstable_zeta = zeta;
                unstable_excess = value;
                if last_replaced_unstable == Some(true) {
                    stable_excess *= 0.5;
                }
                last_replaced_unstable = Some(true);
            } else {
                stable_zeta = zeta;
                stable_excess = value;
                if last_replaced_unstable == Some(false) {
                    unstable_excess *= 0.5;
                }
                last_replaced_unstable = Some(false);
            }
        }
        let zeta = 0.5 * (stable_zeta + unstable_zeta);
        let spectrum = spectrum_at(zeta)?;
        let critical = spectrum[0];
        Ok(ThresholdOutcome::Crossing(Threshold {
            zeta,
            critical,
            spectrum,
            evaluations: evaluations + 1,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn single(modulus: f64) -> Result<Vec<Eigenvalue>, StabilityError> {
        Ok(vec![Eigenvalue::from_complex(modulus, 0.0)])
    }

    #[test]
    fn finds_a_linear_crossing_to_tolerance() {
        let search = ThresholdSearch::default();
        let outcome = search.run_on(|zeta| single(0.9 + 5.0 * zeta)).unwrap();
        let threshold = outcome.crossing().unwrap();
        assert!((threshold.zeta - 0.02).abs() < 1e-10, "{}", threshold.zeta);
        assert!(threshold.evaluations < 80, "{}", threshold.evaluations);
    }

    #[test]
    fn finds_the_first_of_two_crossings_through_a_kink() {
        // ρ = max of two branches; the first crossing is at ζ = 0.3 on the steep branch.
        let search = ThresholdSearch::default();
        let outcome = search
            .run_on(|zeta| single((0.99 + 0.001 * zeta).max(0.4 + 2.0 * zeta)))
            .unwrap();
        assert!((outcome.crossing().unwrap().zeta - 0.3).abs() < 1e-10);
    }

    #[test]
    fn reports_stable_and_unstable_ranges() {
        let search = ThresholdSearch::default();
        assert_eq!(
            search.run_on(|_| single(0.5)).unwrap(),
            ThresholdOutcome::StableUpTo { zeta_max: 1e3 }
        );
        assert!(matches!(
            search.run_on(|_| single(1.5)).unwrap(),
            ThresholdOutcome::UnstableFrom { .. }
        ));
        let bad = ThresholdSearch {
            grid_ratio: 1.0,
            ..ThresholdSearch::default()
        };
        assert!(bad.run_on(|_| single(0.5)).is_err());
    }
}
