//! Cholesky factorisation of small dense symmetric positive definite matrices, allocation-free
//! after construction, and the eigen-decomposition of small symmetric matrices by Jacobi
//! rotations (the modal string's residual modes, `tanpura/modal/points.rs`).
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
}
