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
//! eliminated unknowns are linear).
//!
//! Within a step the forces act only on the nodes `C' ⊂ C` that the *candidate* points'
//! stencils reach (the points that can touch during the step, `barrier_grid.rs`), typically half
//! of `C`. The same elimination applied to `C'` gives `S' = [(A⁻¹)_C'C']⁻¹` and Newton on `C'`
//! alone, again with the same iterates: the unknowns of `C \ C'` carry no force and are linear.
//! `S'` is the inverse of a principal block of the precomputed `G = (A⁻¹)_CC`; it is cached and
//! recomputed (O(|C'|³), allocation-free) only when the block changes, which the candidate set
//! does every few hundred steps. Each update factorises the small SPD Jacobian by LDLᵀ.
//!
//! After Newton, the influence matrix `A⁻¹ e_j` (one precomputed column of the whole string's
//! response per contact node) recovers the whole step, `s = s_lin + Σ_j f_j A⁻¹ e_j`, over the
//! nodes that carry a force: one banded solve per time step (the predictor) and no second one.
//! `A` is banded and diagonally dominant, so each column decays geometrically away from its
//! node; the recovery reads it only where it is above 2⁻⁶⁰ of its peak (on the seed's string
//! within 17 nodes of the contact node, of 199; test
//! `reference_grid_columns_are_significant_near_their_node_only`), which leaves out less than the
//! round-off of the correction (`RESPONSE_CUTOFF`).
//! Energy stability is untouched: the accepted `s` solves the same discrete equations (to the
//! Newton tolerance), so the discrete energy balance of the full scheme holds as before. `G` and
//! the influence columns depend only on `A`, so they are recomputed only when the string's
//! parameters change.

use crate::banded::{BandedLdlt, NotPositiveDefinite};
use crate::tanpura::fd::kernels::Kernels;
use crate::unroll::{for_each_index, LARGEST_UNROLLED};
use pulp::{Simd, WithSimd};

/// The contact block `C = first_node..first_node + size`, its Schur complements and the
/// influence columns.
#[derive(Debug, Clone)]
pub struct ContactCondensation {
    first_node: usize,
    size: usize,
    /// N + 1, the length of a full-node vector.
    full_nodes: usize,
    /// G = (A⁻¹)_CC, row-major `size × size`.
    inverse_block: Vec<f64>,
    /// Column j (j = 0..size) is `A⁻¹ e_{first_node + j}` as a full-node vector (zero at the
    /// fixed ends): the whole string's response to a unit scaled force on contact node j.
    response: Vec<f64>,
    /// The nodes `start..end` of each influence column outside which its entries are below
    /// [`RESPONSE_CUTOFF`] of its largest: the only nodes the recovery touches.
    response_support: Vec<(usize, usize)>,
    /// The active block C' = `active_first..active_first + active_size` (nodes) and its
    /// Schur complement S' = [G_C'C']⁻¹, row-major; `active_size == 0` when none is cached.
    active_first: usize,
    active_size: usize,
    active_schur: Vec<f64>,
    /// (Σ I* C I)_C'C' for the current iterate, banded: `band[r][k]` couples the block's nodes
    /// r and r − k (the contact stencils span four nodes).
    band: Vec<[f64; 4]>,
    /// S' + the band (lower triangle), then its LDLᵀ factors.
    jacobian: Vec<f64>,
    /// s_lin on C.
    predictor: Vec<f64>,
    /// The last accepted contact correction s_C − s_lin,C, for the next step's initial guess.
    previous_correction: Vec<f64>,
    /// The one before it (for the linear extrapolation of the initial guess).
    older_correction: Vec<f64>,
    /// The reduced residual, then the Newton update (length |C'|).
    update: Vec<f64>,
    /// Scratch row of the LDLᵀ factorisation.
    scratch: Vec<f64>,
    /// The vector unit the Newton update is compiled for ([`NewtonUpdate`]).
    kernels: Kernels,
}

impl ContactCondensation {
    /// Room for the nodes `first_node..=last_node` (all interior) of a string with
    /// `unknowns` = N − 1 free nodes. Allocates.
    pub fn new(first_node: usize, last_node: usize, unknowns: usize) -> Self {
        let size = last_node + 1 - first_node;
        let full_nodes = unknowns + 2;
        Self {
            first_node,
            size,
            full_nodes,
            inverse_block: vec![0.0; size * size],
            response: vec![0.0; size * full_nodes],
            response_support: vec![(0, full_nodes); size],
            active_first: first_node,
            active_size: 0,
            active_schur: vec![0.0; size * size],
            band: vec![[0.0; 4]; size],
            jacobian: vec![0.0; size * size],
            predictor: vec![0.0; size],
            previous_correction: vec![0.0; size],
            older_correction: vec![0.0; size],
            update: vec![0.0; size],
            scratch: vec![0.0; size],
            kernels: Kernels::detect(),
        }
    }

    pub fn first_node(&self) -> usize {
        self.first_node
    }

    pub fn size(&self) -> usize {
        self.size
    }

    /// The active block C' as (first node, size).
    pub fn active_block(&self) -> (usize, usize) {
        (self.active_first, self.active_size)
    }

    /// Recomputes `G` and the influence columns from the factorised step matrix `A` (N − 1
    /// unknowns; row i ↔ node i + 1). `column` is scratch of length ≥ N − 1. Allocation-free.
    pub fn prepare(
        &mut self,
        step_factor: &BandedLdlt,
        column: &mut [f64],
    ) -> Result<(), NotPositiveDefinite> {
        let size = self.size;
        let offset = self.first_node - 1;
        let unknowns = self.full_nodes - 2;
        let column = &mut column[..unknowns];
        for j in 0..size {
            column.fill(0.0);
            column[offset + j] = 1.0;
            step_factor.solve_in_place(column);
            for i in 0..size {
                self.inverse_block[i * size + j] = column[offset + i];
            }
            let response = &mut self.response[j * self.full_nodes..(j + 1) * self.full_nodes];
            response.fill(0.0);
            response[1..=unknowns].copy_from_slice(column);
            self.response_support[j] = significant_support(response);
        }
        self.previous_correction.fill(0.0);
        self.older_correction.fill(0.0);
        self.active_size = 0;
        // G must be positive definite: check it once here, so that every principal block the
        // steps ask for is (up to round-off) as well.
        self.active_schur[..size * size].copy_from_slice(&self.inverse_block);
        if !ldlt_in_place(&mut self.active_schur, size, &mut self.scratch) {
            return Err(NotPositiveDefinite { row: 0 });
        }
        Ok(())
    }

    /// Makes the nodes `first..=last` (inside C) the active block, recomputing its Schur
    /// complement `S' = [G_C'C']⁻¹` unless it is the cached one. Returns false, leaving no
    /// block cached, if that principal block of `G` is not positive definite (round-off on an
    /// ill-conditioned `A`). Allocation-free.
    pub fn set_active_block(&mut self, first: usize, last: usize) -> bool {
        debug_assert!(first >= self.first_node && last < self.first_node + self.size);
        let size = last + 1 - first;
        if first == self.active_first && size == self.active_size {
            return true;
        }
        self.active_first = first;
        self.active_size = size;
        let offset = first - self.first_node;
        // Factorise G_C'C' (in `jacobian`), then S' column by column.
        for i in 0..size {
            let source = &self.inverse_block[(offset + i) * self.size + offset..][..size];
            self.jacobian[i * size..(i + 1) * size].copy_from_slice(source);
        }
        if !ldlt_in_place(&mut self.jacobian, size, &mut self.scratch) {
            self.active_size = 0;
            return false;
        }
        for j in 0..size {
            let unit = &mut self.update[..size];
            unit.fill(0.0);
            unit[j] = 1.0;
            ldlt_solve(&self.jacobian, size, unit);
            for i in 0..size {
                self.active_schur[i * size + j] = unit[i];
            }
        }
        // Symmetrise: S' is symmetric, its computed columns only to round-off.
        for i in 0..size {
            for j in 0..i {
                let mean =
                    0.5 * (self.active_schur[i * size + j] + self.active_schur[j * size + i]);
                self.active_schur[i * size + j] = mean;
                self.active_schur[j * size + i] = mean;
            }
        }
        true
    }

    /// Records `s_lin` on C from the full-node predictor step.
    pub fn set_predictor(&mut self, step: &[f64]) {
        self.predictor
            .copy_from_slice(&step[self.first_node..self.first_node + self.size]);
    }

    /// Starts Newton on the active block from `s_lin` plus the contact correction extrapolated
    /// linearly from the last two steps (`2c_{n−1} − c_{n−2}`): contact forces vary smoothly from
    /// step to step, so this guess saves updates. With the last correction alone the reference
    /// tier's voice took 2.92 updates per step after the default pluck; with the extrapolation
    /// 2.64 (a quadratic extrapolation gave 2.65). The iterates then differ from the last
    /// guess's within the Newton tolerance.
    pub fn apply_initial_guess(&self, step: &mut [f64]) {
        let offset = self.active_first - self.first_node;
        let range = offset..offset + self.active_size;
        let guesses = self.predictor[range.clone()]
            .iter()
            .zip(&self.previous_correction[range.clone()])
            .zip(&self.older_correction[range]);
        for (s, ((predictor, correction), older)) in
            step[self.active_first..].iter_mut().zip(guesses)
        {
            *s = initial_guess(*predictor, *correction, *older);
        }
    }

    /// Forgets the contact correction (a step without contact, or a new excitation).
    pub fn clear_correction(&mut self) {
        self.previous_correction.fill(0.0);
        self.older_correction.fill(0.0);
    }

    /// The largest |s| on C of the step `s = s_lin + G f` that the forces `contact` (full-node,
    /// nonzero on the active block only) give, without forming it elsewhere: the reach check
    /// of the candidate margin.
    pub fn block_step_max_abs(&self, contact: &[f64]) -> f64 {
        let offset = self.active_first - self.first_node;
        let forces = &contact[self.active_first..self.active_first + self.active_size];
        let mut largest = 0.0f64;
        for (i, predictor) in self.predictor.iter().enumerate() {
            let row = &self.inverse_block[i * self.size + offset..][..self.active_size];
            let correction: f64 = row.iter().zip(forces).map(|(g, f)| g * f).sum();
            largest = largest.max((predictor + correction).abs());
        }
        largest
    }

    /// Recovers the whole step from the predictor and the contact forces on the active block:
    /// `s = s_lin + Σ_j f_j A⁻¹ e_j` (full-node vectors; `step` holds `s_lin` outside the
    /// active block on entry). Records the contact correction on C for the next step.
    pub fn recover_step(&mut self, kernels: &Kernels, step: &mut [f64], contact: &[f64]) {
        let first = self.first_node;
        let size = self.size;
        step[first..first + size].copy_from_slice(&self.predictor);
        let offset = self.active_first - first;
        let forces = &contact[self.active_first..self.active_first + self.active_size];
        for (j, &force) in forces.iter().enumerate() {
            if force != 0.0 {
                let column = offset + j;
                let response =
                    &self.response[column * self.full_nodes..(column + 1) * self.full_nodes];
                let (start, end) = self.response_support[column];
                kernels.axpy(force, &response[start..end], &mut step[start..end]);
            }
        }
        std::mem::swap(&mut self.previous_correction, &mut self.older_correction);
        for ((correction, s), predictor) in self
            .previous_correction
            .iter_mut()
            .zip(&step[first..first + size])
            .zip(&self.predictor)
        {
            *correction = s - predictor;
        }
    }

    /// The largest |s| on C of Newton's initial guess (`s_lin` plus the extrapolated
    /// correction, as [`ContactCondensation::apply_initial_guess`] forms it on the block), m.
    pub fn guess_max_abs(&self) -> f64 {
        self.predictor
            .iter()
            .zip(&self.previous_correction)
            .zip(&self.older_correction)
            .fold(0.0, |largest, ((p, c), o)| {
                largest.max(initial_guess(*p, *c, *o).abs())
            })
    }

    /// The contact Jacobian band of the active block, zeroed, for barriers to add their
    /// `I* C I` into; with the block's first node and size.
    pub fn contact_band_reset(&mut self) -> (&mut [[f64; 4]], usize, usize) {
        let band = &mut self.band[..self.active_size];
        band.fill([0.0; 4]);
        (band, self.active_first, self.active_size)
    }

    /// One Newton update on the active block: with the contact forces `contact` (full-node,
    /// I* f̃) and the contact band already evaluated at `step`, forms the Jacobian
    /// `S' + I* C I`, solves and applies the update to `step` on the block. Returns ‖δ‖∞, or
    /// None when the Jacobian is not positive definite.
    pub fn update(&mut self, step: &mut [f64], contact: &[f64]) -> Option<f64> {
        let kernels = self.kernels;
        kernels.arch.dispatch(NewtonUpdate {
            condensation: self,
            step,
            contact,
        })
    }

    /// [`ContactCondensation::update`] on the vector unit of the enclosing dispatch.
    #[inline(always)]
    fn update_inlined(&mut self, step: &mut [f64], contact: &[f64]) -> Option<f64> {
        match self.active_size {
            4 => self.update_fixed::<4>(step, contact),
            5 => self.update_fixed::<5>(step, contact),
            6 => self.update_fixed::<6>(step, contact),
            7 => self.update_fixed::<7>(step, contact),
            8 => self.update_fixed::<8>(step, contact),
            _ => self.update_any_size(step, contact),
        }
    }

    /// [`ContactCondensation::update`] for an active block of `M` nodes (the common sizes at
    /// the seed's grid: 5 to 8), in fixed-size arrays, so that the loops unroll and the factors
    /// stay in registers. The same operations in the same order as the any-size path.
    #[inline(always)]
    // The written-out loops meet ranges and comparisons that are empty or constant at some
    // indices; the compiler folds them, as it should.
    #[allow(clippy::absurd_extreme_comparisons, clippy::reversed_empty_ranges)]
    fn update_fixed<const M: usize>(&mut self, step: &mut [f64], contact: &[f64]) -> Option<f64> {
        let first = self.active_first;
        let offset = first - self.first_node;
        let mut schur = [[0.0; M]; M];
        for (row, source) in schur
            .iter_mut()
            .zip(self.active_schur[..M * M].chunks_exact(M))
        {
            row.copy_from_slice(source);
        }
        let mut jacobian = schur;
        for (row, entries) in self.band[..M].iter().enumerate() {
            for (k, value) in entries.iter().enumerate().take(row + 1) {
                jacobian[row][row - k] += value;
            }
        }
        let block_step: &mut [f64; M] = (&mut step[first..first + M]).try_into().ok()?;
        let predictor: &[f64; M] = self.predictor[offset..offset + M].try_into().ok()?;
        let forces: &[f64; M] = contact[first..first + M].try_into().ok()?;
        // R = S' (s − s_lin) − f on the block.
        let mut difference = [0.0; M];
        for ((d, s), p) in difference.iter_mut().zip(&*block_step).zip(predictor) {
            *d = s - p;
        }
        let mut solution = [0.0; M];
        for ((x, row), force) in solution.iter_mut().zip(&schur).zip(forces) {
            let mut product = 0.0;
            for (a, b) in row.iter().zip(&difference) {
                product += a * b;
            }
            *x = product - force;
        }
        // LDLᵀ in place (as `ldlt_in_place`: L below the diagonal, 1/D on it), then the solve;
        // every loop written out at compile time (`crate::unroll`), the same operations in the
        // same order.
        const { assert!(M <= LARGEST_UNROLLED) };
        for_each_index!(ascending I => {
            if const { I < M } {
                let mut u = [0.0; M];
                for_each_index!(ascending J => {
                    if const { J < I } {
                        let mut dot = 0.0;
                        for k in 0..J {
                            dot += u[k] * jacobian[J][k];
                        }
                        u[J] = jacobian[I][J] - dot;
                    }
                });
                let mut diagonal = jacobian[I][I];
                for j in 0..I {
                    let l = u[j] * jacobian[j][j];
                    jacobian[I][j] = l;
                    diagonal -= u[j] * l;
                }
                if diagonal.is_nan() || diagonal <= 0.0 {
                    return None;
                }
                jacobian[I][I] = 1.0 / diagonal;
            }
        });
        for_each_index!(ascending I => {
            if const { I < M } {
                let mut dot = 0.0;
                for j in 0..I {
                    dot += jacobian[I][j] * solution[j];
                }
                solution[I] -= dot;
            }
        });
        for (i, x) in solution.iter_mut().enumerate() {
            *x *= jacobian[i][i];
        }
        for_each_index!(descending I => {
            if const { I < M } {
                let x = solution[I];
                for j in 0..I {
                    solution[j] -= jacobian[I][j] * x;
                }
            }
        });
        let mut largest = 0.0f64;
        for (s, delta) in block_step.iter_mut().zip(&solution) {
            *s -= delta;
            largest = largest.max(delta.abs());
        }
        Some(largest)
    }

    /// [`ContactCondensation::update`] for any block size.
    fn update_any_size(&mut self, step: &mut [f64], contact: &[f64]) -> Option<f64> {
        let size = self.active_size;
        let first = self.active_first;
        let offset = first - self.first_node;
        let cells = size * size;
        self.jacobian[..cells].copy_from_slice(&self.active_schur[..cells]);
        for (row, entries) in self.band[..size].iter().enumerate() {
            for (k, value) in entries.iter().enumerate().take(row + 1) {
                self.jacobian[row * size + row - k] += value;
            }
        }
        // R = S' (s − s_lin) − f on the block; `scratch` holds s − s_lin.
        let block_step = &step[first..first + size];
        for ((difference, s), predictor) in self.scratch[..size]
            .iter_mut()
            .zip(block_step)
            .zip(&self.predictor[offset..offset + size])
        {
            *difference = s - predictor;
        }
        let forces = &contact[first..first + size];
        let rows = self.active_schur[..size * size].chunks_exact(size);
        for ((residual, row), force) in self.update[..size].iter_mut().zip(rows).zip(forces) {
            let product: f64 = row
                .iter()
                .zip(&self.scratch[..size])
                .map(|(a, b)| a * b)
                .sum();
            *residual = product - force;
        }
        if !ldlt_in_place(&mut self.jacobian[..size * size], size, &mut self.scratch) {
            return None;
        }
        ldlt_solve(
            &self.jacobian[..size * size],
            size,
            &mut self.update[..size],
        );
        let mut largest = 0.0f64;
        for (s, delta) in step[first..first + size]
            .iter_mut()
            .zip(&self.update[..size])
        {
            *s -= delta;
            largest = largest.max(delta.abs());
        }
        Some(largest)
    }
}

/// [`ContactCondensation::update`] compiled for the vector unit found at run time, as
/// [`crate::banded::BandedLdlt`]'s solve is: the same operations in the same order, the same
/// result bit for bit (test `fixed_size_updates_equal_the_any_size_update` compares it with the
/// generic any-size path). The contact law's evaluation stays outside: dispatched together with
/// the update it ran 5 % slower.
struct NewtonUpdate<'a> {
    condensation: &'a mut ContactCondensation,
    step: &'a mut [f64],
    contact: &'a [f64],
}

impl WithSimd for NewtonUpdate<'_> {
    type Output = Option<f64>;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) -> Option<f64> {
        self.condensation.update_inlined(self.step, self.contact)
    }
}

/// Entries of an influence column `A⁻¹ e_j` below this fraction of the column's largest are
/// left out of the recovery. The step matrix is banded and diagonally dominant, so its inverse
/// decays geometrically away from the diagonal: on the seed's string a column falls below 2⁻⁶⁰
/// within 17 nodes of its contact node (a factor of about 11 per node), and what is left out
/// lies under the round-off (2⁻⁵³) of the correction at that node. The recovery then costs a few
/// dozen nodes per forced node instead of the whole string.
const RESPONSE_CUTOFF: f64 = 1.0 / (1u64 << 60) as f64;

/// The nodes `start..end` outside which `column`'s entries are at most [`RESPONSE_CUTOFF`]
/// of its largest (the whole column when it is zero).
fn significant_support(column: &[f64]) -> (usize, usize) {
    let largest = column.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let threshold = RESPONSE_CUTOFF * largest;
    let start = column.iter().position(|v| v.abs() > threshold);
    let end = column.iter().rposition(|v| v.abs() > threshold);
    match (start, end) {
        (Some(start), Some(end)) => (start, end + 1),
        _ => (0, column.len()),
    }
}

/// Newton's initial guess at one node: the predictor plus the contact correction extrapolated
/// linearly from the last two accepted steps' (`2 c − c_older`).
#[inline(always)]
fn initial_guess(predictor: f64, correction: f64, older_correction: f64) -> f64 {
    predictor + (2.0 * correction - older_correction)
}

/// Factorises the symmetric positive definite row-major `size × size` matrix (only its lower
/// triangle is read) in place as `L D Lᵀ`: the strict lower triangle receives L, the diagonal
/// receives 1/D. Returns false if a pivot is not positive. `row_scratch` holds ≥ size values.
/// O(size³/6) multiply-adds, square-root free, allocation-free.
fn ldlt_in_place(matrix: &mut [f64], size: usize, row_scratch: &mut [f64]) -> bool {
    for i in 0..size {
        let (done, rest) = matrix.split_at_mut(i * size);
        let row = &mut rest[..size];
        // u_j = L_ij D_j = A_ij − Σ_{k<j} u_k L_jk, for j < i (u kept in `row_scratch`).
        let u = &mut row_scratch[..i];
        for j in 0..i {
            let previous = &done[j * size..j * size + j];
            let dot: f64 = u[..j].iter().zip(previous).map(|(a, b)| a * b).sum();
            u[j] = row[j] - dot;
        }
        // L_ij = u_j / D_j and D_i = A_ii − Σ_j u_j L_ij.
        let mut diagonal = row[i];
        for j in 0..i {
            let l = u[j] * done[j * size + j];
            row[j] = l;
            diagonal -= u[j] * l;
        }
        if diagonal.is_nan() || diagonal <= 0.0 {
            return false;
        }
        row[i] = 1.0 / diagonal;
    }
    true
}

/// Solves `L D Lᵀ x = rhs` in place with the factors of [`ldlt_in_place`].
fn ldlt_solve(factors: &[f64], size: usize, solution: &mut [f64]) {
    let solution = &mut solution[..size];
    for i in 0..size {
        let row = &factors[i * size..i * size + i];
        let dot: f64 = row.iter().zip(&solution[..i]).map(|(l, x)| l * x).sum();
        solution[i] -= dot;
    }
    for (i, x) in solution.iter_mut().enumerate() {
        *x *= factors[i * size + i];
    }
    for i in (0..size).rev() {
        let x = solution[i];
        let row = &factors[i * size..i * size + i];
        for (target, l) in solution[..i].iter_mut().zip(row) {
            *target -= l * x;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::banded::SymmetricBanded;
    use crate::tanpura::fd::{FdString, FdStringConfig};

    /// A pentadiagonal SPD matrix on `unknowns` unknowns, factorised.
    fn factorised_test_matrix(unknowns: usize) -> BandedLdlt {
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
        factor
    }

    #[test]
    fn schur_complement_reproduces_the_full_solve() {
        // A pentadiagonal SPD matrix on 12 unknowns (nodes 1..=12), C = nodes 4..=7.
        let unknowns = 12;
        let factor = factorised_test_matrix(unknowns);
        let mut condensation = ContactCondensation::new(4, 7, unknowns);
        let mut scratch = vec![0.0; unknowns];
        condensation.prepare(&factor, &mut scratch).unwrap();
        // For a force f on C: s = s_lin + A⁻¹ f, and S (s_C − s_lin,C) must equal f_C.
        assert!(condensation.set_active_block(4, 7));
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
                value += condensation.active_schur[i * 4 + j] * (with_force[3 + j] - s_lin[3 + j]);
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
        condensation.recover_step(&Kernels::detect(), &mut step, &contact);
        for i in 0..unknowns {
            assert!((step[i + 1] - with_force[i]).abs() < 1e-12);
        }
    }

    /// The recovery reads each influence column only where it is significant: on a long string
    /// the columns' supports are short, and the recovered step is the full solve's to
    /// round-off.
    #[test]
    fn recovery_on_the_columns_supports_matches_the_full_solve() {
        let unknowns = 240;
        let factor = factorised_test_matrix(unknowns);
        let (first_node, last_node) = (100, 107);
        let mut condensation = ContactCondensation::new(first_node, last_node, unknowns);
        let mut scratch = vec![0.0; unknowns];
        condensation.prepare(&factor, &mut scratch).unwrap();
        for (j, &(start, end)) in condensation.response_support.iter().enumerate() {
            let node = first_node + j;
            assert!(start <= node && node < end, "column {j}: {start}..{end}");
            assert!(end - start < unknowns / 2, "column {j}: {start}..{end}");
        }
        assert!(condensation.set_active_block(first_node, last_node));
        let rhs: Vec<f64> = (0..unknowns).map(|i| (0.1 * i as f64).sin()).collect();
        let mut s_lin = rhs.clone();
        factor.solve_in_place(&mut s_lin);
        let mut with_force = rhs;
        let mut contact = vec![0.0; unknowns + 2];
        for k in 0..=last_node - first_node {
            let force = 1.0 + 0.3 * k as f64;
            with_force[first_node - 1 + k] += force;
            contact[first_node + k] = force;
        }
        factor.solve_in_place(&mut with_force);
        let mut step = vec![0.0; unknowns + 2];
        step[1..=unknowns].copy_from_slice(&s_lin);
        condensation.set_predictor(&step);
        condensation.recover_step(&Kernels::detect(), &mut step, &contact);
        let largest = with_force.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..unknowns {
            let error = (step[i + 1] - with_force[i]).abs();
            assert!(error <= 1e-15 * largest, "node {}: {error:e}", i + 1);
        }
    }

    /// At the seed's grid (the reference tier) each influence column is significant over a few
    /// dozen nodes around its contact node, not over the string's 199: the figure the module
    /// doc and `docs/performance.md` quote.
    #[test]
    fn reference_grid_columns_are_significant_near_their_node_only() {
        let string = FdString::new(FdStringConfig::REFERENCE);
        let condensation = string.solver.condensation.as_ref().expect("contact block");
        let mut reaches = Vec::new();
        for (j, &(start, end)) in condensation.response_support.iter().enumerate() {
            let node = condensation.first_node + j;
            assert!(start <= node && node < end, "column {j}: {start}..{end}");
            reaches.push((node - start).max(end - 1 - node));
        }
        let (least, most) = (reaches.iter().min().unwrap(), reaches.iter().max().unwrap());
        // 17 nodes on the seed's string.
        assert!(*least >= 14 && *most <= 20, "reach {least}..={most} nodes");
    }

    /// The fixed-size updates (blocks of 4 to 8 nodes) against the any-size update, bit for bit,
    /// for every block size from 1 to 12 and every position of the block in C.
    #[test]
    fn fixed_size_updates_equal_the_any_size_update() {
        let unknowns = 16;
        let factor = factorised_test_matrix(unknowns);
        let (first_node, last_node) = (2, 13);
        let mut condensation = ContactCondensation::new(first_node, last_node, unknowns);
        let mut scratch = vec![0.0; unknowns];
        condensation.prepare(&factor, &mut scratch).unwrap();
        let predictor: Vec<f64> = (0..unknowns + 2).map(|i| (0.7 * i as f64).sin()).collect();
        condensation.set_predictor(&predictor);
        let mut checked_fixed = 0;
        for size in 1..=12 {
            for first in first_node..=last_node + 1 - size {
                assert!(condensation.set_active_block(first, first + size - 1));
                let (band, _, _) = condensation.contact_band_reset();
                for (row, entries) in band.iter_mut().enumerate() {
                    for (k, value) in entries.iter_mut().enumerate() {
                        *value = 0.3 + 0.05 * (row + k) as f64 * if k == 0 { 1.0 } else { -0.2 };
                    }
                }
                let contact: Vec<f64> = (0..unknowns + 2).map(|i| (1.3 * i as f64).cos()).collect();
                let start: Vec<f64> = (0..unknowns + 2)
                    .map(|i| predictor[i] + 0.01 * (0.4 * i as f64).cos())
                    .collect();
                let (mut dispatched, mut general) = (start.clone(), start);
                let a = condensation.update(&mut dispatched, &contact);
                let b = condensation.update_any_size(&mut general, &contact);
                assert_eq!(
                    a.map(f64::to_bits),
                    b.map(f64::to_bits),
                    "size {size}, first {first}"
                );
                assert!(a.is_some());
                for (x, y) in dispatched.iter().zip(&general) {
                    assert_eq!(x.to_bits(), y.to_bits(), "size {size}, first {first}");
                }
                checked_fixed += (4..=8).contains(&size) as usize;
            }
        }
        assert!(checked_fixed > 0);
    }

    #[test]
    fn sub_block_schur_complement_matches_forces_on_the_sub_block() {
        // The same matrix, C = nodes 3..=9, forces only on C' = nodes 5..=7.
        let unknowns = 12;
        let factor = factorised_test_matrix(unknowns);
        let mut condensation = ContactCondensation::new(3, 9, unknowns);
        let mut scratch = vec![0.0; unknowns];
        condensation.prepare(&factor, &mut scratch).unwrap();
        assert!(condensation.set_active_block(5, 7));
        assert_eq!(condensation.active_block(), (5, 3));
        let force = [0.4, -0.2, 1.5];
        let mut response = vec![0.0; unknowns];
        for (k, f) in force.iter().enumerate() {
            response[4 + k] = *f;
        }
        factor.solve_in_place(&mut response);
        for i in 0..3 {
            let value: f64 = (0..3)
                .map(|j| condensation.active_schur[i * 3 + j] * response[4 + j])
                .sum();
            assert!((value - force[i]).abs() < 1e-12, "{value} vs {}", force[i]);
        }
    }

    #[test]
    fn ldlt_solves_a_known_system() {
        // [[4,2,0],[2,5,1],[0,1,3]] x = [2, 7, 7] has x = [0, 1, 2]; only the lower triangle
        // is read, so the upper one holds garbage.
        let mut matrix = [4.0, 99.0, 99.0, 2.0, 5.0, 99.0, 0.0, 1.0, 3.0];
        let mut scratch = [0.0; 3];
        assert!(ldlt_in_place(&mut matrix, 3, &mut scratch));
        let mut x = [2.0, 7.0, 7.0];
        ldlt_solve(&matrix, 3, &mut x);
        for (value, expected) in x.iter().zip([0.0, 1.0, 2.0]) {
            assert!((value - expected).abs() < 1e-14);
        }
        let mut indefinite = [1.0, 0.0, 2.0, 1.0];
        assert!(!ldlt_in_place(&mut indefinite, 2, &mut scratch));
    }
}
