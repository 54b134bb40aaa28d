//! The compact state vector of seed 001, section 3.1, eq. 21–22: the history of outgoing waves.
//!
//! The state is `[L_K, …, L₂, L₁, R₁, R₂, …, R_K']`, where `L_j` (`R_j`) is the perturbation
//! wave that left the bow towards the left (right) j steps ago. One step:
//!
//! - the incoming waves are discrete convolutions of that history with the two reflection
//!   functions, `i_L = Σ_j ρ_L(j) L_j` and `i_R = Σ_j ρ_R(j) R_j` (ρ carries its sign: Raman's
//!   termination is a single tap `−λ` at the round-trip delay);
//! - the bow scatters them exactly as in Fig. 3: `L₁ ← r i_L + (1 + r) i_R`,
//!   `R₁ ← (1 + r) i_L + r i_R`, with `r = ζ` slipping and `r = −γ` sticking;
//! - every other entry moves one place outwards (two delay lines).
//!
//! The time step is the one in which a wave crosses two space-time segments, so for Raman's model
//! with the bow at β = p/(p + q) the delays are p and q steps, the state has p + q entries and the
//! Helmholtz motion slips for p of its p + q steps. The three-tap rounded-corner test case
//! `[σ, λ, σ]` of eq. 22 puts its taps at delays p − 1, p, p + 1 (and q − 1, q, q + 1).

use super::{StabilityError, TransferModel};

/// A discrete reflection function: the tap at delay `first_delay + i` is `taps[i]` (sign
/// included). Delays count compact time steps and start at 1: a wave cannot return in the step
/// it leaves.
#[derive(Debug, Clone, PartialEq)]
pub struct ReflectionFunction {
    first_delay: usize,
    taps: Vec<f64>,
}

impl ReflectionFunction {
    /// Taps `taps[i]` at delays `first_delay + i`; `first_delay ≥ 1`, at least one tap, all finite.
    pub fn new(first_delay: usize, taps: Vec<f64>) -> Result<Self, StabilityError> {
        if first_delay == 0 {
            return Err(StabilityError::InvalidParameter(
                "reflection function: the first tap's delay must be at least 1 step".into(),
            ));
        }
        if taps.is_empty() || taps.iter().any(|tap| !tap.is_finite()) {
            return Err(StabilityError::InvalidParameter(
                "reflection function: needs at least one tap, all finite".into(),
            ));
        }
        Ok(Self { first_delay, taps })
    }

    /// Raman's termination: the single tap `−λ` at the round-trip delay.
    pub fn raman(delay: usize, lambda: f64) -> Result<Self, StabilityError> {
        Self::new(delay, vec![-lambda])
    }

    /// The three-tap rounded corner of eq. 22: `−[σ, λ, σ]` centred on `delay` (≥ 2).
    pub fn three_tap(delay: usize, lambda: f64, sigma: f64) -> Result<Self, StabilityError> {
        if delay < 2 {
            return Err(StabilityError::InvalidParameter(format!(
                "three-tap reflection function: the centre delay {delay} must be at least 2"
            )));
        }
        Self::new(delay - 1, vec![-sigma, -lambda, -sigma])
    }

    /// The longest delay, i.e. how much history the state must hold.
    pub fn max_delay(&self) -> usize {
        self.first_delay + self.taps.len() - 1
    }

    /// The tap values (sign included), starting at [`Self::first_delay`].
    pub fn taps(&self) -> &[f64] {
        &self.taps
    }

    /// Delay of the first tap, in compact steps.
    pub fn first_delay(&self) -> usize {
        self.first_delay
    }

    /// Σ of the taps: −1 for a lossless termination, −λ in Raman's model.
    pub fn area(&self) -> f64 {
        self.taps.iter().sum()
    }
}

/// The compact formulation with one reflection function on each side of the bow.
#[derive(Debug, Clone, PartialEq)]
pub struct CompactModel {
    /// Reflection function of the left side (the p side, bow to bridge and back).
    pub left: ReflectionFunction,
    /// Reflection function of the right side (the q side).
    pub right: ReflectionFunction,
}

impl CompactModel {
    /// Any pair of discrete reflection functions.
    pub fn new(left: ReflectionFunction, right: ReflectionFunction) -> Self {
        Self { left, right }
    }

    /// Raman's model, eq. 21: delays p and q, termination reflection −λ at both ends.
    pub fn raman(p: usize, q: usize, lambda: f64) -> Result<Self, StabilityError> {
        check_lambda(lambda)?;
        if p == 0 || q == 0 {
            return Err(StabilityError::InvalidParameter(format!(
                "p and q: both must be at least 1 (got p = {p}, q = {q})"
            )));
        }
        Ok(Self::new(
            ReflectionFunction::raman(p, lambda)?,
            ReflectionFunction::raman(q, lambda)?,
        ))
    }

    /// The rounded-corner test case of eq. 22: both sides `−[σ, λ, σ]`, centred on p and q.
    pub fn three_tap(p: usize, q: usize, lambda: f64, sigma: f64) -> Result<Self, StabilityError> {
        check_lambda(lambda)?;
        if !(0.0..=1.0).contains(&sigma) {
            return Err(StabilityError::InvalidParameter(format!(
                "sigma: {sigma} is out of range, expected 0 <= sigma <= 1"
            )));
        }
        Ok(Self::new(
            ReflectionFunction::three_tap(p, lambda, sigma)?,
            ReflectionFunction::three_tap(q, lambda, sigma)?,
        ))
    }

    fn left_len(&self) -> usize {
        self.left.max_delay()
    }

    /// State index of `L_j` (j ≥ 1): the left history is stored oldest first.
    fn left_index(&self, j: usize) -> usize {
        self.left_len() - j
    }

    /// State index of `R_j` (j ≥ 1).
    fn right_index(&self, j: usize) -> usize {
        self.left_len() + j - 1
    }

    /// The incoming waves as `(state index, coefficient)` pairs for each side.
    fn incoming_taps<'a>(
        &'a self,
        function: &'a ReflectionFunction,
        index: impl Fn(usize) -> usize + 'a,
    ) -> impl Iterator<Item = (usize, f64)> + 'a {
        function
            .taps
            .iter()
            .enumerate()
            .map(move |(offset, tap)| (index(function.first_delay + offset), *tap))
    }
}

fn check_lambda(lambda: f64) -> Result<(), StabilityError> {
    if lambda > 0.0 && lambda <= 1.0 {
        Ok(())
    } else {
        Err(StabilityError::InvalidParameter(format!(
            "lambda: {lambda} is out of range, expected 0 < lambda <= 1"
        )))
    }
}

impl TransferModel for CompactModel {
    fn state_len(&self) -> usize {
        self.left.max_delay() + self.right.max_delay()
    }

    fn apply_step(&self, bow_reflection: f64, rows: &mut [f64], scratch: &mut [f64]) {
        let columns = self.state_len();
        let row = |index: usize| index * columns..(index + 1) * columns;
        let transmission = 1.0 + bow_reflection;
        // Incoming waves: convolution of the stored history with each reflection function,
        // accumulated into the rows that will become L₁ and R₁.
        let (left_new, right_new) = (self.left_index(1), self.right_index(1));
        scratch[row(left_new)].fill(0.0);
        scratch[row(right_new)].fill(0.0);
        for (index, tap) in self.incoming_taps(&self.left, |j| self.left_index(j)) {
            for column in 0..columns {
                let incoming = tap * rows[index * columns + column];
                scratch[left_new * columns + column] += bow_reflection * incoming;
                scratch[right_new * columns + column] += transmission * incoming;
            }
        }
        for (index, tap) in self.incoming_taps(&self.right, |j| self.right_index(j)) {
            for column in 0..columns {
                let incoming = tap * rows[index * columns + column];
                scratch[left_new * columns + column] += transmission * incoming;
                scratch[right_new * columns + column] += bow_reflection * incoming;
            }
        }
        // Delay lines: L_{j+1} ← L_j, R_{j+1} ← R_j (read from the old state, never from
        // `scratch`, so the order of the copies does not matter).
        for j in 1..self.left.max_delay() {
            let (to, from) = (self.left_index(j + 1), self.left_index(j));
            scratch[row(to)].copy_from_slice(&rows[row(from)]);
        }
        for j in 1..self.right.max_delay() {
            let (to, from) = (self.right_index(j + 1), self.right_index(j));
            scratch[row(to)].copy_from_slice(&rows[row(from)]);
        }
        rows.copy_from_slice(scratch);
    }

    fn step_matrix(&self, bow_reflection: f64) -> faer::Mat<f64> {
        let size = self.state_len();
        let transmission = 1.0 + bow_reflection;
        let mut matrix = faer::Mat::<f64>::zeros(size, size);
        let (left_new, right_new) = (self.left_index(1), self.right_index(1));
        for (index, tap) in self.incoming_taps(&self.left, |j| self.left_index(j)) {
            matrix[(left_new, index)] += bow_reflection * tap;
            matrix[(right_new, index)] += transmission * tap;
        }
        for (index, tap) in self.incoming_taps(&self.right, |j| self.right_index(j)) {
            matrix[(left_new, index)] += transmission * tap;
            matrix[(right_new, index)] += bow_reflection * tap;
        }
        for j in 1..self.left.max_delay() {
            matrix[(self.left_index(j + 1), self.left_index(j))] = 1.0;
        }
        for j in 1..self.right.max_delay() {
            matrix[(self.right_index(j + 1), self.right_index(j))] = 1.0;
        }
        matrix
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_matrix_eq(matrix: &faer::Mat<f64>, printed: &[Vec<f64>]) {
        assert_eq!(matrix.nrows(), printed.len());
        for (row, printed_row) in printed.iter().enumerate() {
            for (column, value) in printed_row.iter().enumerate() {
                assert!(
                    (matrix[(row, column)] - value).abs() < 1e-15,
                    "entry ({row}, {column}): {} vs {value}",
                    matrix[(row, column)]
                );
            }
        }
    }

    /// Eq. 21 as printed: p = 2, q = 3, state `[L₂, L₁, R₁, R₂, R₃]`.
    #[test]
    fn raman_step_matrix_is_equation_21() {
        let (zeta, lambda) = (0.01, 0.99);
        let model = CompactModel::raman(2, 3, lambda).unwrap();
        let t = 1.0 + zeta;
        let printed = vec![
            vec![0.0, 1.0, 0.0, 0.0, 0.0],
            vec![-lambda * zeta, 0.0, 0.0, 0.0, -lambda * t],
            vec![-lambda * t, 0.0, 0.0, 0.0, -lambda * zeta],
            vec![0.0, 0.0, 1.0, 0.0, 0.0],
            vec![0.0, 0.0, 0.0, 1.0, 0.0],
        ];
        assert_matrix_eq(&model.step_matrix(zeta), &printed);
    }

    /// Eq. 22 as printed: p = 2, q = 3, taps `[σ, λ, σ]`, state `[L₃, L₂, L₁, R₁, …, R₄]`.
    #[test]
    fn three_tap_step_matrix_is_equation_22() {
        let (zeta, lambda, sigma) = (0.01, 0.9, 0.05);
        let model = CompactModel::three_tap(2, 3, lambda, sigma).unwrap();
        let t = 1.0 + zeta;
        let printed = vec![
            vec![0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            vec![
                -sigma * zeta,
                -lambda * zeta,
                -sigma * zeta,
                0.0,
                -sigma * t,
                -lambda * t,
                -sigma * t,
            ],
            vec![
                -sigma * t,
                -lambda * t,
                -sigma * t,
                0.0,
                -sigma * zeta,
                -lambda * zeta,
                -sigma * zeta,
            ],
            vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            vec![0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        ];
        assert_matrix_eq(&model.step_matrix(zeta), &printed);
    }

    #[test]
    fn fast_product_matches_dense_reference_for_arbitrary_taps() {
        let model = CompactModel::new(
            ReflectionFunction::new(3, vec![-0.1, -0.6, -0.2, -0.05]).unwrap(),
            ReflectionFunction::new(7, vec![-0.3, -0.5, -0.15]).unwrap(),
        );
        let reflections: Vec<f64> = (0..13)
            .map(|step| if step % 4 == 0 { 0.02 } else { -0.7 })
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
    fn invalid_reflection_functions_are_named() {
        assert!(ReflectionFunction::new(0, vec![-1.0]).is_err());
        assert!(ReflectionFunction::three_tap(1, 0.9, 0.05)
            .unwrap_err()
            .to_string()
            .contains("at least 2"));
        assert!(CompactModel::three_tap(6, 16, 0.9, 1.5)
            .unwrap_err()
            .to_string()
            .contains("sigma"));
        assert!(CompactModel::raman(0, 3, 0.9).is_err());
    }
}
