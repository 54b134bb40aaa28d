//! Eigenvalues of a transfer matrix and their reading as subharmonics (seed 001, section 2.3–2.4).
//!
//! An eigenvalue `μ = |μ| e^{iθ}` of the one-period transfer matrix multiplies its perturbation
//! pattern by `|μ|` per period and advances its phase by θ. When `θ/2π ≈ k/n` the pattern repeats
//! after n periods: an n-th subharmonic (order 1, phase 0, is the "unsubharmonic" of section 2.2).

use super::StabilityError;
use faer::complex::Complex;

/// Largest subharmonic order [`subharmonic_order`] looks for.
pub const MAX_SUBHARMONIC_ORDER: u32 = 64;

/// How far `θ/2π` may lie from `k/n` and still be read as an n-th subharmonic. Table II's
/// 0.2479 (a fourth subharmonic damped by torsion) is 0.0021 away from 1/4.
pub const SUBHARMONIC_PHASE_TOLERANCE: f64 = 0.01;

/// One eigenvalue of a transfer matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eigenvalue {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
    /// Modulus |μ|: growth factor of its pattern per period.
    pub modulus: f64,
    /// Phase θ/2π in (−0.5, 0.5].
    pub phase_over_2pi: f64,
    /// The n of the n-th subharmonic this phase stands for (see [`subharmonic_order`]).
    pub subharmonic_order: u32,
}

impl Eigenvalue {
    /// Reads modulus, phase and subharmonic order off a complex eigenvalue.
    pub fn from_complex(re: f64, im: f64) -> Self {
        let modulus = re.hypot(im);
        let mut phase_over_2pi = im.atan2(re) / std::f64::consts::TAU;
        // atan2 returns −π for a negative real number with a −0.0 imaginary part.
        if phase_over_2pi <= -0.5 {
            phase_over_2pi += 1.0;
        }
        Self {
            re,
            im,
            modulus,
            phase_over_2pi,
            subharmonic_order: subharmonic_order(phase_over_2pi),
        }
    }
}

/// The subharmonic order of a phase θ/2π: the smallest n ≤ [`MAX_SUBHARMONIC_ORDER`] for which
/// some k/n lies within [`SUBHARMONIC_PHASE_TOLERANCE`] of it; failing that, the n of the
/// closest k/n.
pub fn subharmonic_order(phase_over_2pi: f64) -> u32 {
    let distance = |order: u32| {
        let multiple = phase_over_2pi * f64::from(order);
        (multiple - multiple.round()).abs() / f64::from(order)
    };
    (1..=MAX_SUBHARMONIC_ORDER)
        .find(|&order| distance(order) <= SUBHARMONIC_PHASE_TOLERANCE)
        .unwrap_or_else(|| {
            (1..=MAX_SUBHARMONIC_ORDER)
                .min_by(|a, b| distance(*a).total_cmp(&distance(*b)))
                .unwrap_or(1)
        })
}

/// All eigenvalues of `matrix`, sorted by decreasing modulus; within a conjugate pair the one
/// with the positive phase comes first.
pub fn spectrum(matrix: &faer::Mat<f64>) -> Result<Vec<Eigenvalue>, StabilityError> {
    let values: Vec<Complex<f64>> = matrix
        .eigenvalues()
        .map_err(|error| StabilityError::EigenSolver(format!("{error:?}")))?;
    let mut eigenvalues: Vec<Eigenvalue> = values
        .iter()
        .map(|value| Eigenvalue::from_complex(value.re, value.im))
        .collect();
    sort_by_decreasing_modulus(&mut eigenvalues);
    Ok(eigenvalues)
}

/// Sorts by decreasing modulus; within a run of moduli equal to rounding (conjugate pairs,
/// the repeated eigenvalues of the space-time formulation) by decreasing phase.
pub fn sort_by_decreasing_modulus(eigenvalues: &mut [Eigenvalue]) {
    eigenvalues.sort_by(|a, b| b.modulus.total_cmp(&a.modulus));
    let mut run_start = 0;
    for index in 1..=eigenvalues.len() {
        let run_ends = index == eigenvalues.len() || {
            let (previous, current) = (eigenvalues[index - 1].modulus, eigenvalues[index].modulus);
            previous - current > 1e-12 * previous
        };
        if run_ends {
            eigenvalues[run_start..index]
                .sort_by(|a, b| b.phase_over_2pi.total_cmp(&a.phase_over_2pi));
            run_start = index;
        }
    }
}

/// The largest modulus among the eigenvalues of `matrix`.
pub fn spectral_radius(matrix: &faer::Mat<f64>) -> Result<f64, StabilityError> {
    Ok(spectrum(matrix)?
        .first()
        .map_or(0.0, |eigenvalue| eigenvalue.modulus))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_of_simple_fractions() {
        assert_eq!(subharmonic_order(0.0), 1);
        assert_eq!(subharmonic_order(0.5), 2);
        assert_eq!(subharmonic_order(-0.3333), 3);
        assert_eq!(subharmonic_order(0.2479), 4);
        assert_eq!(subharmonic_order(0.4), 5);
        assert_eq!(subharmonic_order(3.0 / 7.0), 7);
    }

    #[test]
    fn phase_of_a_negative_real_is_one_half() {
        let eigenvalue = Eigenvalue::from_complex(-0.5, -0.0);
        assert_eq!(eigenvalue.phase_over_2pi, 0.5);
        assert_eq!(eigenvalue.subharmonic_order, 2);
        assert_eq!(eigenvalue.modulus, 0.5);
    }

    #[test]
    fn rotation_matrix_spectrum() {
        // A rotation by 2π/3 scaled by 0.9: a damped third subharmonic pair.
        let angle = std::f64::consts::TAU / 3.0;
        let matrix = faer::Mat::from_fn(2, 2, |row, column| {
            0.9 * match (row, column) {
                (0, 0) | (1, 1) => angle.cos(),
                (0, 1) => -angle.sin(),
                _ => angle.sin(),
            }
        });
        let eigenvalues = spectrum(&matrix).unwrap();
        assert!((eigenvalues[0].modulus - 0.9).abs() < 1e-14);
        assert!((eigenvalues[0].phase_over_2pi - 1.0 / 3.0).abs() < 1e-14);
        assert!((eigenvalues[1].phase_over_2pi + 1.0 / 3.0).abs() < 1e-14);
        assert_eq!(eigenvalues[0].subharmonic_order, 3);
    }
}
