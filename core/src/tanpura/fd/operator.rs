//! The stiff, lossy string: its finite-difference operator, step matrix, energy and nut force.
//!
//! Source: seed 000, eq. 5, 7–9, 13–16, restated in `shared/notes/tanpura-model.md`.
//!
//! Continuous model: `ρA y_tt = (T y_xx − EI y_xxxx)(1 + η ∂_t) − ρA γ y_t + contact forces`,
//! with `y(0) = y_TB` (the lowered left support at the tuning bead), `y(L) = 0` (the nut) and
//! `y_xx = 0` at both ends (simply supported).
//!
//! Grid `x_m = mΔx`, `m = 0..=N`; nodes 0 and N are fixed, so the unknowns are `m = 1..N−1`.
//! Full-node vectors (length N + 1) carry the boundary values, so the lowered support enters
//! every stencil without a separate constant vector. With the curvature `c_m = δxx y_m` and
//! `c_0 = c_N = 0` (the discrete `y_xx = 0`), the restoring force density is
//!
//! ```text
//! g_m = −T c_m + EI (c_{m−1} − 2c_m + c_{m+1}) / Δx²       (= (K y − b)_m)
//! ```
//!
//! which is exactly `(1/Δx) ∂V/∂y_m` of the discrete potential
//! `V = Δx Σ_{m=0}^{N−1} T/2 (δx+ y_m)² + Δx Σ_{m=1}^{N−1} EI/2 c_m²`. That gradient identity
//! is what makes the mid-point scheme's energy balance exact. `K` is the constant symmetric
//! positive definite pentadiagonal Hessian, `D = (Δt²/4ρA) K`, and the step matrix of eq. 15 is
//! `A = (1 + γΔt/2) I + (1 + 2η/Δt) D`.

use crate::banded::SymmetricBanded;
use crate::tanpura::string::StringParameters;

/// The discretised string operator on a fixed grid and time step.
#[derive(Debug, Clone)]
pub struct StringOperator {
    parameters: StringParameters,
    intervals: usize,
    spacing_m: f64,
    time_step_s: f64,
    /// K, the Hessian of the discrete potential divided by Δx, on the N − 1 interior nodes.
    stiffness: SymmetricBanded,
}

impl StringOperator {
    /// The operator for `intervals` grid intervals (N ≥ 4) and time step `time_step_s`.
    pub fn new(parameters: StringParameters, intervals: usize, time_step_s: f64) -> Self {
        assert!(intervals >= 4, "a string needs at least 4 grid intervals");
        let mut operator = Self {
            parameters,
            intervals,
            spacing_m: parameters.length_m / intervals as f64,
            time_step_s,
            stiffness: SymmetricBanded::zeros(intervals - 1, 2),
        };
        operator.set_parameters(parameters);
        operator
    }

    /// Changes the physical constants (same grid and length); allocation-free.
    pub fn set_parameters(&mut self, parameters: StringParameters) {
        debug_assert_eq!(parameters.length_m, self.parameters.length_m);
        self.parameters = parameters;
        let dx2 = self.spacing_m * self.spacing_m;
        let tension_term = parameters.tension_n / dx2;
        let bending_term = parameters.bending_stiffness_n_m2 / (dx2 * dx2);
        let unknowns = self.intervals - 1;
        for row in 0..unknowns {
            // δxx δxx with c_0 = c_N = 0 gives 5 on the first and last diagonal entries, 6 inside.
            let at_end = row == 0 || row == unknowns - 1;
            let bending_diagonal = if at_end { 5.0 } else { 6.0 };
            self.stiffness.set(
                row,
                row,
                2.0 * tension_term + bending_diagonal * bending_term,
            );
            if row >= 1 {
                self.stiffness
                    .set(row, row - 1, -tension_term - 4.0 * bending_term);
            }
            if row >= 2 {
                self.stiffness.set(row, row - 2, bending_term);
            }
        }
    }

    pub fn parameters(&self) -> &StringParameters {
        &self.parameters
    }

    /// N, the number of grid intervals.
    pub fn intervals(&self) -> usize {
        self.intervals
    }

    /// Δx, m.
    pub fn spacing_m(&self) -> f64 {
        self.spacing_m
    }

    /// Δt, s.
    pub fn time_step_s(&self) -> f64 {
        self.time_step_s
    }

    /// Δt²/(4ρA): turns a force density into the scheme's `D`-scaled units.
    pub fn force_scale(&self) -> f64 {
        self.time_step_s * self.time_step_s / (4.0 * self.parameters.linear_density_kg_m)
    }

    /// K on the interior nodes (row i ↔ node i + 1).
    pub fn stiffness_matrix(&self) -> &SymmetricBanded {
        &self.stiffness
    }

    /// Writes the step matrix `A = (1 + γΔt/2) I + (1 + 2η/Δt) D` of eq. 15 into `matrix`.
    pub fn step_matrix_into(&self, matrix: &mut SymmetricBanded) {
        let identity_factor = 1.0 + 0.5 * self.parameters.gamma_per_s * self.time_step_s;
        let operator_factor =
            (1.0 + 2.0 * self.parameters.eta_s / self.time_step_s) * self.force_scale();
        matrix.clear();
        for row in 0..self.intervals - 1 {
            for offset in 0..=2.min(row) {
                let value = operator_factor * self.stiffness.get(row, row - offset);
                matrix.set(row, row - offset, value);
            }
            matrix.add(row, row, identity_factor);
        }
    }

    /// The restoring force density `g = K y − b` (N/m) at the interior nodes of the full-node
    /// vector `displacement` (length N + 1, boundary values included). `output[0]` and
    /// `output[N]` are set to zero.
    pub fn restoring_force(&self, displacement: &[f64], output: &mut [f64]) {
        let n = self.intervals;
        let inverse_dx2 = 1.0 / (self.spacing_m * self.spacing_m);
        let tension = self.parameters.tension_n;
        let bending = self.parameters.bending_stiffness_n_m2 * inverse_dx2;
        let curvature = |m: usize| -> f64 {
            if m == 0 || m == n {
                0.0
            } else {
                (displacement[m + 1] - 2.0 * displacement[m] + displacement[m - 1]) * inverse_dx2
            }
        };
        output[0] = 0.0;
        output[n] = 0.0;
        let mut previous = 0.0;
        let mut current = curvature(1);
        for m in 1..n {
            let next = curvature(m + 1);
            output[m] = -tension * current + bending * (previous - 2.0 * current + next);
            previous = current;
            current = next;
        }
    }

    /// The string's potential energy V (J) of eq. 8–9 for a full-node displacement vector.
    pub fn potential_energy_j(&self, displacement: &[f64]) -> f64 {
        let n = self.intervals;
        let dx = self.spacing_m;
        let mut stretching = 0.0;
        for m in 0..n {
            let slope = (displacement[m + 1] - displacement[m]) / dx;
            stretching += slope * slope;
        }
        let mut bending = 0.0;
        for m in 1..n {
            let curvature =
                (displacement[m + 1] - 2.0 * displacement[m] + displacement[m - 1]) / (dx * dx);
            bending += curvature * curvature;
        }
        0.5 * dx
            * (self.parameters.tension_n * stretching
                + self.parameters.bending_stiffness_n_m2 * bending)
    }

    /// The kinetic energy (J) of the scaled momentum `q = (Δt/2ρA) p` (full-node vector).
    pub fn kinetic_energy_j(&self, scaled_momentum: &[f64]) -> f64 {
        let factor =
            2.0 * self.parameters.linear_density_kg_m / (self.time_step_s * self.time_step_s);
        let sum: f64 = scaled_momentum[1..self.intervals]
            .iter()
            .map(|q| q * q)
            .sum();
        factor * self.spacing_m * sum
    }

    /// Energy dissipated by γ and η over one step `s` (full-node vector, zero at the ends), J:
    /// `Δx [ (η/Δt) sᵀKs + (ρAγ/Δt) sᵀs ]`. `scratch` (length N + 1) receives `K s`.
    pub fn step_loss_j(&self, step: &[f64], scratch: &mut [f64]) -> f64 {
        let p = &self.parameters;
        let mut operator_term = 0.0;
        let mut identity_term = 0.0;
        if p.eta_s != 0.0 {
            self.restoring_force(step, scratch);
            for m in 1..self.intervals {
                operator_term += step[m] * scratch[m];
            }
        }
        for s in &step[1..self.intervals] {
            identity_term += s * s;
        }
        self.spacing_m / self.time_step_s
            * (p.eta_s * operator_term + p.linear_density_kg_m * p.gamma_per_s * identity_term)
    }

    /// The force on the nut (eq. 13), `F_n = EI y_xxx(L) − T y_x(L)`, N, from one-sided
    /// differences at the nut. It equals the discrete reaction `−∂V/∂y_N`, so it is consistent
    /// with the energy of the scheme.
    pub fn nut_force_n(&self, displacement: &[f64]) -> f64 {
        let n = self.intervals;
        let dx = self.spacing_m;
        let last = displacement[n - 1];
        let curvature_before_nut = (displacement[n] - 2.0 * last + displacement[n - 2]) / (dx * dx);
        let slope_at_nut = (displacement[n] - last) / dx;
        let third_derivative_at_nut = (0.0 - curvature_before_nut) / dx;
        self.parameters.bending_stiffness_n_m2 * third_derivative_at_nut
            - self.parameters.tension_n * slope_at_nut
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn operator() -> StringOperator {
        StringOperator::new(StringParameters::SEED, 200, 1.0 / 176_400.0)
    }

    fn wiggly(n: usize, left: f64) -> Vec<f64> {
        let mut y: Vec<f64> = (0..=n)
            .map(|m| 1e-3 * ((m as f64) * 0.37).sin() * ((m as f64) * 0.05).cos())
            .collect();
        y[0] = left;
        y[n] = 0.0;
        y
    }

    #[test]
    fn stencil_force_is_the_matrix_times_y_minus_the_support_vector() {
        let op = operator();
        let n = op.intervals();
        let y = wiggly(n, -2e-3);
        let mut force = vec![0.0; n + 1];
        op.restoring_force(&y, &mut force);
        // The affine part: force at y with interior zeroed is −b.
        let mut support_only = vec![0.0; n + 1];
        support_only[0] = y[0];
        let mut minus_b = vec![0.0; n + 1];
        op.restoring_force(&support_only, &mut minus_b);
        let mut k_y = vec![0.0; n - 1];
        op.stiffness_matrix().multiply(&y[1..n], &mut k_y);
        for m in 1..n {
            let expected = k_y[m - 1] + minus_b[m];
            assert!(
                (force[m] - expected).abs() <= 1e-9 * expected.abs().max(1.0),
                "node {m}: {} vs {expected}",
                force[m]
            );
        }
    }

    #[test]
    fn force_is_the_gradient_of_the_potential() {
        let op = operator();
        let n = op.intervals();
        let y = wiggly(n, -2e-3);
        let mut force = vec![0.0; n + 1];
        op.restoring_force(&y, &mut force);
        for &m in &[1, 2, 57, n - 2, n - 1] {
            let h = 1e-9;
            let mut up = y.clone();
            up[m] += h;
            let mut down = y.clone();
            down[m] -= h;
            let gradient = (op.potential_energy_j(&up) - op.potential_energy_j(&down)) / (2.0 * h);
            let expected = force[m] * op.spacing_m();
            assert!(
                (gradient - expected).abs() <= 1e-5 * expected.abs(),
                "node {m}: {gradient} vs {expected}"
            );
        }
    }

    #[test]
    fn straight_string_from_lowered_support_has_only_tension_energy() {
        let op = operator();
        let n = op.intervals();
        let left = -2e-3;
        let y: Vec<f64> = (0..=n)
            .map(|m| left * (1.0 - m as f64 / n as f64))
            .collect();
        let expected = 0.5 * StringParameters::SEED.tension_n * left * left / 0.668;
        assert!((op.potential_energy_j(&y) - expected).abs() < 1e-12 * expected);
        let mut force = vec![0.0; n + 1];
        op.restoring_force(&y, &mut force);
        assert!(
            force.iter().all(|f| f.abs() < 1e-9),
            "a straight string is in equilibrium"
        );
        // The nut then carries T times the slope.
        let nut = op.nut_force_n(&y);
        let expected_nut = -StringParameters::SEED.tension_n * (-left / 0.668);
        assert!((nut - expected_nut).abs() < 1e-9);
    }

    #[test]
    fn nut_force_is_the_reaction_of_the_potential() {
        let op = operator();
        let n = op.intervals();
        let mut y = wiggly(n, -2e-3);
        let h = 1e-9;
        y[n] = h;
        let up = op.potential_energy_j(&y);
        y[n] = -h;
        let down = op.potential_energy_j(&y);
        y[n] = 0.0;
        let reaction = -(up - down) / (2.0 * h);
        let nut = op.nut_force_n(&y);
        assert!(
            (reaction - nut).abs() < 1e-6 * nut.abs(),
            "{reaction} vs {nut}"
        );
    }
}
