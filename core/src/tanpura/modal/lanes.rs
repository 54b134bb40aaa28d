//! The loops over the modes, as SIMD kernels dispatched at run time.
//!
//! The modal step (`docs/modal-tanpura.md`, eq. M1) spends its time in two passes over the
//! contiguous mode arrays: the free motion of every contact point `Δu_i = Ψ_i · s` (one dot
//! product per point), and the update that adds the contact forces, advances the state,
//! forms the nut force and computes the next step's free step `s = a p − b r` in the
//! same pass, so that a step stores only r, p and s. (The free step alone, [`Kernels::free_step`],
//! is needed only after the state is set from outside.) Each pass is a [`pulp::WithSimd`] kernel:
//! [`pulp::Arch`] picks AVX-512, AVX2+FMA or scalar code once per process from the CPU, so the one
//! generic x86-64 binary runs the widest unit the machine has (pulp comes with faer, so it adds
//! nothing to the build). The kernels are generic over [`Real`] (f32 for the fast tier, f64 for
//! the plain reference path); every array is padded to a multiple of [`LANE_PADDING`] elements
//! with zeros, so no kernel has a tail on any instruction set.
//!
//! Hand-written rather than a linear-algebra crate: the vectors are about a hundred long, the
//! calls happen once per sample on the audio thread, and a BLAS call would cost more in dispatch
//! and bounds checks than the arithmetic (and some allocate). The dot products keep eight
//! independent accumulators so that the multiply-add latency is hidden.
//!
//! Determinism: the same machine always takes the same path and the same summation order, so a
//! render is bit-identical run to run; two machines with different vector units may differ at
//! round-off.

use super::ModalString;
pub use crate::simd::Kernels;
use pulp::{Simd, WithSimd};
use std::fmt::Debug;

/// Mode arrays are padded to a multiple of this many elements: two registers of 16 f32 lanes
/// (AVX-512), so that every kernel sees whole register pairs on every instruction set.
pub const LANE_PADDING: usize = 32;

/// `count` modes rounded up to whole [`LANE_PADDING`] blocks: the length every kernel runs over.
pub fn padded_lanes(count: usize) -> usize {
    count.div_ceil(LANE_PADDING) * LANE_PADDING
}

/// A floating-point type the mode kernels run in.
pub trait Real: Copy + Default + Debug + PartialEq + Send + Sync + 'static {
    /// The SIMD register of this type for the instruction set `S`.
    type Lanes<S: Simd>: Copy;

    fn from_f64(value: f64) -> Self;
    fn to_f64(self) -> f64;
    /// The slice as registers (its length is a multiple of [`LANE_PADDING`]).
    fn lanes<S: Simd>(slice: &[Self]) -> &[Self::Lanes<S>];
    fn lanes_mut<S: Simd>(slice: &mut [Self]) -> &mut [Self::Lanes<S>];
    fn splat<S: Simd>(simd: S, value: Self) -> Self::Lanes<S>;
    fn add<S: Simd>(simd: S, a: Self::Lanes<S>, b: Self::Lanes<S>) -> Self::Lanes<S>;
    fn sub<S: Simd>(simd: S, a: Self::Lanes<S>, b: Self::Lanes<S>) -> Self::Lanes<S>;
    fn mul<S: Simd>(simd: S, a: Self::Lanes<S>, b: Self::Lanes<S>) -> Self::Lanes<S>;
    /// `a b + c`, fused where the unit has FMA.
    fn mul_add<S: Simd>(
        simd: S,
        a: Self::Lanes<S>,
        b: Self::Lanes<S>,
        c: Self::Lanes<S>,
    ) -> Self::Lanes<S>;
    fn sum<S: Simd>(simd: S, a: Self::Lanes<S>) -> Self;

    /// [`ModalString::step`] for this type: compiled once, in this crate. The step is generic
    /// over the type, and a generic function is compiled again in every crate that calls it
    /// (each example, test and tool built with optimisation); this non-generic function in the
    /// type's implementation is the one they all call instead.
    fn step_string(string: &mut ModalString<Self>);
    /// [`ModalString::step_into`] for this type, compiled once as [`Real::step_string`] is.
    fn step_string_into(string: &mut ModalString<Self>, output: &mut [f32], nut_weight: f64);
}

macro_rules! impl_real {
    ($ty:ty, $lanes:ident, $as:ident, $as_mut:ident, $splat:ident, $add:ident, $sub:ident,
     $mul:ident, $fma:ident, $sum:ident) => {
        impl Real for $ty {
            type Lanes<S: Simd> = S::$lanes;

            #[inline(always)]
            fn from_f64(value: f64) -> Self {
                value as $ty
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn lanes<S: Simd>(slice: &[Self]) -> &[Self::Lanes<S>] {
                let (lanes, tail) = S::$as(slice);
                debug_assert!(tail.is_empty(), "mode arrays are padded to whole registers");
                lanes
            }
            #[inline(always)]
            fn lanes_mut<S: Simd>(slice: &mut [Self]) -> &mut [Self::Lanes<S>] {
                let (lanes, tail) = S::$as_mut(slice);
                debug_assert!(tail.is_empty(), "mode arrays are padded to whole registers");
                lanes
            }
            #[inline(always)]
            fn splat<S: Simd>(simd: S, value: Self) -> Self::Lanes<S> {
                simd.$splat(value)
            }
            #[inline(always)]
            fn add<S: Simd>(simd: S, a: Self::Lanes<S>, b: Self::Lanes<S>) -> Self::Lanes<S> {
                simd.$add(a, b)
            }
            #[inline(always)]
            fn sub<S: Simd>(simd: S, a: Self::Lanes<S>, b: Self::Lanes<S>) -> Self::Lanes<S> {
                simd.$sub(a, b)
            }
            #[inline(always)]
            fn mul<S: Simd>(simd: S, a: Self::Lanes<S>, b: Self::Lanes<S>) -> Self::Lanes<S> {
                simd.$mul(a, b)
            }
            #[inline(always)]
            fn mul_add<S: Simd>(
                simd: S,
                a: Self::Lanes<S>,
                b: Self::Lanes<S>,
                c: Self::Lanes<S>,
            ) -> Self::Lanes<S> {
                simd.$fma(a, b, c)
            }
            #[inline(always)]
            fn sum<S: Simd>(simd: S, a: Self::Lanes<S>) -> Self {
                simd.$sum(a)
            }
            #[inline(never)]
            fn step_string(string: &mut ModalString<Self>) {
                string.dispatch_step();
            }
            #[inline(never)]
            fn step_string_into(
                string: &mut ModalString<Self>,
                output: &mut [f32],
                nut_weight: f64,
            ) {
                string.dispatch_step_into(output, nut_weight);
            }
        }
    };
}

impl_real!(
    f32,
    f32s,
    as_simd_f32s,
    as_mut_simd_f32s,
    splat_f32s,
    add_f32s,
    sub_f32s,
    mul_f32s,
    mul_add_e_f32s,
    reduce_sum_f32s
);
impl_real!(
    f64,
    f64s,
    as_simd_f64s,
    as_mut_simd_f64s,
    splat_f64s,
    add_f64s,
    sub_f64s,
    mul_f64s,
    mul_add_e_f64s,
    reduce_sum_f64s
);

/// The free step of every mode, `s = a p − b r` (eq. M1 without contact forces).
struct FreeStep<'a, T: Real> {
    a: &'a [T],
    b: &'a [T],
    r: &'a [T],
    p: &'a [T],
    s: &'a mut [T],
}

impl<T: Real> WithSimd for FreeStep<'_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let (a, b) = (T::lanes::<S>(self.a), T::lanes::<S>(self.b));
        let (r, p) = (T::lanes::<S>(self.r), T::lanes::<S>(self.p));
        let modes = T::lanes_mut::<S>(self.s)
            .iter_mut()
            .zip(a.iter().zip(b))
            .zip(r.iter().zip(p));
        for ((s, (a, b)), (r, p)) in modes {
            *s = T::sub(simd, T::mul(simd, *a, *p), T::mul(simd, *b, *r));
        }
    }
}

/// Four dot products with one vector, `[r0 · x, r1 · x, r2 · x, r3 · x]`: two accumulators per
/// row (even and odd registers), so that eight independent multiply-add chains hide the latency
/// and each load of x serves four rows. The rows are zipped with x, so no access needs a bounds
/// check.
#[inline(always)]
fn four_dots<T: Real, S: Simd>(simd: S, x: &[T::Lanes<S>], rows: [&[T::Lanes<S>]; 4]) -> [f64; 4] {
    let zero = T::splat(simd, T::default());
    let mut even = [zero; 4];
    let mut odd = [zero; 4];
    let pairs = x
        .chunks_exact(2)
        .zip(rows[0].chunks_exact(2))
        .zip(rows[1].chunks_exact(2))
        .zip(rows[2].chunks_exact(2))
        .zip(rows[3].chunks_exact(2));
    for ((((xk, a), b), c), d) in pairs {
        even[0] = T::mul_add(simd, a[0], xk[0], even[0]);
        even[1] = T::mul_add(simd, b[0], xk[0], even[1]);
        even[2] = T::mul_add(simd, c[0], xk[0], even[2]);
        even[3] = T::mul_add(simd, d[0], xk[0], even[3]);
        odd[0] = T::mul_add(simd, a[1], xk[1], odd[0]);
        odd[1] = T::mul_add(simd, b[1], xk[1], odd[1]);
        odd[2] = T::mul_add(simd, c[1], xk[1], odd[2]);
        odd[3] = T::mul_add(simd, d[1], xk[1], odd[3]);
    }
    // No closures here: a closure's body is compiled without the caller's target features, so
    // the vector operations inside it would become calls.
    let mut sums = [0.0; 4];
    for j in 0..4 {
        sums[j] = T::sum(simd, T::add(simd, even[j], odd[j])).to_f64();
    }
    sums
}

/// One dot product in the order of [`four_dots`] (even and odd registers apart).
#[inline(always)]
fn one_dot<T: Real, S: Simd>(simd: S, x: &[T::Lanes<S>], row: &[T::Lanes<S>]) -> f64 {
    let zero = T::splat(simd, T::default());
    let mut sums = [zero; 2];
    for (xk, a) in x.chunks_exact(2).zip(row.chunks_exact(2)) {
        sums[0] = T::mul_add(simd, a[0], xk[0], sums[0]);
        sums[1] = T::mul_add(simd, a[1], xk[1], sums[1]);
    }
    T::sum(simd, T::add(simd, sums[0], sums[1])).to_f64()
}

/// Dot products of several rows of a matrix with one vector: `out[j] = matrix[rows[j]] · x`,
/// or with `SCATTER`, `out[rows[j]] = matrix[rows[j]] · x`.
pub(super) struct Dots<'a, T: Real, const SCATTER: bool> {
    pub matrix: &'a [T],
    pub stride: usize,
    pub rows: &'a [usize],
    pub x: &'a [T],
    pub out: &'a mut [f64],
}

impl<T: Real, const SCATTER: bool> WithSimd for Dots<'_, T, SCATTER> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let length = self.x.len();
        let x = T::lanes::<S>(self.x);
        let row = |index: usize| {
            let start = index * self.stride;
            T::lanes::<S>(&self.matrix[start..start + length])
        };
        if SCATTER {
            let out = self.out;
            let mut rows = self.rows.chunks_exact(4);
            for indices in &mut rows {
                let rows = [
                    row(indices[0]),
                    row(indices[1]),
                    row(indices[2]),
                    row(indices[3]),
                ];
                let sums = four_dots::<T, S>(simd, x, rows);
                for (&index, sum) in indices.iter().zip(sums) {
                    out[index] = sum;
                }
            }
            for &index in rows.remainder() {
                out[index] = one_dot::<T, S>(simd, x, row(index));
            }
            return;
        }
        let mut rows = self.rows.chunks_exact(4);
        let mut outputs = self.out.chunks_exact_mut(4);
        for (indices, out) in (&mut rows).zip(&mut outputs) {
            let rows = [
                row(indices[0]),
                row(indices[1]),
                row(indices[2]),
                row(indices[3]),
            ];
            out.copy_from_slice(&four_dots::<T, S>(simd, x, rows));
        }
        for (&index, out) in rows.remainder().iter().zip(outputs.into_remainder()) {
            *out = one_dot::<T, S>(simd, x, row(index));
        }
    }
}

/// [`Dots`] of the first `out.len()` rows, walked in order without an index list (every
/// contact point's free step, each step): `out[j] = matrix[j] · x`, the same sums bit for bit.
pub(super) struct LeadingDots<'a, T: Real> {
    pub matrix: &'a [T],
    pub stride: usize,
    pub x: &'a [T],
    pub out: &'a mut [f64],
}

impl<T: Real> WithSimd for LeadingDots<'_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let (length, stride) = (self.x.len(), self.stride);
        let x = T::lanes::<S>(self.x);
        let count = self.out.len();
        let mut groups = self.matrix[..count * stride].chunks_exact(4 * stride);
        let mut outputs = self.out.chunks_exact_mut(4);
        for (group, out) in (&mut groups).zip(&mut outputs) {
            let (first, rest) = group.split_at(stride);
            let (second, rest) = rest.split_at(stride);
            let (third, fourth) = rest.split_at(stride);
            let rows = [
                T::lanes::<S>(&first[..length]),
                T::lanes::<S>(&second[..length]),
                T::lanes::<S>(&third[..length]),
                T::lanes::<S>(&fourth[..length]),
            ];
            out.copy_from_slice(&four_dots::<T, S>(simd, x, rows));
        }
        let rest = groups.remainder().chunks_exact(stride);
        for (row, out) in rest.zip(outputs.into_remainder()) {
            *out = one_dot::<T, S>(simd, x, T::lanes::<S>(&row[..length]));
        }
    }
}

/// Dot products of several rows of a matrix with two vectors:
/// `out_x[j] = matrix[rows[j]] · x`, `out_y[j] = matrix[rows[j]] · y`. Each row is read once for
/// both; every sum runs in the order of [`Dots`] (even and odd registers apart), so each result
/// equals the one [`Dots`] gives bit for bit.
struct DotsPair<'a, T: Real> {
    matrix: &'a [T],
    stride: usize,
    rows: &'a [usize],
    x: &'a [T],
    y: &'a [T],
    out_x: &'a mut [f64],
    out_y: &'a mut [f64],
}

impl<T: Real> WithSimd for DotsPair<'_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let length = self.x.len();
        let x = T::lanes::<S>(self.x);
        let y = &T::lanes::<S>(&self.y[..length])[..x.len()];
        let row = |index: usize| {
            let start = index * self.stride;
            T::lanes::<S>(&self.matrix[start..start + length])
        };
        let zero = T::splat(simd, T::default());
        // Two rows per pass: eight multiply-add chains (two rows, two vectors, even and odd).
        let mut rows = self.rows.chunks_exact(2);
        let mut out_x = self.out_x.chunks_exact_mut(2);
        let mut out_y = self.out_y.chunks_exact_mut(2);
        for ((indices, out_x), out_y) in (&mut rows).zip(&mut out_x).zip(&mut out_y) {
            let (r0, r1) = (row(indices[0]), row(indices[1]));
            let mut even = [zero; 4];
            let mut odd = [zero; 4];
            let pairs = x
                .chunks_exact(2)
                .zip(y.chunks_exact(2))
                .zip(r0.chunks_exact(2))
                .zip(r1.chunks_exact(2));
            for (((xk, yk), a), b) in pairs {
                even[0] = T::mul_add(simd, a[0], xk[0], even[0]);
                even[1] = T::mul_add(simd, b[0], xk[0], even[1]);
                even[2] = T::mul_add(simd, a[0], yk[0], even[2]);
                even[3] = T::mul_add(simd, b[0], yk[0], even[3]);
                odd[0] = T::mul_add(simd, a[1], xk[1], odd[0]);
                odd[1] = T::mul_add(simd, b[1], xk[1], odd[1]);
                odd[2] = T::mul_add(simd, a[1], yk[1], odd[2]);
                odd[3] = T::mul_add(simd, b[1], yk[1], odd[3]);
            }
            let total = |j: usize| T::sum(simd, T::add(simd, even[j], odd[j])).to_f64();
            out_x[0] = total(0);
            out_x[1] = total(1);
            out_y[0] = total(2);
            out_y[1] = total(3);
        }
        let remainder = rows
            .remainder()
            .iter()
            .zip(out_x.into_remainder())
            .zip(out_y.into_remainder());
        for ((&index, out_x), out_y) in remainder {
            let mut sums = [zero; 4];
            let pairs = x
                .chunks_exact(2)
                .zip(y.chunks_exact(2))
                .zip(row(index).chunks_exact(2));
            for ((xk, yk), a) in pairs {
                sums[0] = T::mul_add(simd, a[0], xk[0], sums[0]);
                sums[1] = T::mul_add(simd, a[1], xk[1], sums[1]);
                sums[2] = T::mul_add(simd, a[0], yk[0], sums[2]);
                sums[3] = T::mul_add(simd, a[1], yk[1], sums[3]);
            }
            *out_x = T::sum(simd, T::add(simd, sums[0], sums[1])).to_f64();
            *out_y = T::sum(simd, T::add(simd, sums[2], sums[3])).to_f64();
        }
    }
}

/// Rows of Ψ whose forces the fused update keeps in registers; further rows go through memory.
const REGISTER_ROWS: usize = 8;

/// Adds the contact forces to the free step, advances the state (eq. M1) and prepares the next
/// step, in one pass over the modes: `s += b Σ_j ΔF_j Ψ_j`, `r += s`, `p = s − p`, then the next
/// free step `s ← a p − b r`. Returns the nut force `c · r` after the step. The
/// modal force of the first [`REGISTER_ROWS`] rows never leaves the registers, so a pass stores
/// only r, p, the next free step and the whole step.
pub(super) struct AdvanceAndPrepare<'a, T: Real> {
    pub a: &'a [T],
    pub b: &'a [T],
    pub c: &'a [T],
    pub matrix: &'a [T],
    pub stride: usize,
    pub rows: &'a [usize],
    pub forces: &'a [T],
    /// The arrays' length: scratch for the rows beyond [`REGISTER_ROWS`] on entry, the whole
    /// step `s + b Σ_j ΔF_j Ψ_j` on return.
    pub work: &'a mut [T],
    pub s: &'a mut [T],
    pub r: &'a mut [T],
    pub p: &'a mut [T],
}

impl<T: Real> AdvanceAndPrepare<'_, T> {
    /// The pass with `ROWS` rows in registers (and, if `SPILLS`, the rest summed into `work`
    /// first). The row count is a constant so that the force sum unrolls and every slice has the
    /// registers' count as its length: no bounds check and no loop counter inside the pass. The
    /// nut force keeps one accumulator for the even registers and one for the odd.
    #[inline(always)]
    fn run<S: Simd, const ROWS: usize, const SPILLS: bool>(self, simd: S) -> f64 {
        let zero = T::splat(simd, T::default());
        let length = self.s.len();
        let s = T::lanes_mut::<S>(self.s);
        let registers = s.len();
        let shape = |row: usize| {
            let start = row * self.stride;
            &T::lanes::<S>(&self.matrix[start..start + length])[..registers]
        };
        let mut rows: [&[T::Lanes<S>]; ROWS] = [&[]; ROWS];
        let mut forces = [zero; ROWS];
        for j in 0..ROWS {
            rows[j] = shape(self.rows[j]);
            forces[j] = T::splat(simd, self.forces[j]);
        }
        let work = &mut T::lanes_mut::<S>(self.work)[..registers];
        if SPILLS {
            work.fill(zero);
            for (&row, force) in self.rows[ROWS..].iter().zip(&self.forces[ROWS..]) {
                let force = T::splat(simd, *force);
                for (sum, shape) in work.iter_mut().zip(shape(row)) {
                    *sum = T::mul_add(simd, *shape, force, *sum);
                }
            }
        }
        let a = &T::lanes::<S>(self.a)[..registers];
        let b = &T::lanes::<S>(self.b)[..registers];
        let c = &T::lanes::<S>(self.c)[..registers];
        let r = &mut T::lanes_mut::<S>(self.r)[..registers];
        let p = &mut T::lanes_mut::<S>(self.p)[..registers];
        // One register of modes, written out twice below (a closure would not inherit the
        // kernel's target features and would not be inlined).
        macro_rules! advance {
            ($v:expr, $nut:ident) => {{
                let v = $v;
                let mut force = if SPILLS { work[v] } else { zero };
                for j in 0..ROWS {
                    force = T::mul_add(simd, rows[j][v], forces[j], force);
                }
                let step = T::mul_add(simd, b[v], force, s[v]);
                work[v] = step;
                let displacement = T::add(simd, r[v], step);
                let velocity = T::sub(simd, step, p[v]);
                r[v] = displacement;
                p[v] = velocity;
                $nut = T::mul_add(simd, c[v], displacement, $nut);
                let next = T::sub(
                    simd,
                    T::mul(simd, a[v], velocity),
                    T::mul(simd, b[v], displacement),
                );
                s[v] = next;
            }};
        }
        let (mut nut_even, mut nut_odd) = (zero, zero);
        for pair in 0..registers / 2 {
            advance!(2 * pair, nut_even);
            advance!(2 * pair + 1, nut_odd);
        }
        T::sum(simd, T::add(simd, nut_even, nut_odd)).to_f64()
    }
}

impl<T: Real> WithSimd for AdvanceAndPrepare<'_, T> {
    type Output = f64;

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> f64 {
        match self.rows.len() {
            0 => self.run::<S, 0, false>(simd),
            1 => self.run::<S, 1, false>(simd),
            2 => self.run::<S, 2, false>(simd),
            3 => self.run::<S, 3, false>(simd),
            4 => self.run::<S, 4, false>(simd),
            5 => self.run::<S, 5, false>(simd),
            6 => self.run::<S, 6, false>(simd),
            7 => self.run::<S, 7, false>(simd),
            8 => self.run::<S, 8, false>(simd),
            _ => self.run::<S, REGISTER_ROWS, true>(simd),
        }
    }
}

impl Kernels {
    /// `s = a p − b r`.
    pub fn free_step<T: Real>(&self, a: &[T], b: &[T], r: &[T], p: &[T], s: &mut [T]) {
        self.arch.dispatch(FreeStep { a, b, r, p, s });
    }

    /// `out[j] = matrix[rows[j]] · x` for every listed row of the row-major `matrix` whose rows
    /// start `stride` elements apart (`x.len() ≤ stride`).
    pub fn dots<T: Real>(
        &self,
        matrix: &[T],
        stride: usize,
        rows: &[usize],
        x: &[T],
        out: &mut [f64],
    ) {
        debug_assert!(out.len() >= rows.len() && x.len() <= stride);
        self.arch.dispatch(Dots::<T, false> {
            matrix,
            stride,
            rows,
            x,
            out,
        });
    }

    /// `out[j] = matrix[j] · x` for the first `out.len()` rows of the row-major `matrix` whose
    /// rows start `stride` elements apart: [`Kernels::dots`] with the rows `0, 1, 2, …`, bit for
    /// bit, without the index list.
    pub fn leading_dots<T: Real>(&self, matrix: &[T], stride: usize, x: &[T], out: &mut [f64]) {
        debug_assert!(x.len() <= stride && matrix.len() >= out.len() * stride);
        self.arch.dispatch(LeadingDots {
            matrix,
            stride,
            x,
            out,
        });
    }

    /// `out_x[j] = matrix[rows[j]] · x` and `out_y[j] = matrix[rows[j]] · y`, each row read once;
    /// bit for bit what two calls of [`Kernels::dots`] give.
    #[allow(clippy::too_many_arguments)]
    pub fn dots_pair<T: Real>(
        &self,
        matrix: &[T],
        stride: usize,
        rows: &[usize],
        x: &[T],
        y: &[T],
        out_x: &mut [f64],
        out_y: &mut [f64],
    ) {
        debug_assert!(out_x.len() >= rows.len() && out_y.len() >= rows.len());
        debug_assert!(x.len() <= stride && y.len() >= x.len());
        self.arch.dispatch(DotsPair {
            matrix,
            stride,
            rows,
            x,
            y,
            out_x,
            out_y,
        });
    }

    /// `s += b Σ_j forces_j matrix[rows_j]`, `r += s`, `p = s − p`, then the next free step
    /// `s ← a p − b r`; returns `c · r` after the step. `work` (the arrays' length) holds
    /// the whole step `s + b Σ_j forces_j matrix[rows_j]` on return.
    #[allow(clippy::too_many_arguments)]
    pub fn advance_and_prepare<T: Real>(
        &self,
        a: &[T],
        b: &[T],
        c: &[T],
        matrix: &[T],
        stride: usize,
        rows: &[usize],
        forces: &[T],
        work: &mut [T],
        s: &mut [T],
        r: &mut [T],
        p: &mut [T],
    ) -> f64 {
        debug_assert!(forces.len() >= rows.len());
        self.arch.dispatch(AdvanceAndPrepare {
            a,
            b,
            c,
            matrix,
            stride,
            rows,
            forces,
            work,
            s,
            r,
            p,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn padded(values: impl Iterator<Item = f64>, length: usize) -> Vec<f64> {
        let mut v: Vec<f64> = values.take(length).collect();
        v.resize(length, 0.0);
        v
    }

    #[test]
    fn kernels_equal_the_plain_loops() {
        let kernels = Kernels::detect();
        let n = 48;
        let wave = |phase: f64| padded((0..).map(move |k| (k as f64 * 0.37 + phase).sin()), n);
        let (a, b, r, p, c) = (wave(0.1), wave(0.7), wave(1.3), wave(2.1), wave(2.9));
        let rows: Vec<Vec<f64>> = (0..11).map(|j| wave(0.5 * j as f64)).collect();
        let matrix: Vec<f64> = rows.concat();
        let all: Vec<usize> = (0..rows.len()).collect();

        let mut s = vec![0.0; n];
        kernels.free_step(&a, &b, &r, &p, &mut s);
        for k in 0..n {
            assert!((s[k] - (a[k] * p[k] - b[k] * r[k])).abs() < 1e-15);
        }
        let mut dots = vec![0.0; rows.len()];
        kernels.dots(&matrix, n, &all, &s, &mut dots);
        for (j, row) in rows.iter().enumerate() {
            let plain: f64 = row.iter().zip(&s).map(|(x, y)| x * y).sum();
            assert!((dots[j] - plain).abs() < 1e-13, "row {j}");
        }
        // The leading rows without an index list give the same sums bit for bit.
        for count in [1, 4, rows.len()] {
            let mut leading = vec![0.0; count];
            kernels.leading_dots(&matrix, n, &s, &mut leading);
            assert_eq!(leading, dots[..count]);
        }
        // The paired kernel gives each of the two dot products bit for bit, for an even and an
        // odd number of rows.
        let mut dots_r = vec![0.0; rows.len()];
        kernels.dots(&matrix, n, &all, &r, &mut dots_r);
        for count in [rows.len() - 1, rows.len()] {
            let (mut out_s, mut out_r) = (vec![0.0; count], vec![0.0; count]);
            kernels.dots_pair(&matrix, n, &all[..count], &s, &r, &mut out_s, &mut out_r);
            assert_eq!(out_s, dots[..count]);
            assert_eq!(out_r, dots_r[..count]);
        }

        // Three rows stay in registers; eleven spill the last three through memory.
        for count in [3, 11] {
            let forces: Vec<f64> = (0..count).map(|j| 0.3 - 0.17 * j as f64).collect();
            let (mut s2, mut r2, mut p2) = (s.clone(), r.clone(), p.clone());
            let mut whole = vec![0.0; n];
            let nut = kernels.advance_and_prepare(
                &a,
                &b,
                &c,
                &matrix,
                n,
                &all[..count],
                &forces,
                &mut whole,
                &mut s2,
                &mut r2,
                &mut p2,
            );
            let mut plain_nut = 0.0;
            for k in 0..n {
                let modal: f64 = (0..count).map(|j| forces[j] * rows[j][k]).sum();
                let step = s[k] + b[k] * modal;
                let (displacement, velocity) = (r[k] + step, step - p[k]);
                let next = a[k] * velocity - b[k] * displacement;
                assert!((whole[k] - step).abs() < 1e-13);
                assert!((r2[k] - displacement).abs() < 1e-13);
                assert!((p2[k] - velocity).abs() < 1e-13);
                assert!((s2[k] - next).abs() < 1e-13);
                plain_nut += c[k] * displacement;
            }
            assert!((nut - plain_nut).abs() < 1e-12, "{count} rows");
        }
    }

    #[test]
    fn single_precision_kernels_agree_to_single_precision() {
        let kernels = Kernels::detect();
        let n = 32;
        let x: Vec<f32> = (0..n).map(|k| (k as f32 * 0.3).cos()).collect();
        let row: Vec<f32> = (0..n).map(|k| (k as f32 * 0.11).sin()).collect();
        let mut out = [0.0];
        kernels.dots(&row, n, &[0], &x, &mut out);
        let plain: f64 = x.iter().zip(&row).map(|(a, b)| *a as f64 * *b as f64).sum();
        assert!((out[0] - plain).abs() < 1e-5);
    }
}
