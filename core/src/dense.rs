//! Cholesky factorisation of small dense symmetric positive definite matrices, allocation-free
//! after construction.
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
}
