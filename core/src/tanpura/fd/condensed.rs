//! Newton's method reduced to the contact region through a precomputed Schur complement.
//!
//! The step equation of the tanpura (seed 000, eq. 22) is `A s + c − f(s_C) = 0`, where the
//! contact forces `f = Σ I* f̃(I s)` live only on the nodes `C` that the bridge and thread
//! stencils reach (about 14 of the 199 unknowns) and `A` is constant. Eliminating the other
//! unknowns exactly: with the contact-free step `s_lin = −A⁻¹ c`, every solution satisfies
//! `s = s_lin + A⁻¹ f`, so on `C`
//!
//! ```text
//! R(s_C) = S (s_C − s_lin,C) − f_C(s_C) = 0,     S = [(A⁻¹)_CC]⁻¹  (the Schur complement of A)
//! ```
//!
//! with the Jacobian `S + (Σ I* C I)_CC`, symmetric positive definite like the full one. Newton
//! on this reduced system produces the same iterates as Newton on the whole string (the
//! eliminated unknowns are linear), at O(|C|³) per iteration instead of O(N·w²); one banded solve
//! `A s = −c + f` recovers the whole step afterwards. Energy stability is untouched: the accepted
//! `s` solves the same discrete equations (to the Newton tolerance), so the discrete energy
//! balance of the full scheme holds as before. `S` depends only on `A`, so it is recomputed
//! only when the string's parameters change.

use crate::banded::{BandedLdlt, NotPositiveDefinite};
use crate::dense::DenseCholesky;

/// The contact block `C = first_node..first_node + size` and its Schur complement.
#[derive(Debug, Clone)]
pub struct ContactCondensation {
    first_node: usize,
    size: usize,
    /// S = [(A⁻¹)_CC]⁻¹, row-major.
    schur: Vec<f64>,
    /// S + (Σ I* C I)_CC for the current iterate.
    jacobian: Vec<f64>,
    factor: DenseCholesky,
    /// s_lin on C.
    predictor: Vec<f64>,
    /// G = A⁻¹ restricted to the columns of C, row-major (N − 1) × |C|: the response of the
    /// whole string to a unit force on each contact node.
    response: Vec<f64>,
    /// The last accepted contact correction s_C − s_lin,C, the next step's initial guess.
    previous_correction: Vec<f64>,
    /// The reduced residual, then the Newton update.
    update: Vec<f64>,
}

impl ContactCondensation {
    /// Room for the nodes `first_node..=last_node` (all interior) of a string with
    /// `unknowns` = N − 1 free nodes. Allocates.
    pub fn new(first_node: usize, last_node: usize, unknowns: usize) -> Self {
        let size = last_node + 1 - first_node;
        Self {
            first_node,
            size,
            schur: vec![0.0; size * size],
            jacobian: vec![0.0; size * size],
            factor: DenseCholesky::with_capacity(size),
            predictor: vec![0.0; size],
            response: vec![0.0; unknowns * size],
            previous_correction: vec![0.0; size],
            update: vec![0.0; size],
        }
    }

    pub fn first_node(&self) -> usize {
        self.first_node
    }

    pub fn size(&self) -> usize {
        self.size
    }

    /// Recomputes `S` from the factorised step matrix `A` (N − 1 unknowns; row i ↔ node i + 1).
    /// `column` is scratch of length ≥ N − 1. Allocation-free.
    pub fn prepare(
        &mut self,
        step_factor: &BandedLdlt,
        column: &mut [f64],
    ) -> Result<(), NotPositiveDefinite> {
        let size = self.size;
        let offset = self.first_node - 1;
        // G = (A⁻¹)_CC, column by column, stored in `jacobian` for the moment.
        let unknowns = self.response.len() / size;
        for j in 0..size {
            column.fill(0.0);
            column[offset + j] = 1.0;
            step_factor.solve_in_place(column);
            for i in 0..size {
                self.jacobian[i * size + j] = column[offset + i];
            }
            for (row, value) in column[..unknowns].iter().enumerate() {
                self.response[row * size + j] = *value;
            }
        }
        self.previous_correction.fill(0.0);
        // S = G⁻¹, column by column.
        self.factor.factorise(&self.jacobian, size)?;
        for j in 0..size {
            self.update.fill(0.0);
            self.update[j] = 1.0;
            self.factor.solve_in_place(&mut self.update);
            for i in 0..size {
                self.schur[i * size + j] = self.update[i];
            }
        }
        Ok(())
    }

    /// Records `s_lin` on C from the full-node predictor step.
    pub fn set_predictor(&mut self, step: &[f64]) {
        self.predictor
            .copy_from_slice(&step[self.first_node..self.first_node + self.size]);
    }

    /// Starts Newton from `s_lin,C` plus the previous step's contact correction: contact forces
    /// vary smoothly from step to step, so this guess saves about one iteration.
    pub fn apply_initial_guess(&self, step: &mut [f64]) {
        for (i, correction) in self.previous_correction.iter().enumerate() {
            step[self.first_node + i] = self.predictor[i] + correction;
        }
    }

    /// Forgets the contact correction (a step without contact, or a new excitation).
    pub fn clear_correction(&mut self) {
        self.previous_correction.fill(0.0);
    }

    /// Recovers the whole step from the predictor and the contact forces on C:
    /// `s = s_lin + G f_C` (full-node vectors; `step` holds `s_lin` outside C on entry).
    pub fn recover_step(&mut self, step: &mut [f64], contact: &[f64]) {
        let size = self.size;
        let first = self.first_node;
        step[first..first + size].copy_from_slice(&self.predictor);
        let forces = &contact[first..first + size];
        for (row, response) in self.response.chunks_exact(size).enumerate() {
            let correction: f64 = response.iter().zip(forces).map(|(g, f)| g * f).sum();
            step[row + 1] += correction;
        }
        for i in 0..size {
            self.previous_correction[i] = step[first + i] - self.predictor[i];
        }
    }

    /// The largest |s_lin| on C, m.
    pub fn predictor_max_abs(&self) -> f64 {
        self.predictor.iter().fold(0.0, |a, s| a.max(s.abs()))
    }

    /// The jacobian buffer, reset to S, for barriers to add their `I* C I` block into.
    pub fn jacobian_reset_to_schur(&mut self) -> &mut [f64] {
        self.jacobian.copy_from_slice(&self.schur);
        &mut self.jacobian
    }

    /// One Newton update on C: with the contact forces `contact` (full-node, I* f̃) already
    /// evaluated at `step` and the Jacobian assembled, solves and applies the update to `step`
    /// on C. Returns ‖δ‖∞, or None when the Jacobian is not positive definite.
    pub fn update(&mut self, step: &mut [f64], contact: &[f64]) -> Option<f64> {
        let size = self.size;
        let first = self.first_node;
        for i in 0..size {
            let mut value = -contact[first + i];
            for j in 0..size {
                value += self.schur[i * size + j] * (step[first + j] - self.predictor[j]);
            }
            self.update[i] = value;
        }
        self.factor.factorise(&self.jacobian, size).ok()?;
        self.factor.solve_in_place(&mut self.update);
        let mut largest = 0.0f64;
        for i in 0..size {
            step[first + i] -= self.update[i];
            largest = largest.max(self.update[i].abs());
        }
        Some(largest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::banded::SymmetricBanded;

    #[test]
    fn schur_complement_reproduces_the_full_solve() {
        // A pentadiagonal SPD matrix on 12 unknowns (nodes 1..=12), C = nodes 4..=7.
        let unknowns = 12;
        let mut a = SymmetricBanded::zeros(unknowns, 2);
        for row in 0..unknowns {
            a.set(row, row, 6.0 + 0.1 * row as f64);
            if row >= 1 {
                a.set(row, row - 1, -2.0);
            }
            if row >= 2 {
                a.set(row, row - 2, 0.5);
            }
        }
        let mut factor = BandedLdlt::with_shape(unknowns, 2);
        factor.factorise(&a).unwrap();
        let mut condensation = ContactCondensation::new(4, 7, unknowns);
        let mut scratch = vec![0.0; unknowns];
        condensation.prepare(&factor, &mut scratch).unwrap();
        // For a force f on C: s = s_lin + A⁻¹ f, and S (s_C − s_lin,C) must equal f_C.
        let rhs: Vec<f64> = (0..unknowns).map(|i| (i as f64).sin()).collect();
        let mut s_lin = rhs.clone();
        factor.solve_in_place(&mut s_lin);
        let force = [0.3, -1.0, 2.0, 0.7];
        let mut with_force = rhs.clone();
        for (k, f) in force.iter().enumerate() {
            with_force[3 + k] += f;
        }
        factor.solve_in_place(&mut with_force);
        for i in 0..4 {
            let mut value = 0.0;
            for j in 0..4 {
                value += condensation.schur[i * 4 + j] * (with_force[3 + j] - s_lin[3 + j]);
            }
            assert!((value - force[i]).abs() < 1e-12, "{value} vs {}", force[i]);
        }
        // And the recovery s = s_lin + G f_C gives the full solve everywhere.
        let mut step = vec![0.0; unknowns + 2];
        step[1..=unknowns].copy_from_slice(&s_lin);
        condensation.set_predictor(&step);
        let mut contact = vec![0.0; unknowns + 2];
        for (k, f) in force.iter().enumerate() {
            contact[4 + k] = *f;
        }
        condensation.recover_step(&mut step, &contact);
        for i in 0..unknowns {
            assert!((step[i + 1] - with_force[i]).abs() < 1e-12);
        }
    }
}
