//! Cholesky factorisation of small dense symmetric positive definite matrices, allocation-free
//! after construction, the eigen-decomposition of small symmetric matrices by Jacobi rotations,
//! and the few leading eigenpairs of a symmetric positive semi-definite one by subspace iteration
//! (the modal string's residual modes, `tanpura/modal/points.rs`).
//!
//! Both tanpura discretisations solve a small SPD system per Newton update on the contact region:
//! the FD tiers the Schur complement of the step matrix on the ~14 contact nodes
//! (`tanpura/fd/condensed.rs`), the modal tiers `I + D G D` on the points that touch
//! (`tanpura/modal/solve.rs`). The matrices are at most a few dozen rows, built and factorised on
//! the audio thread every step, so a hand-written loop that reuses its buffer is right where a
//! linear-algebra crate would allocate its workspace or cost more in dispatch than the
//! arithmetic.

use crate::banded::NotPositiveDefinite;

/// Cholesky factorisation of a small dense SPD matrix (row-major), allocation-free after
/// construction.
#[derive(Debug, Clone)]
pub struct DenseCholesky {
    size: usize,
    lower: Vec<f64>,
    inverse_diagonal: Vec<f64>,
}

impl DenseCholesky {
    /// Room for matrices up to `capacity × capacity`. Allocates.
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            size: 0,
            lower: vec![0.0; capacity * capacity],
            inverse_diagonal: vec![0.0; capacity],
        }
    }

    /// Factorises the leading `size × size` row-major matrix `matrix = L Lᵀ`.
    pub fn factorise(&mut self, matrix: &[f64], size: usize) -> Result<(), NotPositiveDefinite> {
        self.size = size;
        let lower = &mut self.lower[..size * size];
        for row in 0..size {
            for column in 0..=row {
                let (above, from_row) = lower.split_at_mut(row * size);
                let row_entries = &from_row[..column];
                let column_entries: &[f64] = if column == row {
                    row_entries
                } else {
                    &above[column * size..column * size + column]
                };
                let dot: f64 = row_entries
                    .iter()
                    .zip(column_entries)
                    .map(|(a, b)| a * b)
                    .sum();
                let value = matrix[row * size + column] - dot;
                if row == column {
                    if value.is_nan() || value <= 0.0 {
                        return Err(NotPositiveDefinite { row });
                    }
                    let root = value.sqrt();
                    from_row[column] = root;
                    self.inverse_diagonal[row] = 1.0 / root;
                } else {
                    from_row[column] = value * self.inverse_diagonal[column];
                }
            }
        }
        Ok(())
    }

    /// Solves `M x = rhs` in place for the last factorised matrix.
    pub fn solve_in_place(&self, solution: &mut [f64]) {
        let size = self.size;
        let lower = &self.lower[..size * size];
        let solution = &mut solution[..size];
        for (row, entries) in lower.chunks_exact(size).enumerate() {
            let dot: f64 = entries[..row]
                .iter()
                .zip(&solution[..row])
                .map(|(l, x)| l * x)
                .sum();
            solution[row] = (solution[row] - dot) * self.inverse_diagonal[row];
        }
        for (row, entries) in lower.chunks_exact(size).enumerate().rev() {
            let x = solution[row] * self.inverse_diagonal[row];
            solution[row] = x;
            for (l, target) in entries[..row].iter().zip(&mut solution[..row]) {
                *target -= l * x;
            }
        }
    }
}

/// The eigenvalues and eigenvectors of the symmetric `size × size` matrix in `matrix` (row-major,
/// row stride `stride`), by cyclic Jacobi rotations: on return the diagonal of `matrix` holds the
/// eigenvalues and column j of `vectors` (same layout) the unit eigenvector of the j-th. Each
/// rotation zeroes one off-diagonal pair exactly (the rotation of Golub & Van Loan, §8.5, with
/// the smaller of the two angles), so the off-diagonal mass falls quadratically once small;
/// sweeps stop when it is below 1e-30 of the matrix's squared norm, after at most 30.
/// Allocation-free: for the few dozen contact points of the modal string, on every retune.
pub fn symmetric_eigen_jacobi(matrix: &mut [f64], vectors: &mut [f64], size: usize, stride: usize) {
    for i in 0..size {
        for j in 0..size {
            vectors[i * stride + j] = if i == j { 1.0 } else { 0.0 };
        }
    }
    let norm_squared: f64 = (0..size)
        .flat_map(|i| (0..size).map(move |j| (i, j)))
        .map(|(i, j)| matrix[i * stride + j] * matrix[i * stride + j])
        .sum();
    for _ in 0..30 {
        let off: f64 = (0..size)
            .flat_map(|i| (0..i).map(move |j| (i, j)))
            .map(|(i, j)| 2.0 * matrix[i * stride + j] * matrix[i * stride + j])
            .sum();
        if off <= 1e-30 * norm_squared || !off.is_finite() {
            return;
        }
        for p in 0..size {
            for q in p + 1..size {
                let apq = matrix[p * stride + q];
                if apq == 0.0 {
                    continue;
                }
                let (app, aqq) = (matrix[p * stride + p], matrix[q * stride + q]);
                let theta = (aqq - app) / (2.0 * apq);
                // signum(0) = 1: equal diagonals rotate by π/4.
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..size {
                    let (akp, akq) = (matrix[k * stride + p], matrix[k * stride + q]);
                    matrix[k * stride + p] = c * akp - s * akq;
                    matrix[k * stride + q] = s * akp + c * akq;
                }
                for k in 0..size {
                    let (apk, aqk) = (matrix[p * stride + k], matrix[q * stride + k]);
                    matrix[p * stride + k] = c * apk - s * aqk;
                    matrix[q * stride + k] = s * apk + c * aqk;
                }
                for k in 0..size {
                    let (vkp, vkq) = (vectors[k * stride + p], vectors[k * stride + q]);
                    vectors[k * stride + p] = c * vkp - s * vkq;
                    vectors[k * stride + q] = s * vkp + c * vkq;
                }
            }
        }
    }
}

/// The largest block of subspace iteration [`leading_eigenpairs`] runs (the wanted pairs and two
/// guards).
pub const LEADING_BLOCK_CAPACITY: usize = 10;
/// Iterations [`leading_eigenpairs`] runs before it gives up.
const LEADING_MAX_ITERATIONS: usize = 40;
/// [`leading_eigenpairs`] stops when every wanted Ritz pair's residual `‖A x − θ x‖` is below this
/// fraction of the largest Ritz value.
const LEADING_TOLERANCE: f64 = 1e-12;

/// The `wanted` largest eigenvalues of the symmetric positive semi-definite `size × size` matrix
/// `matrix` (row-major, row stride `stride`; not modified) into `values`, largest first, and
/// their unit eigenvectors into the columns of `vectors` (same layout), each signed so that its
/// largest entry in magnitude is positive. `work` needs `2 · size · LEADING_BLOCK_CAPACITY`
/// entries. Returns `false` (and leaves the outputs unspecified) when the iteration does not
/// converge, when `wanted + 2` exceeds [`LEADING_BLOCK_CAPACITY`] or a third of `size`, or for a
/// non-finite matrix: the caller then decomposes the whole matrix ([`symmetric_eigen_jacobi`]).
///
/// Subspace iteration with Rayleigh–Ritz (Golub & Van Loan, §8.2.4; Saad, *Numerical Methods for
/// Large Eigenvalue Problems*, ch. 5) on a block of `p = wanted + 2` vectors started from the
/// columns of the matrix with the largest diagonal entries: each iteration orthonormalises the
/// block V (modified Gram–Schmidt, twice), forms W = A V and the p × p projection H = Vᵀ W,
/// diagonalises H by Jacobi rotations (H = Y Θ Yᵀ), and takes the Ritz vectors X = V Y with
/// A X = W Y. The wanted pairs' residuals fall as `(λ_{p+1}/λ_wanted)^k`; the next block is A X.
/// Deterministic (the start depends on the matrix only) and allocation-free. For the modal
/// string's ~24 contact points and two residual modes it costs a few hundred dot products of
/// length 24 where the whole decomposition costs several sweeps of O(size³) rotations.
pub fn leading_eigenpairs(
    matrix: &[f64],
    size: usize,
    stride: usize,
    wanted: usize,
    values: &mut [f64],
    vectors: &mut [f64],
    work: &mut [f64],
) -> bool {
    let block = wanted + 2;
    // A block of more than a third of the matrix converges slowly (the wanted values are no
    // longer well separated from the rest) and costs as much as the whole decomposition.
    if wanted == 0 || block > LEADING_BLOCK_CAPACITY || 3 * block > size {
        return false;
    }
    let entry = |i: usize, j: usize| matrix[i * stride + j];
    // Columns of V and W are stored contiguously: V[:, c] = basis[c * size..(c + 1) * size].
    let (basis, image) = work[..2 * size * block].split_at_mut(size * block);
    // Start: the columns of the matrix at its `block` largest diagonal entries (ties: first).
    let mut taken = [usize::MAX; LEADING_BLOCK_CAPACITY];
    for c in 0..block {
        let column = (0..size)
            .filter(|i| !taken[..c].contains(i))
            .fold(None, |best: Option<usize>, i| match best {
                Some(b) if entry(b, b) >= entry(i, i) => Some(b),
                _ => Some(i),
            })
            .expect("block ≤ size");
        taken[c] = column;
        for i in 0..size {
            basis[c * size + i] = entry(i, column);
        }
    }
    let mut projection = [0.0; LEADING_BLOCK_CAPACITY * LEADING_BLOCK_CAPACITY];
    let mut rotation = [0.0; LEADING_BLOCK_CAPACITY * LEADING_BLOCK_CAPACITY];
    let mut ritz = [0.0; LEADING_BLOCK_CAPACITY];
    let mut order = [0usize; LEADING_BLOCK_CAPACITY];
    for _ in 0..LEADING_MAX_ITERATIONS {
        // Orthonormalise V; a column that collapses is replaced by the first unit vector that
        // survives (the block then still spans `block` directions).
        for c in 0..block {
            let mut replacement = 0;
            loop {
                let start_norm = norm(&basis[c * size..(c + 1) * size]);
                for _ in 0..2 {
                    for d in 0..c {
                        let (done, rest) = basis.split_at_mut(c * size);
                        let previous = &done[d * size..(d + 1) * size];
                        let column = &mut rest[..size];
                        let overlap = dot(previous, column);
                        for (x, p) in column.iter_mut().zip(previous) {
                            *x -= overlap * p;
                        }
                    }
                }
                let column = &mut basis[c * size..(c + 1) * size];
                let length = norm(column);
                if !length.is_finite() {
                    return false;
                }
                if length > 1e-8 * start_norm && length > 0.0 {
                    column.iter_mut().for_each(|x| *x /= length);
                    break;
                }
                if replacement == size {
                    return false;
                }
                column.iter_mut().for_each(|x| *x = 0.0);
                column[replacement] = 1.0;
                replacement += 1;
            }
        }
        // W = A V, H = Vᵀ W.
        for c in 0..block {
            let column = &basis[c * size..(c + 1) * size];
            for i in 0..size {
                image[c * size + i] = dot(&matrix[i * stride..i * stride + size], column);
            }
        }
        for a in 0..block {
            for b in 0..=a {
                let value = 0.5
                    * (dot(
                        &basis[a * size..(a + 1) * size],
                        &image[b * size..(b + 1) * size],
                    ) + dot(
                        &basis[b * size..(b + 1) * size],
                        &image[a * size..(a + 1) * size],
                    ));
                projection[a * LEADING_BLOCK_CAPACITY + b] = value;
                projection[b * LEADING_BLOCK_CAPACITY + a] = value;
            }
        }
        symmetric_eigen_jacobi(
            &mut projection,
            &mut rotation,
            block,
            LEADING_BLOCK_CAPACITY,
        );
        for (c, value) in ritz[..block].iter_mut().enumerate() {
            *value = projection[c * LEADING_BLOCK_CAPACITY + c];
        }
        for (c, slot) in order[..block].iter_mut().enumerate() {
            *slot = c;
        }
        order[..block].sort_by(|&a, &b| ritz[b].total_cmp(&ritz[a]));
        let largest = ritz[order[0]].abs();
        // The wanted Ritz pairs and their residuals, x = V y and A x = W y.
        let mut converged = true;
        for (rank, &c) in order[..wanted].iter().enumerate() {
            let theta = ritz[c];
            let mut residual = 0.0;
            for i in 0..size {
                let (mut x, mut ax) = (0.0, 0.0);
                for k in 0..block {
                    let y = rotation[k * LEADING_BLOCK_CAPACITY + c];
                    x += basis[k * size + i] * y;
                    ax += image[k * size + i] * y;
                }
                vectors[i * stride + rank] = x;
                residual += (ax - theta * x) * (ax - theta * x);
            }
            values[rank] = theta;
            converged &= residual.sqrt() <= LEADING_TOLERANCE * largest;
        }
        if converged {
            for rank in 0..wanted {
                let column = (0..size).map(|i| vectors[i * stride + rank]);
                let (mut peak, mut sign) = (0.0, 1.0);
                for x in column {
                    if x.abs() > peak {
                        (peak, sign) = (x.abs(), x.signum());
                    }
                }
                let length = (0..size)
                    .map(|i| vectors[i * stride + rank].powi(2))
                    .sum::<f64>()
                    .sqrt();
                for i in 0..size {
                    vectors[i * stride + rank] *= sign / length;
                }
            }
            return true;
        }
        // The next block: A X (the Ritz vectors' images, all `block` of them).
        for c in 0..block {
            for i in 0..size {
                basis[c * size + i] = (0..block)
                    .map(|k| image[k * size + i] * rotation[k * LEADING_BLOCK_CAPACITY + order[c]])
                    .sum();
            }
        }
    }
    false
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_cholesky_solves_a_known_system() {
        // [[4,2,0],[2,5,1],[0,1,3]] x = [2, 7, 7] has x = [0, 1, 2].
        let matrix = [4.0, 2.0, 0.0, 2.0, 5.0, 1.0, 0.0, 1.0, 3.0];
        let mut factor = DenseCholesky::with_capacity(3);
        factor.factorise(&matrix, 3).unwrap();
        let mut x = [2.0, 7.0, 7.0];
        factor.solve_in_place(&mut x);
        for (value, expected) in x.iter().zip([0.0, 1.0, 2.0]) {
            assert!((value - expected).abs() < 1e-14);
        }
    }

    /// A · v = λ v for every eigenpair of a random symmetric matrix, with orthonormal vectors.
    #[test]
    fn jacobi_gives_the_eigenpairs_of_a_symmetric_matrix() {
        let size = 9;
        let stride = 11;
        let entry = |i: usize, j: usize| {
            ((i * 7 + j * 7 + i * j) as f64 * 0.37).sin() + if i == j { 2.0 } else { 0.0 }
        };
        let mut matrix = vec![0.0; stride * stride];
        for i in 0..size {
            for j in 0..size {
                matrix[i * stride + j] = entry(i.min(j), i.max(j));
            }
        }
        let original = matrix.clone();
        let mut vectors = vec![0.0; stride * stride];
        symmetric_eigen_jacobi(&mut matrix, &mut vectors, size, stride);
        for j in 0..size {
            let lambda = matrix[j * stride + j];
            for i in 0..size {
                let product: f64 = (0..size)
                    .map(|k| original[i * stride + k] * vectors[k * stride + j])
                    .sum();
                assert!(
                    (product - lambda * vectors[i * stride + j]).abs() < 1e-12,
                    "pair {j}, row {i}"
                );
            }
            for l in 0..size {
                let dot: f64 = (0..size)
                    .map(|k| vectors[k * stride + j] * vectors[k * stride + l])
                    .sum();
                let expected = if j == l { 1.0 } else { 0.0 };
                assert!((dot - expected).abs() < 1e-12);
            }
        }
    }

    /// A positive semi-definite matrix `Q diag(λ) Qᵀ` with the spectrum `spectrum` (Q from the
    /// eigenvectors of a fixed symmetric matrix), row stride `stride`.
    fn with_spectrum(spectrum: &[f64], stride: usize) -> Vec<f64> {
        let size = spectrum.len();
        let mut scratch = vec![0.0; stride * stride];
        for i in 0..size {
            for j in 0..size {
                let (a, b) = (i.min(j), i.max(j));
                scratch[i * stride + j] = ((a * 5 + b * 3 + a * b) as f64 * 0.61).cos();
            }
        }
        let mut basis = vec![0.0; stride * stride];
        symmetric_eigen_jacobi(&mut scratch, &mut basis, size, stride);
        let mut matrix = vec![0.0; stride * stride];
        for i in 0..size {
            for j in 0..size {
                matrix[i * stride + j] = (0..size)
                    .map(|k| basis[i * stride + k] * spectrum[k] * basis[j * stride + k])
                    .sum();
            }
        }
        matrix
    }

    /// The leading pairs of subspace iteration are the whole decomposition's, to round-off, with
    /// the largest entry of each vector positive; a spectrum shaped like the modal string's
    /// residual compliance (two near-equal leading values, then a pair a third as large).
    #[test]
    fn subspace_iteration_finds_the_leading_eigenpairs() {
        let spectrum = [
            6.0e-5, 1.6e-5, 5.6e-5, 8.5e-6, 1.5e-5, 6.5e-6, 3e-6, 1e-6, 0.0, 2e-7, 4e-6, 1e-8,
            5e-7, 3e-7, 1e-7, 8e-8, 5e-8, 2e-8, 1e-9, 0.0,
        ];
        let (size, stride) = (spectrum.len(), 22);
        let matrix = with_spectrum(&spectrum, stride);
        for wanted in 1..=4 {
            let mut values = [0.0; 4];
            let mut vectors = vec![0.0; stride * stride];
            let mut work = vec![0.0; 2 * size * LEADING_BLOCK_CAPACITY];
            assert!(leading_eigenpairs(
                &matrix,
                size,
                stride,
                wanted,
                &mut values,
                &mut vectors,
                &mut work
            ));
            let mut sorted = spectrum;
            sorted.sort_by(|a, b| b.total_cmp(a));
            for rank in 0..wanted {
                assert!(
                    (values[rank] - sorted[rank]).abs() < 1e-12 * sorted[0],
                    "{wanted}: {values:?}"
                );
                let column: Vec<f64> = (0..size).map(|i| vectors[i * stride + rank]).collect();
                let peak = column.iter().copied().fold(
                    0.0,
                    |m: f64, x| {
                        if x.abs() > m.abs() {
                            x
                        } else {
                            m
                        }
                    },
                );
                assert!(peak > 0.0);
                for i in 0..size {
                    let product: f64 = (0..size).map(|k| matrix[i * stride + k] * column[k]).sum();
                    assert!((product - values[rank] * column[i]).abs() < 1e-11 * sorted[0]);
                }
            }
        }
        // Too many pairs for the block, or for the matrix: the caller's whole decomposition.
        let mut work = vec![0.0; 2 * size * LEADING_BLOCK_CAPACITY];
        let mut vectors = vec![0.0; stride * stride];
        let mut values = [0.0; 20];
        assert!(!leading_eigenpairs(
            &matrix,
            size,
            stride,
            9,
            &mut values,
            &mut vectors,
            &mut work
        ));
        assert!(!leading_eigenpairs(
            &matrix,
            11,
            stride,
            2,
            &mut values,
            &mut vectors,
            &mut work
        ));
    }
}
