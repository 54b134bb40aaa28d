//! The space-time state vector of seed 001, section 2.3, eq. 14.
//!
//! The string is cut into p + q segments of one time step's travel; the bow sits between segment
//! p and segment p + 1, a fraction β = p/(p + q) from one end. The state is
//! `[u₁, d₁, u₂, d₂, …, u_{p+q}, d_{p+q}]`: amplitudes of the waves passing "up" (towards segment
//! 1) and "down" (towards segment p + q) through each segment. One step:
//!
//! - `u_k ← u_{k+1}` and `d_k ← d_{k−1}` (travel by one segment);
//! - `d₁ ← −λ u₁` and `u_{p+q} ← −λ d_{p+q}` (the terminations, Fig. 3d);
//! - at the bow, `u_p ← r d_p + (1 + r) u_{p+1}` and `d_{p+1} ← (1 + r) d_p + r u_{p+1}`
//!   with `r = ζ` slipping and `r = −γ` sticking (Fig. 3a–c).
//!
//! For p = 2, q = 3 this is exactly the 10 × 10 matrix printed as eq. 14.

use super::{StabilityError, TransferModel};

/// Raman's model in the space-time formulation: equal termination reflection `−λ` at both ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpaceTimeModel {
    /// Segments between the bow and the near end (the bow is at β = p/(p + q)).
    pub p: usize,
    /// Segments between the bow and the far end.
    pub q: usize,
    /// Magnitude of the termination reflection, λ = 1 − ε (the reflection is −λ), 0 < λ ≤ 1.
    pub lambda: f64,
}

impl SpaceTimeModel {
    /// Checks `p ≥ 1`, `q ≥ 1` and `0 < λ ≤ 1`.
    pub fn new(p: usize, q: usize, lambda: f64) -> Result<Self, StabilityError> {
        if p == 0 || q == 0 {
            return Err(StabilityError::InvalidParameter(format!(
                "p and q: both must be at least 1 (got p = {p}, q = {q})"
            )));
        }
        if !(lambda > 0.0 && lambda <= 1.0) {
            return Err(StabilityError::InvalidParameter(format!(
                "lambda: {lambda} is out of range, expected 0 < lambda <= 1"
            )));
        }
        Ok(Self { p, q, lambda })
    }

    fn segments(&self) -> usize {
        self.p + self.q
    }

    /// State index of the up-going wave in segment `k` (1-based, as in the seed).
    fn up(k: usize) -> usize {
        2 * (k - 1)
    }

    /// State index of the down-going wave in segment `k` (1-based).
    fn down(k: usize) -> usize {
        2 * (k - 1) + 1
    }

    /// The sources of one step as `(target, [(source, coefficient); ≤ 2])`, shared by the fast
    /// and the reference path so that both read the physics from one place.
    fn for_each_update(&self, bow_reflection: f64, mut update: impl FnMut(usize, &[(usize, f64)])) {
        let segments = self.segments();
        let p = self.p;
        let transmission = 1.0 + bow_reflection;
        for k in 1..=segments {
            // Up-going wave arriving in segment k.
            if k == segments {
                update(Self::up(k), &[(Self::down(k), -self.lambda)]);
            } else if k == p {
                update(
                    Self::up(k),
                    &[
                        (Self::down(p), bow_reflection),
                        (Self::up(p + 1), transmission),
                    ],
                );
            } else {
                update(Self::up(k), &[(Self::up(k + 1), 1.0)]);
            }
            // Down-going wave arriving in segment k.
            if k == 1 {
                update(Self::down(k), &[(Self::up(1), -self.lambda)]);
            } else if k == p + 1 {
                update(
                    Self::down(k),
                    &[
                        (Self::down(p), transmission),
                        (Self::up(p + 1), bow_reflection),
                    ],
                );
            } else {
                update(Self::down(k), &[(Self::down(k - 1), 1.0)]);
            }
        }
    }
}

impl TransferModel for SpaceTimeModel {
    fn state_len(&self) -> usize {
        2 * self.segments()
    }

    fn apply_step(&self, bow_reflection: f64, rows: &mut [f64], scratch: &mut [f64]) {
        let columns = self.state_len();
        self.for_each_update(bow_reflection, |target, sources| {
            let target_row = &mut scratch[target * columns..(target + 1) * columns];
            target_row.fill(0.0);
            for &(source, coefficient) in sources {
                let source_row = &rows[source * columns..(source + 1) * columns];
                for (out, value) in target_row.iter_mut().zip(source_row) {
                    *out += coefficient * value;
                }
            }
        });
        rows.copy_from_slice(scratch);
    }

    fn step_matrix(&self, bow_reflection: f64) -> faer::Mat<f64> {
        let size = self.state_len();
        let mut matrix = faer::Mat::<f64>::zeros(size, size);
        self.for_each_update(bow_reflection, |target, sources| {
            for &(source, coefficient) in sources {
                matrix[(target, source)] += coefficient;
            }
        });
        matrix
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 14 as printed, for p = 2, q = 3, with ζ and λ symbolic values plugged in.
    #[test]
    fn step_matrix_is_equation_14() {
        let (zeta, lambda) = (0.01, 0.99);
        let model = SpaceTimeModel::new(2, 3, lambda).unwrap();
        let matrix = model.step_matrix(zeta);
        let t = 1.0 + zeta;
        #[rustfmt::skip]
        let printed: [[f64; 10]; 10] = [
            [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [-lambda, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, zeta, t, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, t, zeta, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -lambda],
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        ];
        for (row, printed_row) in printed.iter().enumerate() {
            for (column, value) in printed_row.iter().enumerate() {
                assert_eq!(matrix[(row, column)], *value, "entry ({row}, {column})");
            }
        }
    }

    #[test]
    fn fast_product_matches_dense_reference() {
        let model = SpaceTimeModel::new(3, 7, 0.97).unwrap();
        let reflections: Vec<f64> = (0..20)
            .map(|step| if step < 6 { 0.013 } else { -0.8 })
            .collect();
        let fast = model.transfer_matrix(&reflections);
        let reference = model.transfer_matrix_reference(&reflections);
        for row in 0..model.state_len() {
            for column in 0..model.state_len() {
                assert!((fast[(row, column)] - reference[(row, column)]).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn invalid_parameters_are_named() {
        assert!(SpaceTimeModel::new(0, 3, 0.9)
            .unwrap_err()
            .to_string()
            .contains("p and q"));
        assert!(SpaceTimeModel::new(2, 3, 1.5)
            .unwrap_err()
            .to_string()
            .contains("lambda"));
    }
}
