//! Symmetric banded matrices and their LDLᵀ factorisation, allocation-free after construction.
//!
//! The string operator of the tanpura scheme (seed 000, eq. 14–15) is pentadiagonal, and each
//! contact term `I* C I` of the Newton Jacobian (eq. 24) adds a band of half-width 3 from the
//! four-point Lagrange stencil. The Jacobian stays symmetric positive definite (C ≥ 0), so a
//! square-root-free LDLᵀ factorisation without pivoting is exact and stable. No crate offers an
//! allocation-free banded factorisation, hence this hand-written one (`design.md`).

use crate::simd::Kernels;
use pulp::{Simd, WithSimd};

/// A symmetric `size × size` matrix whose entries vanish more than `half_bandwidth` off the
/// diagonal. Storage: `band[row * (w + 1) + k] = A[row][row − k]` for `k = 0..=w`.
#[derive(Debug, Clone, PartialEq)]
pub struct SymmetricBanded {
    size: usize,
    half_bandwidth: usize,
    band: Vec<f64>,
}

impl SymmetricBanded {
    /// A zero matrix. Allocates; everything else is allocation-free.
    pub fn zeros(size: usize, half_bandwidth: usize) -> Self {
        Self {
            size,
            half_bandwidth,
            band: vec![0.0; size * (half_bandwidth + 1)],
        }
    }

    pub fn size(&self) -> usize {
        self.size
    }

    pub fn half_bandwidth(&self) -> usize {
        self.half_bandwidth
    }

    fn index(&self, row: usize, column: usize) -> usize {
        let (row, column) = if row >= column {
            (row, column)
        } else {
            (column, row)
        };
        let offset = row - column;
        debug_assert!(offset <= self.half_bandwidth, "entry outside the band");
        row * (self.half_bandwidth + 1) + offset
    }

    /// Sets every entry to zero.
    pub fn clear(&mut self) {
        self.band.fill(0.0);
    }

    /// `A[row][column]` (zero outside the band).
    pub fn get(&self, row: usize, column: usize) -> f64 {
        if row.abs_diff(column) > self.half_bandwidth {
            0.0
        } else {
            self.band[self.index(row, column)]
        }
    }

    /// Sets `A[row][column]` and, by symmetry, `A[column][row]`.
    pub fn set(&mut self, row: usize, column: usize, value: f64) {
        let index = self.index(row, column);
        self.band[index] = value;
    }

    /// Adds to `A[row][column]` (and its mirror): one call per symmetric pair, not two.
    pub fn add(&mut self, row: usize, column: usize, value: f64) {
        let index = self.index(row, column);
        self.band[index] += value;
    }

    /// Copies another matrix of the same size whose band is no wider than this one's.
    pub fn copy_from(&mut self, other: &SymmetricBanded) {
        debug_assert_eq!(self.size, other.size);
        debug_assert!(other.half_bandwidth <= self.half_bandwidth);
        if other.half_bandwidth == self.half_bandwidth {
            self.band.copy_from_slice(&other.band);
            return;
        }
        self.band.fill(0.0);
        let width = self.half_bandwidth + 1;
        let other_width = other.half_bandwidth + 1;
        for row in 0..self.size {
            self.band[row * width..row * width + other_width]
                .copy_from_slice(&other.band[row * other_width..(row + 1) * other_width]);
        }
    }

    /// `output = A · input`.
    pub fn multiply(&self, input: &[f64], output: &mut [f64]) {
        let width = self.half_bandwidth + 1;
        output[..self.size].fill(0.0);
        for row in 0..self.size {
            let entries = &self.band[row * width..(row + 1) * width];
            output[row] += entries[0] * input[row];
            for (offset, &entry) in entries.iter().enumerate().skip(1) {
                if offset > row {
                    break;
                }
                let column = row - offset;
                output[row] += entry * input[column];
                output[column] += entry * input[row];
            }
        }
    }
}

/// The factors `L` (unit lower triangular, banded) and `D` (diagonal) of `A = L D Lᵀ`, stored in
/// place of the band: `band[row][0] = D[row]`, `band[row][k] = L[row][row − k]`.
#[derive(Debug, Clone)]
pub struct BandedLdlt {
    factors: SymmetricBanded,
    /// 1/D, so that solves multiply instead of divide.
    inverse_diagonal: Vec<f64>,
    /// For half-bandwidth 2 (the string's step matrix, solved every time step), the factors
    /// once more in the order the two sweeps read them: `forward[r] = (L[r][r−1], L[r][r−2])`
    /// and `backward[r] = (1/D[r], L[r+1][r], L[r+2][r])` (zero beyond the matrix). Empty for
    /// other bandwidths.
    forward: Vec<[f64; 2]>,
    backward: Vec<[f64; 3]>,
    /// For the partitioned pentadiagonal solve (see [`PARTITIONS`]), each row's response to
    /// the two values its block's sweep starts from: forward `(∂z[r]/∂z[s−1], ∂z[r]/∂z[s−2])`
    /// for a block starting at `s`, backward `(∂x[r]/∂x[e], ∂x[r]/∂x[e+1])` for a block ending
    /// before `e`. Empty when the matrix is too small to partition.
    forward_homogeneous: Vec<[f64; 2]>,
    backward_homogeneous: Vec<[f64; 2]>,
    /// The vector unit the pentadiagonal solve is compiled for (see [`PentadiagonalSolve`]).
    kernels: Kernels,
}

/// The pentadiagonal sweeps run as this many independent chains over consecutive blocks of
/// rows, joined afterwards through each block's precomputed homogeneous responses.
const PARTITIONS: usize = 4;

/// Below this many rows per block the partitioned solve is not worth its fix-up pass.
const MIN_PARTITION_ROWS: usize = 8;

/// How a pentadiagonal matrix of `size` rows is partitioned: `(prefix, rows)`, the first block
/// being `prefix + rows` long and the other three `rows`; `None` when too small.
fn partition(size: usize) -> Option<(usize, usize)> {
    let rows = size / PARTITIONS;
    (rows >= MIN_PARTITION_ROWS).then_some((size - PARTITIONS * rows, rows))
}

/// The matrix handed to [`BandedLdlt::factorise`] was not positive definite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NotPositiveDefinite {
    pub row: usize,
}

impl BandedLdlt {
    /// Room for factorising matrices of this shape. Allocates.
    pub fn with_shape(size: usize, half_bandwidth: usize) -> Self {
        let pentadiagonal_size = if half_bandwidth == 2 { size } else { 0 };
        Self {
            factors: SymmetricBanded::zeros(size, half_bandwidth),
            inverse_diagonal: vec![0.0; size],
            forward: vec![[0.0; 2]; pentadiagonal_size],
            backward: vec![[0.0; 3]; pentadiagonal_size],
            forward_homogeneous: vec![[0.0; 2]; pentadiagonal_size],
            backward_homogeneous: vec![[0.0; 2]; pentadiagonal_size],
            kernels: Kernels::detect(),
        }
    }

    /// Factorises `matrix` into the preallocated storage: O(size · w²) operations, no allocation.
    pub fn factorise(&mut self, matrix: &SymmetricBanded) -> Result<(), NotPositiveDefinite> {
        self.factors.copy_from(matrix);
        let size = self.factors.size;
        let w = self.factors.half_bandwidth;
        let width = w + 1;
        let band = &mut self.factors.band;
        for row in 0..size {
            // L[row][col] · D[col] = A[row][col] − Σ_{k<col} L[row][k] D[k] L[col][k]
            let first = row.saturating_sub(w);
            for column in first..row {
                let mut value = band[row * width + (row - column)];
                let shared_first = first.max(column.saturating_sub(w));
                for k in shared_first..column {
                    value -= band[row * width + (row - k)]
                        * band[k * width]
                        * band[column * width + (column - k)];
                }
                band[row * width + (row - column)] = value / band[column * width];
            }
            let mut diagonal = band[row * width];
            for k in first..row {
                let l = band[row * width + (row - k)];
                diagonal -= l * l * band[k * width];
            }
            if diagonal.is_nan() || diagonal <= 0.0 {
                return Err(NotPositiveDefinite { row });
            }
            band[row * width] = diagonal;
            self.inverse_diagonal[row] = 1.0 / diagonal;
        }
        if w == 2 {
            let entry = |row: usize, offset: usize| {
                if row < size {
                    self.factors.band[row * 3 + offset]
                } else {
                    0.0
                }
            };
            for row in 0..size {
                self.forward[row] = [entry(row, 1), entry(row, 2)];
                self.backward[row] = [
                    self.inverse_diagonal[row],
                    entry(row + 1, 1),
                    entry(row + 2, 2),
                ];
            }
            self.prepare_partitions();
        }
        Ok(())
    }

    /// The homogeneous responses of each block of the partitioned solve (zero right-hand side,
    /// a unit value in one of the two rows the block's sweep starts from).
    fn prepare_partitions(&mut self) {
        let size = self.factors.size;
        let Some((prefix, rows)) = partition(size) else {
            return;
        };
        for block in 1..PARTITIONS {
            let start = prefix + block * rows;
            // (z[r−1], z[r−2]) for the two unit starts.
            let mut state = [[1.0, 0.0], [0.0, 1.0]];
            for row in start..start + rows {
                let [l1, l2] = self.forward[row];
                let mut response = [0.0; 2];
                for (value, [previous, before_previous]) in response.iter_mut().zip(&mut state) {
                    *value = -l2 * *before_previous - l1 * *previous;
                    *before_previous = *previous;
                    *previous = *value;
                }
                self.forward_homogeneous[row] = response;
            }
        }
        for block in 0..PARTITIONS - 1 {
            let end = prefix + (block + 1) * rows;
            let start = if block == 0 { 0 } else { end - rows };
            // (x[r+1], x[r+2]) for the two unit ends.
            let mut state = [[1.0, 0.0], [0.0, 1.0]];
            for row in (start..end).rev() {
                let [_, u1, u2] = self.backward[row];
                let mut response = [0.0; 2];
                for (value, [next, after_next]) in response.iter_mut().zip(&mut state) {
                    *value = -u2 * *after_next - u1 * *next;
                    *after_next = *next;
                    *next = *value;
                }
                self.backward_homogeneous[row] = response;
            }
        }
    }

    /// Solves `A x = rhs` in place (`solution` holds `rhs` on entry).
    pub fn solve_in_place(&self, solution: &mut [f64]) {
        if self.factors.half_bandwidth == 2 {
            self.solve_pentadiagonal(solution);
        } else {
            self.solve_general(solution);
        }
    }

    /// The plain solve for any bandwidth (the reference for the pentadiagonal fast path).
    pub fn solve_general(&self, solution: &mut [f64]) {
        let size = self.factors.size;
        let w = self.factors.half_bandwidth;
        let width = w + 1;
        let band = &self.factors.band[..size * width];
        let solution = &mut solution[..size];
        // Forward: L z = b. Row r of `band` holds L[r][r−1..r−w] at offsets 1..=w.
        for (row, entries) in band.chunks_exact(width).enumerate() {
            let reach = w.min(row);
            let mut value = solution[row];
            for (l, x) in entries[1..=reach]
                .iter()
                .zip(solution[row - reach..row].iter().rev())
            {
                value -= l * x;
            }
            solution[row] = value;
        }
        // Diagonal: D u = z.
        for (x, inverse) in solution.iter_mut().zip(&self.inverse_diagonal) {
            *x *= inverse;
        }
        // Backward: Lᵀ x = u, as column sweeps: once x[row] is final, remove it from the rows
        // above that it couples to.
        for (row, entries) in band.chunks_exact(width).enumerate().rev() {
            let reach = w.min(row);
            let x = solution[row];
            for (l, target) in entries[1..=reach]
                .iter()
                .zip(solution[row - reach..row].iter_mut().rev())
            {
                *target -= l * x;
            }
        }
    }
}

impl BandedLdlt {
    /// The same solve for half-bandwidth 2 (the string's step matrix, solved every time step).
    /// The sweeps are a serial dependency chain, so the coefficients come from the two
    /// sweep-ordered arrays, the diagonal scaling rides in the backward sweep, and each row
    /// subtracts the older neighbour first, so that only one multiply and one subtraction wait
    /// for the previous row.
    fn solve_pentadiagonal(&self, solution: &mut [f64]) {
        self.kernels.arch.dispatch(PentadiagonalSolve {
            factor: self,
            solution,
        });
    }

    /// [`BandedLdlt::solve_pentadiagonal`] on the vector unit of the enclosing dispatch.
    #[inline(always)]
    fn solve_pentadiagonal_inlined(&self, solution: &mut [f64]) {
        match partition(self.factors.size) {
            Some((prefix, rows)) => self.solve_partitioned(prefix, rows, solution),
            None => self.solve_serial(solution),
        }
    }

    /// The two sweeps as one chain each (row after row).
    #[inline(always)]
    fn solve_serial(&self, solution: &mut [f64]) {
        let size = self.factors.size;
        let solution = &mut solution[..size];
        let (mut previous, mut before_previous) = (0.0, 0.0);
        for (x, [l1, l2]) in solution.iter_mut().zip(&self.forward) {
            let value = (*x - l2 * before_previous) - l1 * previous;
            *x = value;
            before_previous = previous;
            previous = value;
        }
        // Backward: x[r] = z[r]/D[r] − L[r+1][r] x[r+1] − L[r+2][r] x[r+2].
        let (mut next, mut after_next) = (0.0, 0.0);
        for (x, [inverse, u1, u2]) in solution.iter_mut().zip(&self.backward).rev() {
            let value = (*x * inverse - u2 * after_next) - u1 * next;
            *x = value;
            after_next = next;
            next = value;
        }
    }

    /// The same sweeps as four chains at once. Each sweep is a linear recurrence of order two,
    /// so a block's values are its particular solution (the sweep started from zero) plus its
    /// homogeneous responses times the two true values it starts from. The four blocks' particular
    /// solutions run interleaved, four independent dependency chains instead of one four times as
    /// long; then the start values pass from block to block (two values each) and each block is
    /// fixed up in a pass with no chain. Same result as [`Self::solve_serial`] to round-off.
    #[inline(always)]
    fn solve_partitioned(&self, prefix: usize, rows: usize, solution: &mut [f64]) {
        let size = self.factors.size;
        let solution = &mut solution[..size];
        // Forward. The first block starts with the prefix rows (its true start, zero values).
        let mut previous = [0.0; PARTITIONS];
        let mut before_previous = [0.0; PARTITIONS];
        for (x, [l1, l2]) in solution[..prefix].iter_mut().zip(&self.forward) {
            let value = (*x - l2 * before_previous[0]) - l1 * previous[0];
            *x = value;
            before_previous[0] = previous[0];
            previous[0] = value;
        }
        {
            let (x0, rest) = solution[prefix..].split_at_mut(rows);
            let (x1, rest) = rest.split_at_mut(rows);
            let (x2, x3) = rest.split_at_mut(rows);
            let blocks = [x0, x1, x2, &mut x3[..rows]];
            let coefficients = &self.forward[prefix..prefix + PARTITIONS * rows];
            let (c0, rest) = coefficients.split_at(rows);
            let (c1, rest) = rest.split_at(rows);
            let (c2, c3) = rest.split_at(rows);
            let [x0, x1, x2, x3] = blocks;
            for i in 0..rows {
                let xs = [&mut x0[i], &mut x1[i], &mut x2[i], &mut x3[i]];
                let cs = [c0[i], c1[i], c2[i], c3[i]];
                for (chain, (x, [l1, l2])) in xs.into_iter().zip(cs).enumerate() {
                    let value = (*x - l2 * before_previous[chain]) - l1 * previous[chain];
                    *x = value;
                    before_previous[chain] = previous[chain];
                    previous[chain] = value;
                }
            }
        }
        for block in 1..PARTITIONS {
            let start = prefix + block * rows;
            let (done, block_rows) = solution.split_at_mut(start);
            let (last, before_last) = (done[start - 1], done[start - 2]);
            for (x, [g, h]) in block_rows[..rows]
                .iter_mut()
                .zip(&self.forward_homogeneous[start..start + rows])
            {
                *x += g * last + h * before_last;
            }
        }
        // Backward. The last block ends at the matrix's end (zero values there); the first
        // block's chain runs on through the prefix rows.
        let mut next = [0.0; PARTITIONS];
        let mut after_next = [0.0; PARTITIONS];
        {
            let (x0, rest) = solution[prefix..].split_at_mut(rows);
            let (x1, rest) = rest.split_at_mut(rows);
            let (x2, x3) = rest.split_at_mut(rows);
            let coefficients = &self.backward[prefix..prefix + PARTITIONS * rows];
            let (c0, rest) = coefficients.split_at(rows);
            let (c1, rest) = rest.split_at(rows);
            let (c2, c3) = rest.split_at(rows);
            let x3 = &mut x3[..rows];
            for i in (0..rows).rev() {
                let xs = [&mut x0[i], &mut x1[i], &mut x2[i], &mut x3[i]];
                let cs = [c0[i], c1[i], c2[i], c3[i]];
                for (chain, (x, [inverse, u1, u2])) in xs.into_iter().zip(cs).enumerate() {
                    let value = (*x * inverse - u2 * after_next[chain]) - u1 * next[chain];
                    *x = value;
                    after_next[chain] = next[chain];
                    next[chain] = value;
                }
            }
        }
        for (x, [inverse, u1, u2]) in solution[..prefix]
            .iter_mut()
            .zip(&self.backward[..prefix])
            .rev()
        {
            let value = (*x * inverse - u2 * after_next[0]) - u1 * next[0];
            *x = value;
            after_next[0] = next[0];
            next[0] = value;
        }
        for block in (0..PARTITIONS - 1).rev() {
            let end = prefix + (block + 1) * rows;
            let start = if block == 0 { 0 } else { end - rows };
            let (head, done) = solution.split_at_mut(end);
            let (first, second) = (done[0], done[1]);
            for (x, [g, h]) in head[start..]
                .iter_mut()
                .zip(&self.backward_homogeneous[start..end])
            {
                *x += g * first + h * second;
            }
        }
    }
}

/// The pentadiagonal solve compiled for the vector unit found at run time (AVX2 or AVX-512
/// where present, `pulp`'s dispatch) instead of the generic x86-64 target's SSE2: the same
/// operations in the same order (Rust never fuses a multiply and an add on its own), so the same
/// result bit for bit. A `-C target-cpu=native` build showed where this pays: the solve took a
/// fifth less time there; dispatched, the reference tier's step gained 2–5 %.
struct PentadiagonalSolve<'a> {
    factor: &'a BandedLdlt,
    solution: &'a mut [f64],
}

impl WithSimd for PentadiagonalSolve<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.factor.solve_pentadiagonal_inlined(self.solution);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A diagonally dominant symmetric test matrix with entries that differ everywhere.
    fn test_matrix(size: usize, w: usize) -> SymmetricBanded {
        let mut matrix = SymmetricBanded::zeros(size, w);
        for row in 0..size {
            matrix.set(row, row, 10.0 + row as f64 * 0.1);
            for offset in 1..=w.min(row) {
                matrix.set(
                    row,
                    row - offset,
                    1.0 / (1.0 + offset as f64 + 0.3 * row as f64),
                );
            }
        }
        matrix
    }

    #[test]
    fn solves_against_a_known_solution() {
        for w in 1..=4 {
            let size = 23;
            let matrix = test_matrix(size, w);
            let exact: Vec<f64> = (0..size).map(|i| (i as f64 * 0.7).sin() + 0.1).collect();
            let mut rhs = vec![0.0; size];
            matrix.multiply(&exact, &mut rhs);
            let mut ldlt = BandedLdlt::with_shape(size, w);
            ldlt.factorise(&matrix).unwrap();
            ldlt.solve_in_place(&mut rhs);
            for (x, e) in rhs.iter().zip(&exact) {
                assert!((x - e).abs() < 1e-13, "w={w}: {x} vs {e}");
            }
        }
    }

    #[test]
    fn pentadiagonal_fast_path_equals_the_general_solve() {
        let matrix = test_matrix(57, 2);
        let mut ldlt = BandedLdlt::with_shape(57, 2);
        ldlt.factorise(&matrix).unwrap();
        let rhs: Vec<f64> = (0..57).map(|i| (i as f64 * 1.3).cos()).collect();
        let (mut fast, mut general) = (rhs.clone(), rhs);
        ldlt.solve_in_place(&mut fast);
        ldlt.solve_general(&mut general);
        for (a, b) in fast.iter().zip(&general) {
            assert!((a - b).abs() <= 1e-15 * b.abs().max(1.0), "{a} vs {b}");
        }
    }

    /// Every split of the rows into the partitioned solve's blocks (each remainder, the smallest
    /// partitioned size, the string's 199 rows), and sizes too small to partition, against the
    /// general solve on a matrix like the string's (strongly coupled, slowly decaying responses).
    #[test]
    fn partitioned_solve_equals_the_general_solve() {
        for size in (5..=40).chain([57, 99, 199]) {
            let mut matrix = SymmetricBanded::zeros(size, 2);
            for row in 0..size {
                matrix.set(row, row, 1.0 + 6.0 * 0.3 + 0.01 * (row % 7) as f64);
                if row >= 1 {
                    matrix.set(row, row - 1, -4.0 * 0.3);
                }
                if row >= 2 {
                    matrix.set(row, row - 2, 0.3);
                }
            }
            let mut ldlt = BandedLdlt::with_shape(size, 2);
            ldlt.factorise(&matrix).unwrap();
            let rhs: Vec<f64> = (0..size).map(|i| (i as f64 * 1.3).cos() + 0.2).collect();
            let (mut fast, mut general) = (rhs.clone(), rhs);
            ldlt.solve_in_place(&mut fast);
            ldlt.solve_general(&mut general);
            let scale = general.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (row, (a, b)) in fast.iter().zip(&general).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-13 * scale,
                    "size {size}, row {row}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn multiply_matches_dense_product_by_hand() {
        // [[2,1,0],[1,3,4],[0,4,5]] · [1,2,3] = [4, 19, 23]
        let mut matrix = SymmetricBanded::zeros(3, 1);
        matrix.set(0, 0, 2.0);
        matrix.set(1, 1, 3.0);
        matrix.set(2, 2, 5.0);
        matrix.set(1, 0, 1.0);
        matrix.set(2, 1, 4.0);
        let mut output = [0.0; 3];
        matrix.multiply(&[1.0, 2.0, 3.0], &mut output);
        assert_eq!(output, [4.0, 19.0, 23.0]);
    }

    #[test]
    fn indefinite_matrix_is_reported_not_factorised() {
        let mut matrix = SymmetricBanded::zeros(2, 1);
        matrix.set(0, 0, 1.0);
        matrix.set(1, 1, 1.0);
        matrix.set(1, 0, 2.0);
        let mut ldlt = BandedLdlt::with_shape(2, 1);
        assert_eq!(ldlt.factorise(&matrix), Err(NotPositiveDefinite { row: 1 }));
    }

    #[test]
    fn narrow_matrix_copies_into_wider_band() {
        let narrow = test_matrix(9, 2);
        let mut wide = SymmetricBanded::zeros(9, 3);
        wide.copy_from(&narrow);
        for row in 0..9 {
            for column in 0..9 {
                assert_eq!(wide.get(row, column), narrow.get(row, column));
            }
        }
    }
}
