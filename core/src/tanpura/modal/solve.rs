//! The static solves of the modal tiers (`docs/modal-tanpura.md`, section 5).
//!
//! The dynamic step's solve is in `step.rs`; its Newton updates use the LDLᵀ solvers here.
//!
//! **Static problems** (rest state, pressed finger). The equilibrium minimises the convex
//! `Π(r) = |r|²/2 + Σ_i w_i k/2 ⌊g_i − Ψ_i r⌋²`; at the minimum `r = Σ_i F_i Ψ_i`. Newton's step
//! for the current contact set A is the exact minimiser of the quadratic model,
//! `F_A = D (I + D G^s_AA D)⁻¹ D g_A` with `G^s = Ψ Ψᵀ + R` (R the truncated modes' static
//! compliance, zero without the static flexibility, so that `G^s` is then the whole string's
//! `C`) and `D = diag(√(w_i k))`; the points move by `u = Ψ r + R F` and Π gains `½ Fᵀ R F`, the
//! truncated modes' strain energy (Π stays convex in F). A backtracking
//! line search on Π makes it converge from any start, and it ends exactly once the contact set
//! stops changing (the problem is piecewise quadratic).
//!
//! **Linearised fundamental.** The lowest eigenvalue of `(I + Ψ_Aᵀ C Ψ_A) x = ω² diag(1/ω_k²) x`
//! (the modes with a spring at every point in contact at rest: the step's dynamics, which move
//! the string in its kept modes), by inverse iteration; the inverse is applied through the
//! Woodbury identity in O(|A| K).

use super::lanes::{padded_lanes, Kernels};
use super::modes::MODE_CAPACITY;
use super::points::ContactPoints;
use crate::dense::DenseCholesky;
use crate::unroll::{for_each_index, LARGEST_UNROLLED};

/// Solves `A x = b` in place for the SPD `n × n` matrix whose lower triangle is in `matrix`
/// (row-major), by an LDLᵀ factorisation written over it: `L` below the diagonal, `D` on it. No
/// pivoting and no square roots: the tracked solve's matrices have eigenvalues ≥ 1. `scratch`
/// holds `L_jk d_k` for the row being factorised.
pub(super) fn ldl_solve_in_place(matrix: &mut [f64], n: usize, x: &mut [f64], scratch: &mut [f64]) {
    for j in 0..n {
        // w_k = L_jk d_k; d_j = a_jj − Σ_k L_jk w_k.
        let mut diagonal = matrix[j * n + j];
        for k in 0..j {
            let weighted = matrix[j * n + k] * matrix[k * n + k];
            scratch[k] = weighted;
            diagonal -= matrix[j * n + k] * weighted;
        }
        matrix[j * n + j] = diagonal;
        // L_ij = (a_ij − Σ_k L_ik w_k) / d_j for the rows below.
        for i in j + 1..n {
            let row = &matrix[i * n..i * n + j];
            let sum: f64 = row.iter().zip(&scratch[..j]).map(|(l, w)| l * w).sum();
            matrix[i * n + j] = (matrix[i * n + j] - sum) / diagonal;
        }
    }
    ldl_substitute_in_place(matrix, n, x);
}

/// Solves with the factors [`ldl_solve_in_place`] leaves in `factors` (another right-hand side
/// for the same matrix): `L y = b`, `D z = y`, `Lᵀ x = z`, in place.
pub(super) fn ldl_substitute_in_place(factors: &[f64], n: usize, x: &mut [f64]) {
    for i in 0..n {
        let row = &factors[i * n..i * n + i];
        let sum: f64 = row.iter().zip(&x[..i]).map(|(l, v)| l * v).sum();
        x[i] -= sum;
    }
    for i in 0..n {
        x[i] /= factors[i * n + i];
    }
    for i in (0..n).rev() {
        let value = x[i];
        for k in 0..i {
            x[k] -= factors[i * n + k] * value;
        }
    }
}

/// [`ldl_solve_in_place`] on a fixed-size matrix given by its upper triangle (`matrix[b][a]`
/// holds `A_ab`, a ≥ b: row k is column k of the lower triangle), for a contact set of exactly
/// `N` points; the compiler unrolls it.
#[cfg(test)]
pub(super) fn ldl_solve_fixed<const N: usize>(matrix: &mut [[f64; N]; N], x: &mut [f64; N]) {
    ldl_factor_fixed(matrix);
    ldl_substitute_fixed(matrix, x);
}

/// The LDLᵀ factorisation of [`ldl_solve_fixed`], written over its upper triangle: `L` by
/// columns (`matrix[k][i] = L_ik`, i > k), `D` on the diagonal. Each entry takes the products of
/// the row-wise left-looking factorisation, subtracted one by one for k ascending, so the
/// factors are those of the row-wise loops bit for bit; by columns, each column's update runs
/// over whole rows of `N` lanes (the lanes above the column are formed and dropped), which the
/// compiler vectorises where the row-wise sums stay scalar: on AVX2, 30 M of the 73 M
/// instructions the factorisations execute in `tier_cost fine 1 1` are 4-wide register
/// operations (callgrind per instruction, stop 46 in `docs/performance.md`). Every loop is
/// written out at compile time (`crate::unroll`), for `N` up to 16.
#[inline(always)]
// At some indices of the written-out loops a guard is constant; the compiler folds it.
#[allow(clippy::absurd_extreme_comparisons)]
pub(super) fn ldl_factor_fixed<const N: usize>(matrix: &mut [[f64; N]; N]) {
    const { assert!(N <= LARGEST_UNROLLED) };
    let mut rows = *matrix;
    for_each_index!(ascending J => {
        if const { J < N } {
            // Column J less Σ_k L_ik (L_Jk d_k), k ascending; its lane J is d_J.
            let mut column = rows[J];
            for_each_index!(ascending K => {
                if const { K < J } {
                    let row_k = rows[K];
                    let weighted = row_k[J] * row_k[K];
                    for (value, &l) in column.iter_mut().zip(&row_k) {
                        *value -= l * weighted;
                    }
                }
            });
            let diagonal = column[J];
            let inverse = 1.0 / diagonal;
            let row_j = &mut rows[J];
            row_j[J] = diagonal;
            for (target, value) in row_j[J + 1..].iter_mut().zip(&column[J + 1..]) {
                *target = value * inverse;
            }
        }
    });
    *matrix = rows;
}

/// Solves with the factors of [`ldl_factor_fixed`]: `L y = b`, `D z = y`, `Lᵀ x = z`, in place,
/// each entry's products subtracted one by one in the order of the row-wise substitution;
/// unrolled at compile time as the factorisation is.
#[inline(always)]
pub(super) fn ldl_substitute_fixed<const N: usize>(factors: &[[f64; N]; N], x: &mut [f64; N]) {
    const { assert!(N <= LARGEST_UNROLLED) };
    let mut solution = *x;
    for_each_index!(ascending K => {
        if const { K < N } {
            let solved = solution[K];
            let row = &factors[K];
            for (i, (value, &l)) in solution.iter_mut().zip(row).enumerate() {
                *value = if i > K { *value - l * solved } else { *value };
            }
        }
    });
    for (i, value) in solution.iter_mut().enumerate() {
        *value /= factors[i][i];
    }
    for_each_index!(descending K => {
        if const { K < N } {
            let row = &factors[K];
            let mut value = solution[K];
            for i in (K + 1..N).rev() {
                value -= row[i] * solution[i];
            }
            solution[K] = value;
        }
    });
    *x = solution;
}

/// [`ldl_substitute_fixed`] on `R` right sides at once: each right side takes the same
/// operations in the same order as alone (the same bits), but the loops over the rows are
/// written out with the right sides innermost, so their dependency chains (each row waits on
/// the one before it) overlap instead of following each other. The exact finish of a step with
/// crossing points substitutes Newton's update and one direction per crossing point through the
/// same factors (`nodal.rs`, `NodalContact::update_in_lanes`).
#[inline(always)]
// At some indices of the written-out loops a guard is constant; the compiler folds it.
#[allow(clippy::absurd_extreme_comparisons)]
pub(super) fn ldl_substitute_many<const N: usize, const R: usize>(
    factors: &[[f64; N]; N],
    right_sides: &mut [[f64; N]; R],
) {
    const { assert!(N <= LARGEST_UNROLLED && R <= LARGEST_UNROLLED) };
    let mut solutions = *right_sides;
    for_each_index!(ascending K => {
        if const { K < N } {
            let row = &factors[K];
            for_each_index!(ascending SIDE => {
                if const { SIDE < R } {
                    let solution = &mut solutions[SIDE];
                    let solved = solution[K];
                    for (i, (value, &l)) in solution.iter_mut().zip(row).enumerate() {
                        *value = if i > K { *value - l * solved } else { *value };
                    }
                }
            });
        }
    });
    for solution in solutions.iter_mut() {
        for (i, value) in solution.iter_mut().enumerate() {
            *value /= factors[i][i];
        }
    }
    for_each_index!(descending K => {
        if const { K < N } {
            let row = &factors[K];
            for_each_index!(ascending SIDE => {
                if const { SIDE < R } {
                    let solution = &mut solutions[SIDE];
                    let mut value = solution[K];
                    for i in (K + 1..N).rev() {
                        value -= row[i] * solution[i];
                    }
                    solution[K] = value;
                }
            });
        }
    });
    *right_sides = solutions;
}

/// Static equilibrium of the string on a set of points (bridge, thread and maybe finger).
#[derive(Debug, Clone)]
pub struct StaticSolver {
    capacity: usize,
    /// Ψ rows of the points, `capacity × MODE_CAPACITY`.
    pub shapes: Vec<f64>,
    /// R between the points, `capacity × capacity` (zero without the static flexibility).
    pub residual: Vec<f64>,
    /// g_i, m, and w_i k, N/m.
    pub free_gaps_m: Vec<f64>,
    pub springs_n_m: Vec<f64>,
    /// The forces at the solution (and the warm start on entry), N.
    pub forces_n: Vec<f64>,
    /// r = Σ F_i Ψ_i at the solution.
    pub modal: Vec<f64>,
    /// u_i = Ψ_i · r at the solution, m.
    pub displacements_m: Vec<f64>,
    trial_forces: Vec<f64>,
    blended_forces: Vec<f64>,
    trial_modal: Vec<f64>,
    trial_displacements: Vec<f64>,
    active: Vec<usize>,
    previous_active: Vec<usize>,
    roots: Vec<f64>,
    matrix: Vec<f64>,
    solution: Vec<f64>,
    factor: DenseCholesky,
    /// The dot products over the modes run as SIMD kernels (`lanes.rs`): every static solve
    /// and tuning pass of a retune is on the audio thread's path.
    kernels: Kernels,
    /// 0, 1, 2, …: the rows of every loaded point, for the kernels.
    all_rows: Vec<usize>,
    /// Scratch for one row of dot products.
    dots: Vec<f64>,
}

/// Newton updates a static solve may take; each ends the piecewise-linear problem's current
/// contact set, so a handful suffice (the line search makes up to this many safe).
const STATIC_MAX_ITERATIONS: usize = 100;

impl StaticSolver {
    /// Room for `capacity` points. Allocates.
    pub fn new(capacity: usize) -> Self {
        let zeros = |n: usize| vec![0.0; n];
        Self {
            capacity,
            shapes: zeros(capacity * MODE_CAPACITY),
            residual: zeros(capacity * capacity),
            free_gaps_m: zeros(capacity),
            springs_n_m: zeros(capacity),
            forces_n: zeros(capacity),
            modal: zeros(MODE_CAPACITY),
            displacements_m: zeros(capacity),
            trial_forces: zeros(capacity),
            blended_forces: zeros(capacity),
            trial_modal: zeros(MODE_CAPACITY),
            trial_displacements: zeros(capacity),
            active: vec![0; capacity],
            previous_active: vec![0; capacity],
            roots: zeros(capacity),
            matrix: zeros(capacity * capacity),
            solution: zeros(capacity),
            factor: DenseCholesky::with_capacity(capacity),
            kernels: Kernels::detect(),
            all_rows: (0..capacity).collect(),
            dots: zeros(capacity),
        }
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Loads the bridge and thread points as the first rows; returns their count.
    pub fn load_points(&mut self, points: &ContactPoints) -> usize {
        let count = points.len().min(self.capacity);
        self.shapes[..count * MODE_CAPACITY]
            .copy_from_slice(&points.shapes[..count * MODE_CAPACITY]);
        self.free_gaps_m[..count].copy_from_slice(&points.free_gaps_m[..count]);
        self.springs_n_m[..count].copy_from_slice(&points.springs_n_m[..count]);
        let stride = self.capacity;
        for i in 0..count {
            for j in 0..count {
                self.residual[i * stride + j] = points.residual(i, j);
            }
        }
        count
    }

    /// R between point `i` and `j` of the loaded rows.
    pub fn residual(&self, i: usize, j: usize) -> f64 {
        self.residual[i * self.capacity + j]
    }

    /// Sets R between row `i` and row `j` (both ways).
    pub fn set_residual(&mut self, i: usize, j: usize, value: f64) {
        self.residual[i * self.capacity + j] = value;
        self.residual[j * self.capacity + i] = value;
    }

    /// r = Σ_i forces_i Ψ_i and u = Ψ r + R F for `count` points over `modes` modes; `residual`
    /// is R with row stride `stride`.
    #[allow(clippy::too_many_arguments)]
    fn modal_response(
        (kernels, rows): (&Kernels, &[usize]),
        shapes: &[f64],
        (residual, stride): (&[f64], usize),
        count: usize,
        modes: usize,
        forces: &[f64],
        modal: &mut [f64],
        displacements: &mut [f64],
    ) {
        let lanes = padded_lanes(modes);
        modal[..lanes].fill(0.0);
        for i in 0..count {
            let force = forces[i];
            if force != 0.0 {
                let row = &shapes[i * MODE_CAPACITY..i * MODE_CAPACITY + modes];
                for (m, psi) in modal[..modes].iter_mut().zip(row) {
                    *m += force * psi;
                }
            }
        }
        kernels.dots(
            shapes,
            MODE_CAPACITY,
            &rows[..count],
            &modal[..lanes],
            &mut displacements[..count],
        );
        for i in 0..count {
            let truncated: f64 = residual[i * stride..i * stride + count]
                .iter()
                .zip(&forces[..count])
                .map(|(r, f)| r * f)
                .sum();
            displacements[i] += truncated;
        }
    }

    /// Π: the kept modes' and the truncated modes' strain energy and the contact potential.
    fn energy(
        &self,
        count: usize,
        modes: usize,
        forces: &[f64],
        modal: &[f64],
        displacements: &[f64],
    ) -> f64 {
        let stride = self.capacity;
        let truncated: f64 = (0..count)
            .filter(|&i| forces[i] != 0.0)
            .map(|i| {
                let row = &self.residual[i * stride..i * stride + count];
                0.5 * forces[i]
                    * row
                        .iter()
                        .zip(&forces[..count])
                        .map(|(r, f)| r * f)
                        .sum::<f64>()
            })
            .sum();
        let string: f64 = modal[..modes].iter().map(|r| 0.5 * r * r).sum::<f64>() + truncated;
        let contact: f64 = (0..count)
            .map(|i| {
                let penetration = (self.free_gaps_m[i] - displacements[i]).max(0.0);
                0.5 * self.springs_n_m[i] * penetration * penetration
            })
            .sum();
        string + contact
    }

    /// Solves for `count` points over `modes` modes, starting from `forces_n`. Returns whether it
    /// converged. Allocation-free.
    pub fn solve(&mut self, count: usize, modes: usize) -> bool {
        Self::modal_response(
            (&self.kernels, &self.all_rows),
            &self.shapes,
            (&self.residual, self.capacity),
            count,
            modes,
            &self.forces_n,
            &mut self.modal,
            &mut self.displacements_m,
        );
        let mut energy = self.energy(
            count,
            modes,
            &self.forces_n,
            &self.modal,
            &self.displacements_m,
        );
        let mut previous_size = usize::MAX;
        let mut last_step_full = false;
        for _ in 0..STATIC_MAX_ITERATIONS {
            // The contact set of the current iterate.
            let mut size = 0;
            for i in 0..count {
                if self.free_gaps_m[i] - self.displacements_m[i] > 0.0 {
                    self.active[size] = i;
                    self.roots[size] = self.springs_n_m[i].sqrt();
                    size += 1;
                }
            }
            // The problem is piecewise quadratic: a full Newton step that lands in the contact
            // set it was computed for is its exact minimiser.
            let same_set =
                size == previous_size && self.active[..size] == self.previous_active[..size];
            let settled = same_set
                && (last_step_full
                    || (0..count).all(|i| {
                        let expected = self.springs_n_m[i]
                            * (self.free_gaps_m[i] - self.displacements_m[i]).max(0.0);
                        (self.forces_n[i] - expected).abs() <= 1e-12 * expected.abs().max(1e-9)
                    }));
            if settled {
                return true;
            }
            // The minimiser of the quadratic model: F_A = D (I + D G_AA D)⁻¹ D g_A.
            let lanes = padded_lanes(modes);
            for row in 0..size {
                let i = self.active[row];
                self.kernels.dots(
                    &self.shapes,
                    MODE_CAPACITY,
                    &self.active[..=row],
                    &self.shapes[i * MODE_CAPACITY..i * MODE_CAPACITY + lanes],
                    &mut self.dots[..=row],
                );
                for column in 0..=row {
                    let j = self.active[column];
                    let dot = self.dots[column];
                    let value = self.roots[row] * (dot + self.residual(i, j)) * self.roots[column]
                        + if row == column { 1.0 } else { 0.0 };
                    self.matrix[row * size + column] = value;
                    self.matrix[column * size + row] = value;
                }
                self.solution[row] = self.roots[row] * self.free_gaps_m[i];
            }
            if size > 0 {
                if self
                    .factor
                    .factorise(&self.matrix[..size * size], size)
                    .is_err()
                {
                    return false;
                }
                self.factor.solve_in_place(&mut self.solution[..size]);
            }
            self.trial_forces[..count].fill(0.0);
            for row in 0..size {
                self.trial_forces[self.active[row]] = self.roots[row] * self.solution[row];
            }
            // Backtracking on the convex Π along the Newton direction.
            let mut fraction = 1.0;
            loop {
                for i in 0..count {
                    self.blended_forces[i] =
                        self.forces_n[i] + fraction * (self.trial_forces[i] - self.forces_n[i]);
                }
                Self::modal_response(
                    (&self.kernels, &self.all_rows),
                    &self.shapes,
                    (&self.residual, self.capacity),
                    count,
                    modes,
                    &self.blended_forces,
                    &mut self.trial_modal,
                    &mut self.trial_displacements,
                );
                let trial_energy = self.energy(
                    count,
                    modes,
                    &self.blended_forces,
                    &self.trial_modal,
                    &self.trial_displacements,
                );
                // Round-off in Π near the minimum must not reject a converging step.
                if trial_energy <= energy + 1e-13 * energy.abs() || fraction < 1e-6 {
                    last_step_full = fraction == 1.0;
                    self.forces_n[..count].copy_from_slice(&self.blended_forces[..count]);
                    self.modal[..modes].copy_from_slice(&self.trial_modal[..modes]);
                    self.displacements_m[..count]
                        .copy_from_slice(&self.trial_displacements[..count]);
                    energy = trial_energy;
                    break;
                }
                fraction *= 0.5;
            }
            self.previous_active[..size].copy_from_slice(&self.active[..size]);
            previous_size = size;
        }
        false
    }
}

/// The lowest eigenfrequency of the modes with a spring `w_i k` at every point in contact at
/// rest, rad/s, by inverse iteration (at most `iterations` solves, fewer once the Rayleigh
/// quotient has settled within `settled_below` of itself: `super::rayleigh_settled`). `omega`
/// are the modes' angular frequencies. Allocation-free: it works in the static solver's buffers.
pub fn linearised_fundamental(
    points: &ContactPoints,
    omega: &[f64],
    modes: usize,
    solver: &mut StaticSolver,
    iterations: usize,
    settled_below: f64,
) -> f64 {
    let lanes = padded_lanes(modes);
    let kernels = solver.kernels;
    // The springs in contact at rest and their Woodbury matrix I + D G^s_AA D.
    let mut size = 0;
    for i in 0..points.len() {
        if points.rest_forces_n[i] > 0.0 {
            solver.active[size] = i;
            solver.roots[size] = points.springs_n_m[i].sqrt();
            size += 1;
        }
    }
    for row in 0..size {
        let i = solver.active[row];
        kernels.dots(
            &points.shapes,
            MODE_CAPACITY,
            &solver.active[..=row],
            &points.shape(i)[..lanes],
            &mut solver.dots[..=row],
        );
        for column in 0..=row {
            let value = solver.roots[row] * solver.dots[column] * solver.roots[column]
                + if row == column { 1.0 } else { 0.0 };
            solver.matrix[row * size + column] = value;
            solver.matrix[column * size + row] = value;
        }
    }
    if size > 0
        && solver
            .factor
            .factorise(&solver.matrix[..size * size], size)
            .is_err()
    {
        return f64::NAN;
    }
    let x = &mut solver.modal;
    let product = &mut solver.trial_modal;
    x[modes..lanes].fill(0.0);
    product[modes..lanes].fill(0.0);
    for k in 0..modes {
        x[k] = 1.0 / omega[k];
    }
    let mut rayleigh = 0.0;
    let mut norms = [0.0];
    for _ in 0..iterations {
        // v = M x, M = diag(1/ω²); x ← K⁻¹ v = v − Ψ_Aᵀ D (I + D G D)⁻¹ D Ψ_A v.
        for k in 0..modes {
            product[k] = x[k] / (omega[k] * omega[k]);
        }
        kernels.dots(
            &points.shapes,
            MODE_CAPACITY,
            &solver.active[..size],
            &product[..lanes],
            &mut solver.solution[..size],
        );
        for (value, root) in solver.solution[..size].iter_mut().zip(&solver.roots) {
            *value *= root;
        }
        if size > 0 {
            solver.factor.solve_in_place(&mut solver.solution[..size]);
        }
        x[..modes].copy_from_slice(&product[..modes]);
        for row in 0..size {
            let i = solver.active[row];
            let weight = solver.roots[row] * solver.solution[row];
            for (value, psi) in x[..modes].iter_mut().zip(points.shape(i)) {
                *value -= weight * psi;
            }
        }
        // Rayleigh quotient xᵀ K x / xᵀ M x, K x = x + Ψ_Aᵀ C Ψ_A x.
        kernels.dots(&x[..lanes], lanes, &[0], &x[..lanes], &mut norms);
        let mut stiffness = norms[0];
        kernels.dots(
            &points.shapes,
            MODE_CAPACITY,
            &solver.active[..size],
            &x[..lanes],
            &mut solver.dots[..size],
        );
        for (dot, root) in solver.dots[..size].iter().zip(&solver.roots) {
            stiffness += root * root * dot * dot;
        }
        let mass: f64 = (0..modes)
            .map(|k| x[k] * x[k] / (omega[k] * omega[k]))
            .sum();
        let previous = std::mem::replace(&mut rayleigh, stiffness / mass);
        if super::rayleigh_settled(previous, rayleigh, settled_below) {
            break;
        }
        let norm = norms[0].sqrt();
        for value in &mut x[..modes] {
            *value /= norm;
        }
    }
    rayleigh.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fixed_size_ldl_agrees_with_the_general_one() {
        const SMALL: usize = 8;
        let n = 5;
        let mut general = vec![0.0; n * n];
        let mut small = [[0.0; SMALL]; SMALL];
        for i in 0..SMALL {
            small[i][i] = 1.0;
        }
        for i in 0..n {
            for j in 0..=i {
                let value = if i == j {
                    3.0 + i as f64
                } else {
                    0.3 / (1 + i + j) as f64
                };
                general[i * n + j] = value;
                small[j][i] = value;
            }
        }
        let rhs = [1.0, -2.0, 0.5, 3.0, -1.5];
        let mut x = rhs.to_vec();
        let mut y = [0.0; SMALL];
        y[..n].copy_from_slice(&rhs);
        ldl_solve_in_place(&mut general, n, &mut x, &mut [0.0; 5]);
        ldl_solve_fixed(&mut small, &mut y);
        for i in 0..n {
            assert!((x[i] - y[i]).abs() < 1e-14);
        }
        assert!(y[n..].iter().all(|&v| v == 0.0));
    }

    /// The row-wise left-looking LDLᵀ that [`ldl_factor_fixed`]'s doc names, entry by entry
    /// (`w_k = L_jk d_k`; `d_j = a_jj − Σ_k L_jk w_k` and `L_ij = (a_ij − Σ_k L_ik w_k) · (1/d_j)`,
    /// each product subtracted in turn, k ascending), and its substitutions (forward by rows,
    /// k ascending; back by rows, later entries first), on `n` unknowns of an upper triangle.
    fn row_wise_solve<const N: usize>(upper: &[[f64; N]; N], n: usize, x: &mut [f64; N]) {
        let (mut lower, mut diagonal) = ([[0.0; N]; N], [0.0; N]);
        for j in 0..n {
            let weighted: [f64; N] = std::array::from_fn(|k| lower[j][k] * diagonal[k]);
            let mut d = upper[j][j];
            for k in 0..j {
                d -= lower[j][k] * weighted[k];
            }
            diagonal[j] = d;
            let inverse = 1.0 / d;
            for i in j + 1..n {
                let mut value = upper[j][i];
                for k in 0..j {
                    value -= lower[i][k] * weighted[k];
                }
                lower[i][j] = value * inverse;
            }
        }
        for i in 0..n {
            for k in 0..i {
                x[i] -= lower[i][k] * x[k];
            }
        }
        for i in 0..n {
            x[i] /= diagonal[i];
        }
        for k in (0..n).rev() {
            for i in (k + 1..n).rev() {
                x[k] -= lower[i][k] * x[i];
            }
        }
    }

    /// The fixed-lane factorisation by columns over whole rows, and its substitutions, give the
    /// row-wise loops' solution bit for bit, as their docs say: on full matrices of 1 to 8 lanes
    /// and of 16, and on fewer unknowns padded with the identity (the padding solves x = 0), for
    /// matrices whose entries round in every product.
    #[test]
    fn the_fixed_lane_ldl_is_the_row_wise_one_bit_for_bit() {
        fn check<const LANES: usize>(n: usize) {
            let mut matrix = [[0.0; LANES]; LANES];
            for (b, row) in matrix.iter_mut().enumerate() {
                for (a, value) in row.iter_mut().enumerate() {
                    *value = if a < n && b < n {
                        let base = 1.0 / (1.0 + a as f64 + b as f64).sqrt();
                        if a == b {
                            3.1 + base + 0.7 * a as f64
                        } else {
                            0.9 * base
                        }
                    } else {
                        (a == b) as u8 as f64
                    };
                }
            }
            let rhs: [f64; LANES] = std::array::from_fn(|i| {
                if i < n {
                    (1.3 * i as f64 - 2.1).sin()
                } else {
                    0.0
                }
            });
            let mut expected = rhs;
            row_wise_solve(&matrix, n, &mut expected);
            let mut solved = rhs;
            ldl_solve_fixed(&mut matrix, &mut solved);
            assert_eq!(
                solved.map(f64::to_bits),
                expected.map(f64::to_bits),
                "{LANES} lanes, n = {n}"
            );
            assert!(solved[n..].iter().all(|&v| v == 0.0));
        }
        check::<1>(1);
        check::<2>(2);
        check::<3>(3);
        check::<4>(4);
        check::<5>(5);
        check::<6>(6);
        check::<7>(7);
        for n in [8, 5, 1] {
            check::<8>(n);
        }
        for n in [16, 11, 9] {
            check::<16>(n);
        }
    }

    #[test]
    fn many_right_sides_substitute_as_each_alone_bit_for_bit() {
        fn check<const LANES: usize, const SIDES: usize>(n: usize) {
            let mut matrix: [[f64; LANES]; LANES] = std::array::from_fn(|b| {
                std::array::from_fn(|a| match (a < n && b < n, a == b) {
                    (true, true) => 2.7 + 0.4 * a as f64,
                    (true, false) => 0.8 / (1.5 + a as f64 + 2.0 * b as f64),
                    (false, diagonal) => diagonal as u8 as f64,
                })
            });
            ldl_factor_fixed(&mut matrix);
            let sides: [[f64; LANES]; SIDES] = std::array::from_fn(|side| {
                std::array::from_fn(|i| {
                    if i < n {
                        (0.9 * i as f64 + 1.7 * side as f64 - 0.4).cos()
                    } else {
                        0.0
                    }
                })
            });
            let mut together = sides;
            ldl_substitute_many(&matrix, &mut together);
            for (side, (alone, solved)) in sides.iter().zip(&together).enumerate() {
                let mut alone = *alone;
                ldl_substitute_fixed(&matrix, &mut alone);
                assert_eq!(
                    solved.map(f64::to_bits),
                    alone.map(f64::to_bits),
                    "{LANES} lanes, n = {n}, right side {side} of {SIDES}"
                );
                assert!(solved[..n].iter().any(|&v| v != 0.0));
            }
        }
        check::<8, 1>(8);
        check::<8, 2>(7);
        check::<8, 3>(5);
        check::<8, 9>(8);
        check::<16, 2>(16);
        check::<16, 5>(11);
        check::<16, 9>(9);
    }

    #[test]
    fn ldl_solves_a_known_system() {
        // [[4,2,0],[2,5,1],[0,1,3]] x = [2, 7, 7] has x = [0, 1, 2]; lower triangle only.
        let mut matrix = [4.0, 0.0, 0.0, 2.0, 5.0, 0.0, 0.0, 1.0, 3.0];
        let mut x = [2.0, 7.0, 7.0];
        let mut scratch = [0.0; 3];
        ldl_solve_in_place(&mut matrix, 3, &mut x, &mut scratch);
        for (value, expected) in x.iter().zip([0.0, 1.0, 2.0]) {
            assert!((value - expected).abs() < 1e-14, "{value}");
        }
    }
}
