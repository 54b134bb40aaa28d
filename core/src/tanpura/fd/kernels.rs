//! The FD step's passes over the whole string, as SIMD kernels dispatched at run time.
//!
//! Three loops of the step (seed 000, eq. 14–16, 22) run over all N + 1 nodes:
//!
//! - the right-hand side of the contact-free predictor, `A s = −2(D yⁿ − d_b − qⁿ)`, i.e.
//!   `r_m = 2qⁿ_m − (Δt²/2ρA) g_m` with the restoring force `g = K y − b` of `operator.rs`
//!   (`g_m = −T c_m + EI (c_{m−1} − 2c_m + c_{m+1})/Δx²`, `c_m = δxx y_m`, `c_0 = c_N = 0`);
//! - the contact correction `s ← s + f_j A⁻¹ e_j` (`condensed.rs`), one per forced node;
//! - the state update `yⁿ⁺¹ = yⁿ + s`, `qⁿ⁺¹ = s − qⁿ` (eq. 16) with the finiteness check;
//!
//! and one over every barrier point (`barrier_grid.rs`): the gaps `a_i = y_barrier(x_i) − (I y)_i`
//! before the step (eq. 17), computed run by run of points that share a stencil, so that the four
//! node values are broadcast and the weights read by column.
//!
//! Each is a [`pulp::WithSimd`] kernel: [`pulp::Arch`] picks AVX-512, AVX2+FMA or scalar code
//! once, so the generic x86-64 binary uses the widest unit present, as the modal tier's
//! `modal/lanes.rs` does. The vectors are not padded; each kernel ends with a scalar tail.
//! Stencil neighbours are read through shifted (unaligned) slices, so the loops have no index
//! juggling. The multiply-adds may be fused where the unit has FMA: results then differ from
//! the scalar path at round-off, and the same machine always takes the same path
//! (deterministic renders).

pub use crate::simd::Kernels;
use pulp::{Simd, WithSimd};

/// A run `start..end` of barrier points whose interpolation stencils all start at `first_node`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StencilSegment {
    pub first_node: usize,
    pub start: usize,
    pub end: usize,
}

impl Kernels {
    /// `y ← y + a x` over the common length.
    pub fn axpy(&self, a: f64, x: &[f64], y: &mut [f64]) {
        self.arch.dispatch(Axpy { a, x, y });
    }

    /// The predictor's right-hand side on the interior nodes of full-node vectors:
    /// `rhs_m = 2 q_m − force_scale_twice · g_m` (m = 1..N−1), `rhs_0 = rhs_N = 0`, with
    /// `g = K y − b` from the curvature stencil (`operator.rs`). `curvature` is scratch of
    /// the full-node length.
    #[allow(clippy::too_many_arguments)]
    pub fn predictor_rhs(
        &self,
        displacement: &[f64],
        scaled_momentum: &[f64],
        inverse_dx2: f64,
        tension_n: f64,
        bending_over_dx2: f64,
        force_scale_twice: f64,
        curvature: &mut [f64],
        rhs: &mut [f64],
    ) {
        self.arch.dispatch(PredictorRhs {
            y: displacement,
            q: scaled_momentum,
            inverse_dx2,
            tension_n,
            bending_over_dx2,
            force_scale_twice,
            curvature,
            rhs,
        });
    }

    /// `gaps_i = heights_i − Σ_j weights[j]_i · values[first_node + j]` for the points of every
    /// segment (full-node `values`).
    pub fn barrier_gaps(
        &self,
        heights: &[f64],
        weights: [&[f64]; 4],
        segments: &[StencilSegment],
        values: &[f64],
        gaps: &mut [f64],
    ) {
        self.arch.dispatch(BarrierGaps {
            heights,
            weights,
            segments,
            values,
            gaps,
        });
    }

    /// `y ← y + s`, `q ← s − q` on the interior nodes 1..N−1; returns whether every `s` was
    /// finite.
    pub fn advance_state(
        &self,
        step: &[f64],
        displacement: &mut [f64],
        momentum: &mut [f64],
    ) -> bool {
        self.arch.dispatch(AdvanceState {
            s: step,
            y: displacement,
            q: momentum,
        })
    }
}

struct Axpy<'a> {
    a: f64,
    x: &'a [f64],
    y: &'a mut [f64],
}

impl WithSimd for Axpy<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let length = self.x.len().min(self.y.len());
        let (x_lanes, x_tail) = S::as_simd_f64s(&self.x[..length]);
        let (y_lanes, y_tail) = S::as_mut_simd_f64s(&mut self.y[..length]);
        let a = simd.splat_f64s(self.a);
        for (y, x) in y_lanes.iter_mut().zip(x_lanes) {
            *y = simd.mul_add_e_f64s(a, *x, *y);
        }
        for (y, x) in y_tail.iter_mut().zip(x_tail) {
            *y += self.a * x;
        }
    }
}

struct BarrierGaps<'a> {
    heights: &'a [f64],
    weights: [&'a [f64]; 4],
    segments: &'a [StencilSegment],
    values: &'a [f64],
    gaps: &'a mut [f64],
}

impl WithSimd for BarrierGaps<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        for segment in self.segments {
            let range = segment.start..segment.end;
            let y = &self.values[segment.first_node..segment.first_node + 4];
            let (h_lanes, h_tail) = S::as_simd_f64s(&self.heights[range.clone()]);
            let (w0_lanes, w0_tail) = S::as_simd_f64s(&self.weights[0][range.clone()]);
            let (w1_lanes, w1_tail) = S::as_simd_f64s(&self.weights[1][range.clone()]);
            let (w2_lanes, w2_tail) = S::as_simd_f64s(&self.weights[2][range.clone()]);
            let (w3_lanes, w3_tail) = S::as_simd_f64s(&self.weights[3][range.clone()]);
            let (out_lanes, out_tail) = S::as_mut_simd_f64s(&mut self.gaps[range]);
            let (y0, y1) = (simd.splat_f64s(y[0]), simd.splat_f64s(y[1]));
            let (y2, y3) = (simd.splat_f64s(y[2]), simd.splat_f64s(y[3]));
            let lanes = out_lanes
                .iter_mut()
                .zip(h_lanes)
                .zip(w0_lanes.iter().zip(w1_lanes))
                .zip(w2_lanes.iter().zip(w3_lanes));
            for (((out, h), (w0, w1)), (w2, w3)) in lanes {
                let mut sum = simd.mul_f64s(*w0, y0);
                sum = simd.mul_add_e_f64s(*w1, y1, sum);
                sum = simd.mul_add_e_f64s(*w2, y2, sum);
                sum = simd.mul_add_e_f64s(*w3, y3, sum);
                *out = simd.sub_f64s(*h, sum);
            }
            let tail = out_tail
                .iter_mut()
                .zip(h_tail)
                .zip(w0_tail.iter().zip(w1_tail))
                .zip(w2_tail.iter().zip(w3_tail));
            for (((out, h), (w0, w1)), (w2, w3)) in tail {
                *out = h - (w0 * y[0] + w1 * y[1] + w2 * y[2] + w3 * y[3]);
            }
        }
    }
}

struct PredictorRhs<'a> {
    y: &'a [f64],
    q: &'a [f64],
    inverse_dx2: f64,
    tension_n: f64,
    bending_over_dx2: f64,
    force_scale_twice: f64,
    curvature: &'a mut [f64],
    rhs: &'a mut [f64],
}

impl WithSimd for PredictorRhs<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let nodes = self.y.len();
        let n = nodes - 1;
        let (y, c) = (self.y, &mut self.curvature[..nodes]);
        // c_m = (y_{m+1} − 2 y_m + y_{m−1}) / Δx², m = 1..N−1; c_0 = c_N = 0.
        c[0] = 0.0;
        c[n] = 0.0;
        {
            let (after, centre, before) = (&y[2..=n], &y[1..n], &y[..n - 1]);
            let out = &mut c[1..n];
            let (out_lanes, out_tail) = S::as_mut_simd_f64s(out);
            let (a_lanes, a_tail) = S::as_simd_f64s(after);
            let (m_lanes, m_tail) = S::as_simd_f64s(centre);
            let (b_lanes, b_tail) = S::as_simd_f64s(before);
            let scale = simd.splat_f64s(self.inverse_dx2);
            let two = simd.splat_f64s(2.0);
            for (((out, a), m), b) in out_lanes.iter_mut().zip(a_lanes).zip(m_lanes).zip(b_lanes) {
                let second = simd.sub_f64s(simd.add_f64s(*a, *b), simd.mul_f64s(two, *m));
                *out = simd.mul_f64s(second, scale);
            }
            for (((out, a), m), b) in out_tail.iter_mut().zip(a_tail).zip(m_tail).zip(b_tail) {
                *out = (a + b - 2.0 * m) * self.inverse_dx2;
            }
        }
        // g_m = −T c_m + (EI/Δx²)(c_{m−1} − 2c_m + c_{m+1}); rhs_m = 2 q_m − F₂ g_m.
        let rhs = &mut self.rhs[..nodes];
        rhs[0] = 0.0;
        rhs[n] = 0.0;
        let (after, centre, before) = (&c[2..=n], &c[1..n], &c[..n - 1]);
        let q = &self.q[1..n];
        let (out_lanes, out_tail) = S::as_mut_simd_f64s(&mut rhs[1..n]);
        let (a_lanes, a_tail) = S::as_simd_f64s(after);
        let (m_lanes, m_tail) = S::as_simd_f64s(centre);
        let (b_lanes, b_tail) = S::as_simd_f64s(before);
        let (q_lanes, q_tail) = S::as_simd_f64s(q);
        let (tension, bending) = (self.tension_n, self.bending_over_dx2);
        let minus_tension = simd.splat_f64s(-tension);
        let bending_lanes = simd.splat_f64s(bending);
        let two = simd.splat_f64s(2.0);
        let minus_scale = simd.splat_f64s(-self.force_scale_twice);
        let lanes = out_lanes
            .iter_mut()
            .zip(a_lanes)
            .zip(m_lanes)
            .zip(b_lanes)
            .zip(q_lanes);
        for ((((out, a), m), b), q) in lanes {
            let second = simd.sub_f64s(simd.add_f64s(*a, *b), simd.mul_f64s(two, *m));
            let force =
                simd.mul_add_e_f64s(minus_tension, *m, simd.mul_f64s(bending_lanes, second));
            *out = simd.mul_add_e_f64s(minus_scale, force, simd.mul_f64s(two, *q));
        }
        let tail = out_tail
            .iter_mut()
            .zip(a_tail)
            .zip(m_tail)
            .zip(b_tail)
            .zip(q_tail);
        for ((((out, a), m), b), q) in tail {
            let force = -tension * m + bending * (a + b - 2.0 * m);
            *out = 2.0 * q - self.force_scale_twice * force;
        }
    }
}

struct AdvanceState<'a> {
    s: &'a [f64],
    y: &'a mut [f64],
    q: &'a mut [f64],
}

impl WithSimd for AdvanceState<'_> {
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> bool {
        let n = self.s.len() - 1;
        let s = &self.s[1..n];
        let (s_lanes, s_tail) = S::as_simd_f64s(s);
        let (y_lanes, y_tail) = S::as_mut_simd_f64s(&mut self.y[1..n]);
        let (q_lanes, q_tail) = S::as_mut_simd_f64s(&mut self.q[1..n]);
        // s · 0 is 0 for every finite s and NaN otherwise: one sum tells whether all were.
        let zero = simd.splat_f64s(0.0);
        let mut probe = zero;
        for ((s, y), q) in s_lanes.iter().zip(y_lanes).zip(q_lanes) {
            *y = simd.add_f64s(*y, *s);
            *q = simd.sub_f64s(*s, *q);
            probe = simd.add_f64s(probe, simd.mul_f64s(*s, zero));
        }
        let mut finite = simd.reduce_sum_f64s(probe) == 0.0;
        for ((s, y), q) in s_tail.iter().zip(y_tail).zip(q_tail) {
            *y += s;
            *q = s - *q;
            finite &= s.is_finite();
        }
        finite
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_match_the_scalar_formulas() {
        let kernels = Kernels::detect();
        let n = 23;
        let y: Vec<f64> = (0..=n).map(|m| (m as f64 * 0.7).sin() * 1e-3).collect();
        let q: Vec<f64> = (0..=n).map(|m| (m as f64 * 0.3).cos() * 1e-6).collect();
        let (inverse_dx2, tension, bending, scale) = (4.0, 30.0, 0.5, 1e-3);
        let mut curvature = vec![0.0; n + 1];
        let mut rhs = vec![9.0; n + 1];
        kernels.predictor_rhs(
            &y,
            &q,
            inverse_dx2,
            tension,
            bending,
            scale,
            &mut curvature,
            &mut rhs,
        );
        let c = |m: usize| {
            if m == 0 || m == n {
                0.0
            } else {
                (y[m + 1] - 2.0 * y[m] + y[m - 1]) * inverse_dx2
            }
        };
        assert_eq!((rhs[0], rhs[n]), (0.0, 0.0));
        for m in 1..n {
            let g = -tension * c(m) + bending * (c(m - 1) - 2.0 * c(m) + c(m + 1));
            let expected = 2.0 * q[m] - scale * g;
            // Round-off relative to the terms that cancel (FMA may be used or not).
            let terms = 2.0 * q[m].abs()
                + scale
                    * (tension * c(m).abs()
                        + bending * (c(m - 1).abs() + 2.0 * c(m).abs() + c(m + 1).abs()));
            assert!((rhs[m] - expected).abs() <= 1e-14 * terms, "{m}");
        }

        let mut target = q.clone();
        kernels.axpy(2.5, &y, &mut target);
        for m in 0..=n {
            assert!((target[m] - (q[m] + 2.5 * y[m])).abs() <= 1e-18);
        }

        let (mut y2, mut q2) = (y.clone(), q.clone());
        let mut s = rhs.clone();
        assert!(kernels.advance_state(&s, &mut y2, &mut q2));
        for m in 1..n {
            assert_eq!(y2[m], y[m] + s[m]);
            assert_eq!(q2[m], s[m] - q[m]);
        }
        assert_eq!((y2[0], y2[n]), (y[0], y[n]));
        s[5] = f64::INFINITY;
        assert!(!kernels.advance_state(&s, &mut y2, &mut q2));
        s[5] = 0.0;
        s[n - 1] = f64::NAN;
        assert!(!kernels.advance_state(&s, &mut y2, &mut q2));
    }
}
