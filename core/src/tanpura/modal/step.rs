//! The contact solve of one modal step (`docs/modal-tanpura.md`, section 4).
//!
//! With `Δu_free = Ψ s_free` and the coupling `G`, the points' step solves
//! `R(Δu) = Δu − Δu_free − G (F(Δu) − F_rest) = 0`, where F is the seed's mid-point force of
//! every point (eq. 4, `contact.rs`). Newton's Jacobian is `J = I + G C`, `C = diag(−∂F/∂Δu)`.
//! On the points A with `c_i > 0` the update solves `(I + D G_AA D) y = −D R_A`, `D = diag(√c_i)`,
//! then `δ = −R − G_{:,A} D y` for every point: the exact `δ = −J⁻¹ R`, through a symmetric
//! positive definite matrix whose eigenvalues are at least 1 (never ill-conditioned, however
//! close the points or stiff the contact). Residual and Jacobian are those of the full step, so
//! the accepted Δu satisfies the scheme to the tolerance and the energy balance (eq. M3) holds.
//! Stops when `max|δ| ≤ tolerance`, or exactly when an update leaves every point in the contact
//! case it had (the law is linear there); at the cap the last iterate is taken and counted.
//! When exactly one point enters or leaves contact at the evaluation point (its law is then
//! `P/s + Q s + K`, every other law linear), the update also solves the step exactly for those
//! contact cases: a second right-hand side through the same factors and one quadratic
//! (`ContactStep::finish_exactly`, derived in section 4), or, if the crossing case holds no root,
//! one linear equation in the case the point had before the step; if every other point then lies
//! in the case it was evaluated in, the step is exact and the iteration stops.
//!
//! **Which points Newton sees.** Only the *tracked* points, those within the tracking band of
//! contact or loaded at rest, take part; their state lives in compact arrays in slot order, with
//! their block of G, so Newton touches no index list and no other point. Every awake point's free
//! step `Ψ_i s_free` is computed each step (one dot product per point, in the mode kernels), so
//! every other (far) point's step is known exactly once the forces are, `Ψ_i s_free + Σ_j G_ij
//! ΔF_j`, and its gap follows it. Far points that the string's energy cannot carry into contact
//! before its next excitation sleep ([`ContactStep::sleep_far_points`]). One pass over all
//! points, in plain arrays the compiler vectorises, checks whether a far point would touch; if one
//! would, it joins and the solve is redone before anything moves, so the solve is exact for every
//! point.
//!
//! Up to eight tracked points (nearly every step), and up to sixteen, the iteration runs in
//! fixed lanes (`block.rs`), the same iterates bit for bit. The whole contact work of a step is
//! compiled for the machine's vector unit, inlined into the modal string's step
//! (`ContactStep::step`).
//!
//! Hand-written rather than on a linear-algebra crate: the systems are 1–12 points, solved once
//! or twice per sample on the audio thread; the fixed-size LDLᵀ of `solve.rs` is unrolled by the
//! compiler, and nothing here allocates.

use super::block::{
    contact_case, exact_crossing_step, lanes_of, Block, BlockState, CrossingPoint, BLOCK,
    WIDE_BLOCK,
};
use super::points::ContactPoints;
use super::solve::{ldl_factor_fixed, ldl_solve_in_place, ldl_substitute_fixed};
use crate::newton::NewtonSettings;
use crate::tanpura::contact::HuntCrossley;
use pulp::Simd;

/// The slot of a point that is not tracked.
const UNTRACKED: usize = usize::MAX;
/// A point sleeps only if its gap provably stays this far below contact (more than the tracking
/// band, so a sleeping point is never one that would be tracked).
const SLEEP_MARGIN_M: f64 = 10e-6;

/// Per-step state of the contact points; allocation-free after `new`.
#[derive(Debug, Clone)]
pub struct ContactStep {
    capacity: usize,
    /// The length of the per-slot arrays and the block's row stride: `capacity`, at least
    /// [`WIDE_BLOCK`], so that the fixed lanes' slots always exist.
    slot_stride: usize,
    /// a_i per point, m, after every step.
    pub gaps_m: Vec<f64>,
    /// 0 for an awake far point, −∞ for a tracked or a sleeping one: added to a gap, it keeps
    /// every test on far points from selecting any other point.
    far_offsets_m: Vec<f64>,
    /// `Ψ_i s_free` per point, m.
    point_free_steps_m: Vec<f64>,
    /// 1 for an awake point, 0 for a sleeping one (see [`ContactStep::sleep_far_points`]), and
    /// the awake points in order.
    awake: Vec<f64>,
    awake_points: Vec<usize>,
    awake_count: usize,
    /// This step's `Σ_j G_ij ΔF_j` per point, m.
    coupled_m: Vec<f64>,
    /// Every point's gap after the step at the last forces (the tracked points' are replaced
    /// by Newton's), formed with the test for far points that would touch; and whether a far
    /// point then lies within the tracking band.
    next_gaps_m: Vec<f64>,
    far_point_near: bool,
    /// Each point's slot among the tracked, or [`UNTRACKED`].
    slots: Vec<usize>,
    /// The tracked points (point indices), in slot order.
    tracked: Vec<usize>,
    count: usize,
    // Per slot: the gap before the step, the free step Ψ_i s_free, the iterate Δu_i, the last
    // accepted Δu − Δu_free (the next step's initial guess), the rest force and the law.
    gaps: Vec<f64>,
    free_steps: Vec<f64>,
    steps: Vec<f64>,
    corrections: Vec<f64>,
    rest_forces: Vec<f64>,
    /// The law of each slot, ξ and ψ apart (so that the law runs over the slots in vectors).
    xis: Vec<f64>,
    psis: Vec<f64>,
    /// F, c = −∂F/∂Δu and F − F_rest at the last evaluation.
    forces: Vec<f64>,
    stiffnesses: Vec<f64>,
    changes: Vec<f64>,
    /// Slots with F ≠ F_rest at the last evaluation.
    loaded: Vec<usize>,
    loaded_count: usize,
    /// G on the tracked points, with row stride `slot_stride`; zero in every row and column of
    /// a slot past the tracked ones (see [`ContactStep::clear_slot`]).
    block: Vec<f64>,
    /// Its first [`BLOCK`] and [`WIDE_BLOCK`] rows and columns, for the solve in fixed lanes.
    block_lanes: Block<BLOCK>,
    wide_block_lanes: Box<Block<WIDE_BLOCK>>,
    /// Whether every solve takes the general path (for the test that the two agree).
    #[cfg(test)]
    general_path_only: bool,
    residual: Vec<f64>,
    /// The slots with c > 0 at the last evaluation and their √c.
    active: Vec<usize>,
    roots: Vec<f64>,
    matrix: Vec<f64>,
    solution: Vec<f64>,
    scratch: Vec<f64>,
    /// The exact finish (see [`ContactStep::finish_exactly`]): `D y'` on the active points, the
    /// direction `w = J⁻¹ G e_c` and the candidate steps.
    second_solution: Vec<f64>,
    crossing_direction: Vec<f64>,
    candidate: Vec<f64>,
    /// The loaded points as point indices and their F − F_rest, N: what the modes feel.
    loaded_points: Vec<usize>,
    loaded_changes_n: Vec<f64>,
}

/// What one step's contact work (`ContactStep::step`) reports.
#[derive(Debug, Clone, Copy)]
pub struct ContactOutcome {
    /// Newton updates, and whether the last met the tolerance.
    pub iterations: u32,
    pub converged: bool,
    /// The contact damping's loss over the step, J (0 unless asked for).
    pub damping_loss_j: f64,
    /// The deepest penetration of the tracked points after the step (0 if none), m.
    pub penetration_m: f64,
}

/// The per-point arrays of [`far_points_after_step`].
struct FarPoints<'a> {
    gaps_m: &'a [f64],
    /// 0 for an awake far point, −∞ for a tracked or a sleeping one.
    offsets_m: &'a [f64],
    free_steps_m: &'a [f64],
    coupled_m: &'a [f64],
    /// 1 for an awake point, 0 for a sleeping one.
    awake: &'a [f64],
}

/// Every point's gap after the step, `a − (Ψ_i s_free + Σ_j G_ij ΔF_j)` (a sleeping point's
/// frozen), into `next_gaps_m`, in one pass with the two tests on far points: whether one would
/// touch during the step, and whether one then lies within `band_m` of contact.
#[inline(always)]
fn far_points_after_step(far: FarPoints, next_gaps_m: &mut [f64], band_m: f64) -> (bool, bool) {
    let (mut touches, mut near) = (false, false);
    let inputs = far
        .gaps_m
        .iter()
        .zip(far.offsets_m)
        .zip(far.free_steps_m.iter().zip(far.coupled_m).zip(far.awake));
    for (next, ((&gap, &offset), ((&free_step, &coupled), &awake))) in
        next_gaps_m.iter_mut().zip(inputs)
    {
        let step = free_step + coupled;
        touches |= (gap + offset) - step > 0.0;
        *next = gap - step * awake;
        near |= *next + offset > -band_m;
    }
    (touches, near)
}

/// `target[i] = row[i] · scale`.
#[inline(always)]
fn scaled(target: &mut [f64], row: &[f64], scale: f64) {
    for (t, &g) in target.iter_mut().zip(row) {
        *t = g * scale;
    }
}

/// `target[i] += row[i] · scale`.
#[inline(always)]
fn add_scaled(target: &mut [f64], row: &[f64], scale: f64) {
    for (t, &g) in target.iter_mut().zip(row) {
        *t += g * scale;
    }
}

impl ContactStep {
    /// Room for `capacity` points. Allocates.
    pub fn new(capacity: usize) -> Self {
        let zeros = || vec![0.0; capacity];
        let slot_stride = capacity.max(WIDE_BLOCK);
        let slot_zeros = || vec![0.0; slot_stride];
        Self {
            capacity,
            slot_stride,
            gaps_m: zeros(),
            far_offsets_m: zeros(),
            point_free_steps_m: zeros(),
            awake: vec![1.0; capacity],
            awake_points: (0..capacity).collect(),
            awake_count: 0,
            coupled_m: zeros(),
            next_gaps_m: zeros(),
            far_point_near: false,
            slots: vec![UNTRACKED; capacity],
            tracked: vec![0; capacity],
            count: 0,
            gaps: slot_zeros(),
            free_steps: slot_zeros(),
            steps: slot_zeros(),
            corrections: slot_zeros(),
            rest_forces: slot_zeros(),
            xis: slot_zeros(),
            psis: slot_zeros(),
            forces: slot_zeros(),
            stiffnesses: slot_zeros(),
            changes: slot_zeros(),
            loaded: vec![0; slot_stride],
            loaded_count: 0,
            block: vec![0.0; slot_stride * slot_stride],
            block_lanes: [[0.0; BLOCK]; BLOCK],
            wide_block_lanes: Box::new([[0.0; WIDE_BLOCK]; WIDE_BLOCK]),
            #[cfg(test)]
            general_path_only: false,
            residual: slot_zeros(),
            active: vec![0; slot_stride],
            roots: slot_zeros(),
            matrix: vec![0.0; slot_stride * slot_stride],
            solution: slot_zeros(),
            scratch: slot_zeros(),
            second_solution: slot_zeros(),
            crossing_direction: slot_zeros(),
            candidate: slot_zeros(),
            loaded_points: vec![0; capacity],
            loaded_changes_n: zeros(),
        }
    }

    /// Where the first `count` points' free steps `Ψ_i s_free` go (every step, before
    /// [`ContactStep::solve`]) when every point is awake, or `None`.
    pub fn point_free_steps_mut(&mut self, count: usize) -> Option<&mut [f64]> {
        (self.awake_count == count).then_some(&mut self.point_free_steps_m[..count])
    }

    /// The awake points, and the free steps by point, where the awake points' go (the sleeping
    /// points' stay 0).
    pub fn awake_rows(&mut self) -> (&[usize], &mut [f64]) {
        (
            &self.awake_points[..self.awake_count],
            &mut self.point_free_steps_m,
        )
    }

    /// How many points are awake.
    pub fn awake_count(&self) -> usize {
        self.awake_count
    }

    /// Whether point i is awake.
    pub fn is_awake(&self, i: usize) -> bool {
        self.awake[i] != 0.0
    }

    /// Puts to sleep every far point that cannot touch before the string is next excited from
    /// outside: one with no force at rest, not tracked, and `‖Ψ_i‖ reach < −a_rest,i − margin`,
    /// where `reach` bounds `‖r̃‖` until then. (With the vibration energy H_v, which no step
    /// increases (eq. M3), `‖r̃‖² ≤ 2 H_v`, so `|Ψ_i r̃| ≤ ‖Ψ_i‖ √(2 H_v)` and the point's gap
    /// `a_rest,i − Ψ_i r̃` stays below −margin.) A sleeping point's free step is not computed, its
    /// gap is frozen and it never joins; [`ContactStep::classify`], which every change of the
    /// state from outside ends in, wakes every point.
    pub fn sleep_far_points(&mut self, points: &ContactPoints, shape_norms: &[f64], reach: f64) {
        let mut changed = false;
        for i in 0..points.len() {
            let asleep = self.awake[i] != 0.0
                && self.slots[i] == UNTRACKED
                && points.rest_forces_n[i] == 0.0
                && shape_norms[i] * reach < -points.rest_gaps_m[i] - SLEEP_MARGIN_M;
            if asleep {
                self.awake[i] = 0.0;
                self.far_offsets_m[i] = f64::NEG_INFINITY;
                self.point_free_steps_m[i] = 0.0;
                changed = true;
            }
        }
        if changed {
            self.awake_count = 0;
            for i in 0..points.len() {
                if self.awake[i] != 0.0 {
                    self.awake_points[self.awake_count] = i;
                    self.awake_count += 1;
                }
            }
        }
    }

    pub fn tracked_count(&self) -> usize {
        self.count
    }

    /// The points with F ≠ F_rest after the last solve and their F − F_rest, N.
    pub fn loaded(&self) -> (&[usize], &[f64]) {
        (
            &self.loaded_points[..self.loaded_count],
            &self.loaded_changes_n[..self.loaded_count],
        )
    }

    /// Tracks the points whose gap lies within `band_m` of contact or that carry a force at rest,
    /// from scratch. Every gap in `gaps_m` must be exact on entry. Forgets the initial guesses.
    pub fn classify(&mut self, points: &ContactPoints, band_m: f64) {
        // Every slot becomes neutral again (the slots past the tracked ones already are).
        for slot in 0..self.count {
            self.slots[self.tracked[slot]] = UNTRACKED;
            self.clear_slot(slot);
            self.copy_block_lanes(slot);
        }
        self.count = 0;
        self.awake_count = points.len();
        for i in 0..points.len() {
            self.awake[i] = 1.0;
            self.awake_points[i] = i;
            self.far_offsets_m[i] = 0.0;
            if self.gaps_m[i] > -band_m || points.rest_forces_n[i] != 0.0 {
                self.track(points, i, self.gaps_m[i], 0.0, 0.0);
            }
        }
        self.loaded_count = 0;
    }

    /// Forgets Newton's initial guesses (a new excitation starts as on a fresh string).
    pub fn forget_corrections(&mut self) {
        self.corrections[..self.count].fill(0.0);
    }

    /// Starts tracking point i with gap `gap`, free step `free_step` and initial correction
    /// `correction`: a new slot at the end, and its row and column of the block.
    fn track(
        &mut self,
        points: &ContactPoints,
        i: usize,
        gap: f64,
        free_step: f64,
        correction: f64,
    ) {
        let slot = self.count;
        self.count += 1;
        self.slots[i] = slot;
        self.tracked[slot] = i;
        self.far_offsets_m[i] = f64::NEG_INFINITY;
        self.gaps[slot] = gap;
        self.free_steps[slot] = free_step;
        self.steps[slot] = free_step + correction;
        self.corrections[slot] = correction;
        self.rest_forces[slot] = points.rest_forces_n[i];
        self.xis[slot] = points.laws[i].xi;
        self.psis[slot] = points.laws[i].psi;
        self.forces[slot] = points.rest_forces_n[i];
        let stride = self.slot_stride;
        for other in 0..=slot {
            let value = points.coupling(i, self.tracked[other]);
            self.block[slot * stride + other] = value;
            self.block[other * stride + slot] = value;
        }
        self.copy_block_lanes(slot);
    }

    /// Stops tracking the point in `slot`: the last slot moves into it, and the last slot is
    /// made neutral.
    fn untrack(&mut self, slot: usize) {
        let i = self.tracked[slot];
        self.slots[i] = UNTRACKED;
        self.far_offsets_m[i] = 0.0;
        self.corrections[slot] = 0.0;
        let last = self.count - 1;
        self.count = last;
        if slot != last {
            let moved = self.tracked[last];
            self.tracked[slot] = moved;
            self.slots[moved] = slot;
            self.gaps[slot] = self.gaps[last];
            self.free_steps[slot] = self.free_steps[last];
            self.steps[slot] = self.steps[last];
            self.corrections[slot] = self.corrections[last];
            self.rest_forces[slot] = self.rest_forces[last];
            self.xis[slot] = self.xis[last];
            self.psis[slot] = self.psis[last];
            self.forces[slot] = self.forces[last];
            let stride = self.slot_stride;
            for other in 0..last {
                let value = self.block[last * stride + other];
                self.block[slot * stride + other] = value;
                self.block[other * stride + slot] = value;
            }
            self.block[slot * stride + slot] = self.block[last * stride + last];
        }
        self.clear_slot(last);
        self.copy_block_lanes(slot);
        self.copy_block_lanes(last);
    }

    /// Makes `slot` neutral: no gap, step, correction or rest force, and no coupling with any
    /// slot. Every slot past the tracked ones is neutral, as the solve in fixed lanes
    /// (`block.rs`), which runs over [`BLOCK`] or [`WIDE_BLOCK`] slots, needs.
    fn clear_slot(&mut self, slot: usize) {
        let stride = self.slot_stride;
        self.gaps[slot] = 0.0;
        self.free_steps[slot] = 0.0;
        self.steps[slot] = 0.0;
        self.corrections[slot] = 0.0;
        self.rest_forces[slot] = 0.0;
        self.block[slot * stride..(slot + 1) * stride].fill(0.0);
        for other in 0..stride {
            self.block[other * stride + slot] = 0.0;
        }
    }

    /// Row and column `slot` of the block's first rows and columns into `block_lanes` and
    /// `wide_block_lanes` (after they changed).
    fn copy_block_lanes(&mut self, slot: usize) {
        if slot >= WIDE_BLOCK {
            return;
        }
        let stride = self.slot_stride;
        for other in 0..WIDE_BLOCK {
            let (row, column) = (
                self.block[slot * stride + other],
                self.block[other * stride + slot],
            );
            self.wide_block_lanes[slot][other] = row;
            self.wide_block_lanes[other][slot] = column;
            if slot < BLOCK && other < BLOCK {
                self.block_lanes[slot][other] = row;
                self.block_lanes[other][slot] = column;
            }
        }
    }

    /// One step's contact work, inlined into the modal string's step, which runs as one function
    /// compiled for the vector unit `simd` (so its scalar arithmetic uses the unit's encoding and
    /// its passes over all points the unit's full width): [`ContactStep::solve`], the damping loss
    /// (with `track_energy`), [`ContactStep::finish_step`] and [`ContactStep::update_tracking`]
    /// with `band_m` and `release_m`.
    #[inline(always)]
    pub(super) fn step<S: Simd>(
        &mut self,
        _simd: S,
        points: &ContactPoints,
        settings: &NewtonSettings,
        track_energy: bool,
        band_m: f64,
        release_m: f64,
    ) -> ContactOutcome {
        let (iterations, converged) = self.solve(points, settings, band_m);
        let damping_loss_j = if track_energy {
            self.damping_loss_j()
        } else {
            0.0
        };
        let penetration_m = self.finish_step(points);
        self.update_tracking(points, band_m, release_m);
        ContactOutcome {
            iterations,
            converged,
            damping_loss_j,
            penetration_m,
        }
    }

    /// Solves the step's contact (every point's free step must be in place, from
    /// [`ContactStep::point_free_steps_mut`]). A far point that would touch during the step joins
    /// and the solve is redone; whether a far point then lies within `band_m` of contact is
    /// noted for [`ContactStep::update_tracking`]. Returns (Newton updates, converged).
    #[inline(always)]
    pub fn solve(
        &mut self,
        points: &ContactPoints,
        settings: &NewtonSettings,
        band_m: f64,
    ) -> (u32, bool) {
        for slot in 0..self.count {
            let free_step = self.point_free_steps_m[self.tracked[slot]];
            self.free_steps[slot] = free_step;
            self.steps[slot] = free_step + self.corrections[slot];
        }
        let mut iterations = 0;
        let mut converged = true;
        loop {
            let (updates, done) = self.solve_tracked(settings);
            iterations += updates;
            if let Some(done) = done {
                converged = done;
            }
            if !self.join_touching(points, band_m) {
                break;
            }
        }
        for (slot, &local) in self.loaded[..self.loaded_count].iter().enumerate() {
            self.loaded_points[slot] = self.tracked[local];
            self.loaded_changes_n[slot] = self.changes[local];
        }
        (iterations, converged)
    }

    /// The tracked points' forces for the current free steps: none if nothing can touch, else
    /// Newton's iteration from the current steps and the forces at the accepted step (for the
    /// update, the outputs and the ledger). Returns the updates and, if Newton ran, whether it
    /// converged. Up to [`BLOCK`] points (nearly every step) the iteration runs in [`BLOCK`]
    /// fixed lanes (`block.rs`), up to [`WIDE_BLOCK`] in as many; the general path takes more.
    #[inline(always)]
    fn solve_tracked(&mut self, settings: &NewtonSettings) -> (u32, Option<bool>) {
        let (tolerance, cap) = (settings.tolerance_m, settings.max_iterations);
        let lanes_allowed = self.fixed_lanes_allowed();
        if self.count <= BLOCK && lanes_allowed {
            let mut state = self.block_state::<BLOCK>();
            if state.free_of_contact() {
                return self.settle_free::<BLOCK>();
            }
            let outcome = state.newton(&self.block_lanes, tolerance, cap);
            return self.take_block_solution(&state, outcome);
        }
        if self.count <= WIDE_BLOCK && lanes_allowed {
            let mut state = self.block_state::<WIDE_BLOCK>();
            if state.free_of_contact() {
                return self.settle_free::<WIDE_BLOCK>();
            }
            let outcome = state.newton(&self.wide_block_lanes, tolerance, cap);
            return self.take_block_solution(&state, outcome);
        }
        if self.settle_if_free() {
            return (0, None);
        }
        let (updates, done) = self.newton(settings);
        self.evaluate();
        (updates, Some(done))
    }

    /// The tracked points' state in `N` fixed lanes (`count ≤ N`; the slots past them are
    /// neutral).
    #[inline(always)]
    fn block_state<const N: usize>(&self) -> BlockState<N> {
        BlockState {
            count: self.count,
            gaps: lanes_of(&self.gaps),
            free_steps: lanes_of(&self.free_steps),
            steps: lanes_of(&self.steps),
            rest_forces: lanes_of(&self.rest_forces),
            xis: lanes_of(&self.xis),
            psis: lanes_of(&self.psis),
            forces: [0.0; N],
            stiffnesses: [0.0; N],
            changes: [0.0; N],
        }
    }

    /// The free step as the solution, when nothing can touch (see
    /// [`ContactStep::settle_if_free`]), on the first `N` slots (`count ≤ N`; the neutral slots
    /// stay neutral): copies of a fixed length, which compile to a few vector moves rather than
    /// calls into libc.
    #[inline(always)]
    fn settle_free<const N: usize>(&mut self) -> (u32, Option<bool>) {
        self.loaded_count = 0;
        let free_steps: [f64; N] = lanes_of(&self.free_steps);
        self.steps[..N].copy_from_slice(&free_steps);
        self.forces[..N].fill(0.0);
        self.changes[..N].fill(0.0);
        (0, None)
    }

    /// Takes the steps and forces of a solve in fixed lanes (`block.rs`; (updates, converged)
    /// in `outcome`) and lists the loaded slots.
    #[inline(always)]
    fn take_block_solution<const N: usize>(
        &mut self,
        state: &BlockState<N>,
        (updates, converged): (u32, bool),
    ) -> (u32, Option<bool>) {
        let count = self.count;
        // Whole lanes (fixed-length copies, no calls into libc); the lanes past the tracked
        // points hold the neutral slots' zero forces.
        self.steps[..N].copy_from_slice(&state.steps);
        self.forces[..N].copy_from_slice(&state.forces);
        self.stiffnesses[..N].copy_from_slice(&state.stiffnesses);
        self.changes[..N].copy_from_slice(&state.changes);
        self.loaded_count = 0;
        for slot in 0..count {
            if state.changes[slot] != 0.0 {
                self.loaded[self.loaded_count] = slot;
                self.loaded_count += 1;
            }
        }
        (updates, Some(converged))
    }

    /// Makes every solve take the general path, not the fixed lanes (for tests).
    #[cfg(test)]
    pub(super) fn take_general_path_only(&mut self) {
        self.general_path_only = true;
    }

    /// Whether the solve may run in fixed lanes: always, outside the test that compares the
    /// paths.
    #[inline(always)]
    fn fixed_lanes_allowed(&self) -> bool {
        #[cfg(test)]
        return !self.general_path_only;
        #[cfg(not(test))]
        true
    }

    /// Forms every point's `Σ_j G_ij ΔF_j` at the current forces; a far point whose step
    /// `Ψ_i s_free + Σ_j G_ij ΔF_j` would bring it into contact joins (returns true: the solve
    /// must be redone).
    #[inline(always)]
    fn join_touching(&mut self, points: &ContactPoints, band_m: f64) -> bool {
        let count = points.len();
        let stride = self.capacity;
        // Σ_j G_ij ΔF_j for every point, a row of G (= its column) per loaded point.
        // The first loaded point's row is written, not added to zeros: a fill of a few hundred
        // bytes is a call into libc's memset every step (2.4 % of the live step's time, perf).
        let coupled = &mut self.coupled_m[..count];
        match self.loaded[..self.loaded_count].split_first() {
            None => coupled.fill(0.0),
            Some((&first, rest)) => {
                let row = self.tracked[first] * stride;
                scaled(
                    coupled,
                    &points.coupling[row..row + count],
                    self.changes[first],
                );
                for &local in rest {
                    let row = self.tracked[local] * stride;
                    add_scaled(
                        coupled,
                        &points.coupling[row..row + count],
                        self.changes[local],
                    );
                }
            }
        }
        let (touches, near) = far_points_after_step(
            FarPoints {
                gaps_m: &self.gaps_m[..count],
                offsets_m: &self.far_offsets_m[..count],
                free_steps_m: &self.point_free_steps_m[..count],
                coupled_m: &self.coupled_m[..count],
                awake: &self.awake[..count],
            },
            &mut self.next_gaps_m[..count],
            band_m,
        );
        self.far_point_near = near;
        if !touches {
            return false;
        }
        // The same test point by point (the offset leaves out the tracked and the sleeping
        // points); the solve is redone only if a point did join, so the loop in `solve` ends
        // whatever the values.
        let mut joined = false;
        for i in 0..count {
            let step = self.point_free_steps_m[i] + self.coupled_m[i];
            let gap = self.gaps_m[i];
            if (gap + self.far_offsets_m[i]) - step > 0.0 {
                self.track(
                    points,
                    i,
                    gap,
                    self.point_free_steps_m[i],
                    self.coupled_m[i],
                );
                joined = true;
            }
        }
        joined
    }

    /// After the solve: moves the tracked gaps by the accepted steps, keeps the corrections for
    /// the next guess and the far bounds for the next step. Returns the deepest penetration of
    /// the tracked points after the step (0 if none), m.
    #[inline(always)]
    pub fn finish_step(&mut self, points: &ContactPoints) -> f64 {
        // Every point by its step at the converged forces (formed by the last
        // `join_touching`); the tracked ones by Newton's below.
        debug_assert!(points.len() <= self.next_gaps_m.len());
        std::mem::swap(&mut self.gaps_m, &mut self.next_gaps_m);
        let mut penetration = 0.0f64;
        for slot in 0..self.count {
            let gap = self.gaps[slot] - self.steps[slot];
            self.gaps[slot] = gap;
            self.gaps_m[self.tracked[slot]] = gap;
            self.corrections[slot] = self.steps[slot] - self.free_steps[slot];
            penetration = penetration.max(gap);
        }
        penetration
    }

    /// After a step: tracked points farther than `release_m` from contact with no force now and
    /// none at rest leave; far points within `band_m` of contact join.
    #[inline(always)]
    pub fn update_tracking(&mut self, points: &ContactPoints, band_m: f64, release_m: f64) {
        let mut slot = 0;
        while slot < self.count {
            let far = self.gaps[slot] < -release_m
                && self.forces[slot] == 0.0
                && self.rest_forces[slot] == 0.0;
            if far {
                self.untrack(slot);
            } else {
                slot += 1;
            }
        }
        // Whether a far point lies within the band, as the last `join_touching` found (a point
        // released above lies farther than `release_m` ≥ `band_m`, so it is not near).
        if !self.far_point_near {
            return;
        }
        let count = points.len();
        for i in 0..count {
            let gap = self.gaps_m[i];
            if gap + self.far_offsets_m[i] > -band_m {
                self.track(points, i, gap, 0.0, 0.0);
            }
        }
    }

    /// Evaluates every tracked point's force at the iterate and lists the slots whose force
    /// differs from its rest value.
    #[inline(always)]
    fn evaluate(&mut self) {
        let count = self.count;
        self.loaded_count = 0;
        for slot in 0..count {
            let law = HuntCrossley {
                xi: self.xis[slot],
                psi: self.psis[slot],
            };
            let contact = law.midpoint_force_linear_damping(self.gaps[slot], self.steps[slot]);
            self.forces[slot] = contact.force;
            self.stiffnesses[slot] = contact.stiffness;
            let change = contact.force - self.rest_forces[slot];
            self.changes[slot] = change;
            if change != 0.0 {
                self.loaded[self.loaded_count] = slot;
                self.loaded_count += 1;
            }
        }
    }

    /// Whether no point can exert a force different from its rest force during the free step:
    /// nothing rests in contact and nothing touches before or after. Then the free step is the
    /// exact solution and the forces are zero.
    #[inline(always)]
    fn settle_if_free(&mut self) -> bool {
        let count = self.count;
        let free = self.rest_forces[..count]
            .iter()
            .zip(&self.gaps[..count])
            .zip(&self.free_steps[..count])
            .all(|((&rest, &gap), &free)| rest == 0.0 && gap <= 0.0 && gap - free <= 0.0);
        if free {
            self.loaded_count = 0;
            self.steps[..count].copy_from_slice(&self.free_steps[..count]);
            self.forces[..count].fill(0.0);
            self.changes[..count].fill(0.0);
        }
        free
    }

    /// Newton's iteration from the current steps: at most `settings.max_iterations` updates.
    #[inline(always)]
    fn newton(&mut self, settings: &NewtonSettings) -> (u32, bool) {
        let cap = settings.max_iterations.max(1);
        for iteration in 1..=cap {
            self.evaluate();
            let (crossing, crossing_slot) = self.crossing_points();
            let linear = crossing == 0;
            let (largest, exact) = self.update((crossing == 1).then_some(crossing_slot));
            if !largest.is_finite() {
                return (iteration, false);
            }
            // Exact: the update solved the step for the cases of the evaluation point, and the
            // step lies in those cases (always so when the law was linear at the evaluation point
            // and the cases did not change).
            if exact || largest <= settings.tolerance_m || (linear && self.cases_unchanged()) {
                return (iteration, true);
            }
        }
        (cap, false)
    }

    /// Whether every tracked point is in the same contact case before and after its step.
    #[inline(always)]
    fn cases_unchanged(&self) -> bool {
        self.gaps[..self.count]
            .iter()
            .zip(&self.steps[..self.count])
            .all(|(&gap, &step)| {
                let (before, after) = contact_case(gap, step);
                before == after
            })
    }

    /// How many tracked points enter or leave contact during their step (the law is nonlinear
    /// only there), and the slot of the last of them.
    #[inline(always)]
    fn crossing_points(&self) -> (usize, usize) {
        let mut count = 0;
        let mut last = 0;
        for (slot, (&gap, &step)) in self.gaps[..self.count]
            .iter()
            .zip(&self.steps[..self.count])
            .enumerate()
        {
            let (before, after) = contact_case(gap, step);
            if before != after {
                count += 1;
                last = slot;
            }
        }
        (count, last)
    }

    /// One Newton update `δ = −J⁻¹ R` at the last evaluation; applies it and returns its largest
    /// component (NaN when the state is not finite) and whether the step is now exact. The
    /// residual needs G only on the loaded points' rows, the linear solve only on the points with
    /// `c > 0` (the others' rows of `I + D G D` are identity rows). With `crossing` (the one
    /// point that enters or leaves contact during its step), the step is first solved exactly
    /// for the cases of the evaluation point ([`ContactStep::finish_exactly`]).
    #[inline(always)]
    fn update(&mut self, crossing: Option<usize>) -> (f64, bool) {
        let count = self.count;
        let stride = self.slot_stride;
        // R = Δu − Δu_free − G ΔF, with ΔF ≠ 0 only on the loaded points (G is symmetric, so
        // each loaded point adds its row).
        let residual = &mut self.residual[..count];
        for ((r, &step), &free) in residual
            .iter_mut()
            .zip(&self.steps[..count])
            .zip(&self.free_steps[..count])
        {
            *r = step - free;
        }
        for &u in &self.loaded[..self.loaded_count] {
            let change = self.changes[u];
            let row = &self.block[u * stride..u * stride + count];
            for (r, g) in residual.iter_mut().zip(row) {
                *r -= g * change;
            }
        }
        // A: the points with c > 0, and D = diag(√c) on them.
        let mut size = 0;
        for slot in 0..count {
            if self.stiffnesses[slot] > 0.0 {
                self.active[size] = slot;
                self.roots[size] = self.stiffnesses[slot].sqrt();
                size += 1;
            }
        }
        // The exact finish needs the factors for a second right-hand side: the fixed sizes.
        let crossing = crossing.filter(|_| size <= 8);
        match size {
            0 => {}
            1 => self.solve_active_fixed::<1>(crossing),
            2 => self.solve_active_fixed::<2>(crossing),
            3 => self.solve_active_fixed::<3>(crossing),
            4 => self.solve_active_fixed::<4>(crossing),
            5 => self.solve_active_fixed::<5>(crossing),
            6 => self.solve_active_fixed::<6>(crossing),
            7 => self.solve_active_fixed::<7>(crossing),
            8 => self.solve_active_fixed::<8>(crossing),
            _ => self.solve_active_any(size),
        }
        // δ = −R − G_{:,A} D y, a row of the block per active point.
        let deltas = &mut self.scratch[..count];
        for (d, r) in deltas.iter_mut().zip(&self.residual[..count]) {
            *d = -r;
        }
        for a in 0..size {
            let row_start = self.active[a] * stride;
            let row = &self.block[row_start..row_start + count];
            let weight = self.solution[a];
            for (d, g) in deltas.iter_mut().zip(row) {
                *d -= g * weight;
            }
        }
        if let Some(crossing) = crossing {
            if let Some(largest) = self.finish_exactly(crossing, size) {
                return (largest, true);
            }
        }
        let mut largest = 0.0f64;
        for (step, d) in self.steps[..count]
            .iter_mut()
            .zip(self.scratch[..count].iter())
        {
            *step += d;
            largest = largest.max(d.abs());
        }
        if self.solution[..size].iter().all(|y| y.is_finite()) && largest.is_finite() {
            (largest, false)
        } else {
            (f64::NAN, false)
        }
    }

    /// The step solved exactly for the contact cases of the evaluation point, when one point `c`
    /// crosses (enters or leaves contact) and every other point stays in or out, where the law is
    /// linear in its step (`docs/modal-tanpura.md`, section 4). With the Newton update `δ` (in
    /// `scratch`) and `w = J⁻¹ G e_c`, the exact step is `Δu + δ + ρ w`, where
    /// `ρ(s) = F_c(s) − F_c⁰ + c_c (s − s⁰)` is the crossing law's departure from its tangent at
    /// the evaluation point `s⁰`. On a crossing the law is `F_c(s) = P/s + Q s + K` (leaving:
    /// `P = ξa²`, `Q = −2ψa`, `K = 0`; entering: `P = −ξa²`, `Q = −ξ`, `K = 2ξa`), so the
    /// point's own equation `s = s⁰ + δ_c + w_c ρ(s)` is a quadratic in s. Its root in the
    /// crossing case gives the step, or, if that case holds none, the root of the linear equation
    /// in the case the point had before the step ([`exact_crossing_step`]); it is taken (and the
    /// iterate replaced, returning the largest change) only if every other point is then in the
    /// case it was evaluated in, so that the step solves the scheme's equations to round-off.
    /// Otherwise `None`, and Newton goes on.
    /// Newton's own iterates converge to the same root quadratically but from far away, one
    /// update for every digit pair (3–4 more updates per crossing with stiff contact).
    #[inline(always)]
    fn finish_exactly(&mut self, crossing: usize, size: usize) -> Option<f64> {
        let count = self.count;
        let stride = self.slot_stride;
        // w = J⁻¹ G e_c = G e_c − G_{:,A} D y', (I + D G_AA D) y' = D G_{A,c}.
        let direction = &mut self.crossing_direction[..count];
        direction.copy_from_slice(&self.block[crossing * stride..crossing * stride + count]);
        for a in 0..size {
            let row_start = self.active[a] * stride;
            let row = &self.block[row_start..row_start + count];
            let weight = self.second_solution[a];
            for (w, g) in direction.iter_mut().zip(row) {
                *w -= g * weight;
            }
        }
        let (step, departure) = exact_crossing_step(CrossingPoint {
            gap: self.gaps[crossing],
            start: self.steps[crossing],
            law: HuntCrossley {
                xi: self.xis[crossing],
                psi: self.psis[crossing],
            },
            force: self.forces[crossing],
            stiffness: self.stiffnesses[crossing],
            direction: direction[crossing],
            delta: self.scratch[crossing],
        })?;
        let mut largest = 0.0f64;
        for slot in 0..count {
            let candidate = if slot == crossing {
                step
            } else {
                self.steps[slot] + self.scratch[slot] + departure * self.crossing_direction[slot]
            };
            // The crossing point's case is the one its step was solved in.
            let evaluated = contact_case(self.gaps[slot], self.steps[slot]);
            let moved = contact_case(self.gaps[slot], candidate) != evaluated;
            if !candidate.is_finite() || (moved && slot != crossing) {
                return None;
            }
            self.candidate[slot] = candidate;
            largest = largest.max((candidate - self.steps[slot]).abs());
        }
        self.steps[..count].copy_from_slice(&self.candidate[..count]);
        Some(largest)
    }

    /// `(I + D G_AA D) y = −D R_A`, then `y ← D y`, into `solution[..N]`, for exactly `N` active
    /// points (the loops unroll and the arrays stay in registers); with `crossing`, also
    /// `(I + D G_AA D) y' = D G_{A,c}` with the same factors, `D y'` into `second_solution[..N]`.
    #[inline(always)]
    fn solve_active_fixed<const N: usize>(&mut self, crossing: Option<usize>) {
        let stride = self.slot_stride;
        let mut matrix = [[0.0; N]; N];
        let mut y = [0.0; N];
        for a in 0..N {
            let row = &self.block[self.active[a] * stride..];
            for b in 0..=a {
                matrix[b][a] = self.roots[a] * row[self.active[b]] * self.roots[b];
            }
            matrix[a][a] += 1.0;
            y[a] = -self.roots[a] * self.residual[self.active[a]];
        }
        ldl_factor_fixed(&mut matrix);
        ldl_substitute_fixed(&matrix, &mut y);
        for a in 0..N {
            self.solution[a] = y[a] * self.roots[a];
        }
        if let Some(crossing) = crossing {
            let column = &self.block[crossing * stride..];
            let mut second = [0.0; N];
            for a in 0..N {
                second[a] = self.roots[a] * column[self.active[a]];
            }
            ldl_substitute_fixed(&matrix, &mut second);
            for a in 0..N {
                self.second_solution[a] = second[a] * self.roots[a];
            }
        }
    }

    /// [`ContactStep::solve_active_fixed`] for any size, in the heap buffers. The matrix is SPD
    /// with eigenvalues ≥ 1, so LDLᵀ without pivoting is exact and stable.
    fn solve_active_any(&mut self, size: usize) {
        let stride = self.slot_stride;
        let matrix = &mut self.matrix[..size * size];
        for a in 0..size {
            let row = &self.block[self.active[a] * stride..];
            for b in 0..=a {
                matrix[a * size + b] = self.roots[a] * row[self.active[b]] * self.roots[b];
            }
            matrix[a * size + a] += 1.0;
            self.solution[a] = -self.roots[a] * self.residual[self.active[a]];
        }
        let solution = &mut self.solution[..size];
        ldl_solve_in_place(matrix, size, solution, &mut self.scratch[..size]);
        for (y, root) in solution.iter_mut().zip(&self.roots[..size]) {
            *y *= root;
        }
    }

    /// The contact damping's loss over the step at the last evaluation, J.
    #[inline(always)]
    pub fn damping_loss_j(&self) -> f64 {
        let count = self.count;
        (0..count)
            .map(|slot| {
                let law = HuntCrossley {
                    xi: self.xis[slot],
                    psi: self.psis[slot],
                };
                law.linear_damping_loss(self.gaps[slot], self.steps[slot])
            })
            .sum()
    }
}
