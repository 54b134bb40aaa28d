//! The grid modes' contact solved on the FD grid's nodes (`docs/modal-tanpura.md`, section 11).
//!
//! With grid modes (section 10) a contact point sees the cubic Lagrange interpolation of the
//! grid's nodes (the seed's eq. 17), so its shape row factors: `Ψ_i = L_i V`, with `L_i` the
//! point's four stencil weights and `V` the scaled sampled sines on the nodes the stencils reach
//! (`V_jk = sin(kπ n_j/N)/√κ_k`). Everything the step needs from the modes then passes through
//! those few nodes (11 for the seed's bridge and thread, against 170 points at the
//! reference's spacing):
//!
//! - the nodes' free step `Δy_free = V s_free` (one dot product per node), and every point's
//!   `Δu_i = L_i Δy`;
//! - the modal force `Ψᵀ ΔF = Vᵀ Lᵀ ΔF = Vᵀ f`, with the nodal force `f = Lᵀ ΔF`;
//! - the coupling `G = Ψ diag(b) Ψᵀ = L G_N Lᵀ`, `G_N = V diag(b) Vᵀ`, fixed per configuration.
//!
//! **Newton on the nodes.** On the set S of nodes that the tracked points' stencils reach, the
//! step solves `Δy_S = Δy_free,S + G_SS f_S(Δy_S)` (the other nodes follow explicitly once the
//! forces are known, `Δy = Δy_free + G_{:,S} f_S`). With `H = G_SS⁻¹` (symmetric positive
//! definite: `G_N` is, all N − 1 modes being kept and b > 0) the residual in force form is
//! `ρ = f_S − H (Δy_S − Δy_free,S)` and Newton's update solves
//!
//! `(H + Σ_i c_i l_i l_iᵀ) δ = ρ`,   `c_i = −∂F_i/∂Δu_i ≥ 0`,
//!
//! a symmetric positive definite system of at most |S| unknowns, whatever the number of points
//! in contact: it is exactly the point-level update of section 4 (`J = I + G C`, multiplied by
//! `H` on the nodes), so the iterates are the same up to round-off. The iteration stops when
//! `max|δ| ≤ tolerance`, or exactly when an update leaves every tracked point in the linear case
//! (in contact or out, before and after the step) it had at the last evaluation. Where the
//! evaluation finds one to eight points crossing the contact's edge and every other in a linear
//! case, the update finishes the step: one point by its own quadratic (section 4), several by
//! Newton on their steps alone through `W = Lᵀ A⁻¹ L` on the update's factors
//! ([`NodalContact::solve_crossings`]); it stands if every point that was in a linear case kept
//! it. The energy balance (M3) holds as for the point-level solve: the forces are the same law
//! at the same steps, and the modes take `Vᵀ f = Ψᵀ ΔF`.
//!
//! **Which points Newton sees.** Those within the tracking band of contact, or loaded at rest,
//! as in section 4. After Newton every point's step is formed from the nodes in one pass over
//! groups of [`LANES`] points, each summing its band of nodes' steps in order with the weights
//! its points put on them (zeros off a point's stencil, so each sum is the stencil's four
//! products); whether an untracked point touches or comes near is read off each lane's largest
//! gap. If one would touch, it joins and the solve is redone before anything moves. The tracked
//! points are evaluated in chunks of [`LANES`] with a branch-free copy of the contact law; H is
//! formed again only when the node set S changes, not with every point that joins or leaves; up
//! to 8 and 16 nodes the update is solved in fixed lanes.
//!
//! Hand-written rather than on a linear-algebra crate: the systems have at most
//! [`NODE_CAPACITY`] unknowns and are solved once or twice per sample on the audio thread;
//! nothing here allocates after [`NodalContact::new`].

use super::block::{exact_crossing_step, CrossingPoint};
use super::lanes::{padded_lanes, Kernels};
use super::modes::{ModeSet, MODE_CAPACITY};
use super::points::ContactPoints;
use super::solve::{
    ldl_factor_fixed, ldl_solve_in_place, ldl_substitute_fixed, ldl_substitute_in_place,
    ldl_substitute_many,
};
use crate::newton::NewtonSettings;
use crate::step_timers::{self, StepPart};
use crate::tanpura::contact::HuntCrossley;
use crate::tanpura::fd::barrier_grid::lagrange_stencil;
use crate::unroll::for_each_index;
use pulp::{Simd, WithSimd};
use std::f64::consts::PI;

/// The most grid nodes the stencils may reach; a configuration that reaches more runs the
/// point-level solve (`step.rs`).
pub const NODE_CAPACITY: usize = 48;
const _: () = assert!(NODE_CAPACITY <= 64, "the node set is a u64 mask");
const _: () = assert!(
    NODE_CAPACITY.is_multiple_of(4),
    "the node rows are dotted in fours"
);
const UNSET: usize = usize::MAX;
/// Up to this many points crossing the contact's edge in one update, the step is finished by
/// Newton on their steps alone ([`NodalContact::solve_crossings`]).
const MOST_CROSSINGS: usize = 8;
/// The most updates of that small Newton iteration (it takes 1–5 on the bench's string).
const CROSSING_ITERATION_CAP: usize = 16;
/// The points are evaluated in chunks of this many lanes (loops over fixed arrays that the
/// compiler vectorises); the per-point arrays are padded by as many.
const LANES: usize = 8;

/// A point's contact case over a step: the law is linear in the first two.
const OUT: f64 = 0.0;
const IN: f64 = 1.0;
const CROSSING: f64 = 2.0;

/// The ten pairs (j ≤ l) of a stencil's four nodes, for the symmetric `Σ c l lᵀ`.
const PAIRS: [(usize, usize); 10] = [
    (0, 0),
    (0, 1),
    (0, 2),
    (0, 3),
    (1, 1),
    (1, 2),
    (1, 3),
    (2, 2),
    (2, 3),
    (3, 3),
];

/// Consecutive points `start..end` whose stencils reach the same four places: a run of points
/// (the places are local nodes) or a segment of tracked points (the places are slots in S).
#[derive(Debug, Clone, Copy, Default)]
struct Span {
    start: usize,
    end: usize,
    places: [usize; 4],
}

/// Appends point `i`, whose stencil reaches `places`, to the spans `spans[..*count]`: it extends
/// the last span if it follows it with the same places, else it opens a new one.
fn append_to_spans(spans: &mut [Span], count: &mut usize, i: usize, places: [usize; 4]) {
    if let Some(last) = spans[..*count].last_mut() {
        if last.end == i && last.places == places {
            last.end = i + 1;
            return;
        }
    }
    spans[*count] = Span {
        start: i,
        end: i + 1,
        places,
    };
    *count += 1;
}

/// A group of [`LANES`] points' band of nodes: the first node, how many, and where its weight
/// rows start.
#[derive(Debug, Clone, Copy, Default)]
struct GroupBand {
    first_node: usize,
    nodes: usize,
    offset: usize,
}

/// What one step's contact work reports.
#[derive(Debug, Clone, Copy)]
pub struct NodalOutcome {
    pub iterations: u32,
    pub converged: bool,
    /// The contact damping's loss over the step, J.
    pub damping_loss_j: f64,
    /// The deepest penetration of the tracked points after the step (0 if none), m.
    pub penetration_m: f64,
    /// Σ (F_i − F_rest,i) over the points, N.
    pub force_change_n: f64,
}

/// The condensed contact of a grid-mode string; allocation-free after [`NodalContact::new`].
#[derive(Debug, Clone)]
pub struct NodalContact {
    /// The grid nodes (indices 1 … N − 1) the points' stencils reach, in order.
    node_count: usize,
    grid_nodes: Vec<usize>,
    /// V rows in f64, `NODE_CAPACITY × MODE_CAPACITY`.
    pub node_shapes: Vec<f64>,
    /// G_N, `NODE_CAPACITY × NODE_CAPACITY`.
    compliance: Vec<f64>,
    point_count: usize,
    /// Per point: its stencil's nodes (local indices; a support's entry has weight 0 and names
    /// the stencil's nearest interior node); its weights by column.
    stencil_nodes: Vec<[usize; 4]>,
    weight_columns: [Vec<f64>; 4],
    /// The same weights by point, for the sums over a segment's four places (one register).
    weight_rows: Vec<[f64; 4]>,
    /// The points in groups of [`LANES`] (the last padded): each group's weights on the band of
    /// nodes its stencils reach, one row of lanes per node (`group_weights`, from `offset`), and
    /// the band's first node and length.
    group_bands: Vec<GroupBand>,
    group_count: usize,
    group_weights: Vec<[f64; LANES]>,
    /// Per point: the law's ξ and ψ, and the rest force, N.
    xis: Vec<f64>,
    psis: Vec<f64>,
    rest_forces_n: Vec<f64>,
    /// a_i per point after every step, m.
    pub gaps_m: Vec<f64>,
    next_gaps_m: Vec<f64>,
    /// 0 for an untracked point, −∞ for a tracked one.
    far_offsets_m: Vec<f64>,
    /// The tracked points (in order once S is formed).
    tracked: Vec<usize>,
    tracked_count: usize,
    /// Whether the tracked set changed since S and H were formed.
    set_changed: bool,
    /// The node set S as a mask over the local nodes (at most [`NODE_CAPACITY`] ≤ 64).
    set_mask: u64,
    /// S: its nodes (local indices), each node's slot in S (or UNSET), H = G_SS⁻¹ (stride
    /// NODE_CAPACITY).
    set_count: usize,
    set_nodes: Vec<usize>,
    node_slots: Vec<usize>,
    inverse: Vec<f64>,
    /// H by columns, as its solves leave them (`inverse_columns[b · NODE_CAPACITY + a]` is the
    /// `H_ab` of column b's solve; zeros past |S|): the update's right side reads them.
    inverse_columns: Vec<f64>,
    /// The tracked points in segments, and each segment's `Σ c w_j w_l` over [`PAIRS`] at the
    /// last evaluation.
    segments: Vec<Span>,
    segment_count: usize,
    segment_stiffness: Vec<[[f64; 4]; 4]>,
    /// Per slot: the free step, the iterate and the nodal force change.
    slot_free: Vec<f64>,
    slot_steps: Vec<f64>,
    slot_forces: Vec<f64>,
    /// Per local node: the free step, the step, and the last accepted step − free step (the
    /// next step's initial guess).
    pub node_free_steps_m: Vec<f64>,
    node_steps_m: Vec<f64>,
    node_corrections_m: Vec<f64>,
    /// Per point (the tracked ones' at the last evaluation): step, force, c, case.
    point_steps: Vec<f64>,
    point_forces: Vec<f64>,
    point_stiffnesses: Vec<f64>,
    cases: Vec<f64>,
    /// The points crossing at the last evaluation (the first [`MOST_CROSSINGS`] of them).
    crossing_points: [usize; MOST_CROSSINGS],
    matrix: Vec<f64>,
    right_side: Vec<f64>,
    scratch: Vec<f64>,
    /// A node row times b (the compliance's rows), and the dot-product kernels.
    weighted_row: Vec<f64>,
    kernels: Kernels,
    /// The nodes with a non-zero force change after the step, and the changes, N.
    loaded_nodes: Vec<usize>,
    loaded_forces_n: Vec<f64>,
    loaded_count: usize,
    /// Whether an untracked point lies within the tracking band after the step.
    far_point_near: bool,
    /// Whether every update takes the general path (for the test that the paths agree).
    #[cfg(test)]
    general_path_only: bool,
    /// Whether steps with several crossing points are left to Newton's iteration on S (for
    /// the test that their finish is the iteration's solution).
    #[cfg(test)]
    iterate_over_crossings: bool,
}

/// The mid-point force of `contact.rs` (`HuntCrossley::midpoint_force_linear_damping`) for a
/// point with gap `gap` and step `step`, branch-free (each case's value is formed and one is
/// taken), so that a loop over lanes vectorises: (F, c = −∂F/∂s, case).
#[inline(always)]
fn law_lane(gap: f64, step: f64, xi: f64, psi: f64) -> (f64, f64, f64) {
    let after = gap - step;
    let damping = 2.0 * psi * gap.max(0.0);
    let inverse = 1.0 / step;
    let (force_in, stiffness_in) = (xi * (2.0 * gap - step) - damping * step, xi + damping);
    let ratio = gap * inverse;
    let (force_leaving, stiffness_leaving) = (
        xi * gap * ratio - damping * step,
        xi * ratio * ratio + damping,
    );
    let (force_entering, stiffness_entering) = (
        -xi * after * after * inverse,
        -xi * after * (gap + step) * inverse * inverse,
    );
    let (touching, touching_after) = (gap > 0.0, after > 0.0);
    let force = if touching {
        if touching_after {
            force_in
        } else {
            force_leaving
        }
    } else if touching_after {
        force_entering
    } else {
        0.0
    };
    let stiffness = if touching {
        if touching_after {
            stiffness_in
        } else {
            stiffness_leaving
        }
    } else if touching_after {
        stiffness_entering
    } else {
        0.0
    };
    let case = if touching == touching_after {
        if touching {
            IN
        } else {
            OUT
        }
    } else {
        CROSSING
    };
    (force, stiffness, case)
}

/// Node `node`'s row of V into `row` (MODE_CAPACITY long): `V_k = sin(kπ n/N)/√κ_k` over the
/// modes, zeros beyond them. The sines come from the modes' table of the grid's sines
/// ([`ModeSet::grid_sines`], entry k n mod 2N), else by the recurrence `sin((k+1)θ) = 2 cos θ
/// sin(kθ) − sin((k−1)θ)`, a chain of dependent multiply-subtracts that took a seventh of a
/// retune at the fine tier (`docs/performance.md`, stop 55). The condensed step's and the static
/// problems' node rows are the same.
pub(super) fn write_node_row(node: usize, intervals: usize, modes: &ModeSet, row: &mut [f64]) {
    row.fill(0.0);
    if let Some(sines) = modes.grid_sines(intervals) {
        // k n mod 2N, stepped by n < N.
        let node = node % intervals;
        let mut index = 0;
        for (value, scale) in row[..modes.count()]
            .iter_mut()
            .zip(&modes.inverse_root_stiffness)
        {
            index += node;
            if index >= sines.len() {
                index -= sines.len();
            }
            *value = sines[index] * scale;
        }
    } else {
        write_node_row_by_recurrence(node, intervals, modes, row);
    }
}

/// [`write_node_row`] by the sines' recurrence (modes without the grid's table).
fn write_node_row_by_recurrence(node: usize, intervals: usize, modes: &ModeSet, row: &mut [f64]) {
    let theta = PI * node as f64 / intervals as f64;
    let twice_cos = 2.0 * theta.cos();
    let (mut previous, mut current) = (0.0, theta.sin());
    for (value, scale) in row[..modes.count()]
        .iter_mut()
        .zip(&modes.inverse_root_stiffness)
    {
        *value = current * scale;
        (previous, current) = (current, twice_cos * current - previous);
    }
}

/// The first of four `places` that are consecutive, or `None` (a stencil that names a
/// support's node twice): a span whose places are consecutive adds its sums as whole slices.
#[inline(always)]
fn consecutive_start(places: [usize; 4]) -> Option<usize> {
    let first = places[0];
    (places == [first, first + 1, first + 2, first + 3]).then_some(first)
}

/// Adds `sums` to `values` at the four `places`: as one slice when they are consecutive, else
/// one by one in order; either way each entry receives its sums in the same order.
#[inline(always)]
fn add_at_places(values: &mut [f64], places: [usize; 4], sums: [f64; 4]) {
    if let Some(first) = consecutive_start(places) {
        for (value, sum) in values[first..first + 4].iter_mut().zip(sums) {
            *value += sum;
        }
    } else {
        for (place, sum) in places.into_iter().zip(sums) {
            values[place] += sum;
        }
    }
}

/// Calls `add(a, b, value)` with a segment's `Σ c w_j w_l` (`sums`) at its `places`, a ≥ b, one
/// pair of [`PAIRS`] after another: entry (a, b) of the symmetric matrix.
#[inline(always)]
fn add_pairs(places: [usize; 4], sums: &[[f64; 4]; 4], mut add: impl FnMut(usize, usize, f64)) {
    for &(j, k) in &PAIRS {
        let (a, b) = (places[j], places[k]);
        add(a.max(b), a.min(b), sums[j][k]);
    }
}

/// A chunk of [`LANES`] values of `values` from `start` (the arrays are padded).
#[inline(always)]
fn chunk(values: &[f64], start: usize) -> [f64; LANES] {
    let mut lanes = [0.0; LANES];
    lanes.copy_from_slice(&values[start..start + LANES]);
    lanes
}

impl NodalContact {
    /// Room for `capacity` points. Allocates.
    pub fn new(capacity: usize) -> Self {
        let zeros = |n: usize| vec![0.0; n];
        let padded = capacity + LANES;
        Self {
            node_count: 0,
            grid_nodes: vec![0; NODE_CAPACITY],
            node_shapes: zeros(NODE_CAPACITY * MODE_CAPACITY),
            compliance: zeros(NODE_CAPACITY * NODE_CAPACITY),
            point_count: 0,
            stencil_nodes: vec![[0; 4]; capacity],
            weight_columns: std::array::from_fn(|_| zeros(padded)),
            weight_rows: vec![[0.0; 4]; capacity],
            group_bands: vec![GroupBand::default(); capacity.div_ceil(LANES)],
            group_count: 0,
            group_weights: vec![[0.0; LANES]; capacity.div_ceil(LANES) * NODE_CAPACITY],
            xis: zeros(padded),
            psis: zeros(padded),
            rest_forces_n: zeros(padded),
            gaps_m: zeros(padded),
            next_gaps_m: zeros(padded),
            far_offsets_m: zeros(padded),
            tracked: vec![0; capacity],
            tracked_count: 0,
            set_changed: true,
            set_mask: 0,
            set_count: 0,
            set_nodes: vec![0; NODE_CAPACITY],
            node_slots: vec![UNSET; NODE_CAPACITY],
            inverse: zeros(NODE_CAPACITY * NODE_CAPACITY),
            inverse_columns: zeros(NODE_CAPACITY * NODE_CAPACITY),
            segments: vec![Span::default(); capacity],
            segment_count: 0,
            segment_stiffness: vec![[[0.0; 4]; 4]; capacity],
            slot_free: zeros(NODE_CAPACITY),
            slot_steps: zeros(NODE_CAPACITY),
            slot_forces: zeros(NODE_CAPACITY),
            node_free_steps_m: zeros(NODE_CAPACITY),
            node_steps_m: zeros(NODE_CAPACITY),
            node_corrections_m: zeros(NODE_CAPACITY),
            point_steps: zeros(padded),
            point_forces: zeros(padded),
            point_stiffnesses: zeros(padded),
            cases: vec![OUT; padded],
            crossing_points: [UNSET; MOST_CROSSINGS],
            matrix: zeros(NODE_CAPACITY * NODE_CAPACITY),
            right_side: zeros(NODE_CAPACITY),
            scratch: zeros(NODE_CAPACITY),
            weighted_row: zeros(MODE_CAPACITY),
            kernels: Kernels::detect(),
            loaded_nodes: vec![0; NODE_CAPACITY],
            loaded_forces_n: zeros(NODE_CAPACITY),
            loaded_count: 0,
            far_point_near: false,
            #[cfg(test)]
            general_path_only: false,
            #[cfg(test)]
            iterate_over_crossings: false,
        }
    }

    /// Makes every update take the general path (the test that the paths agree).
    #[cfg(test)]
    pub(super) fn take_general_path_only(&mut self) {
        self.general_path_only = true;
    }

    /// Leaves steps with several crossing points to Newton's iteration on S (the test that
    /// their finish is the iteration's solution).
    #[cfg(test)]
    pub(super) fn iterate_over_crossings(&mut self) {
        self.iterate_over_crossings = true;
    }

    /// How many nodes the points reach (0: not configured).
    pub fn node_count(&self) -> usize {
        self.node_count
    }

    /// The nodes with a non-zero force change after the last step and the changes, N: what
    /// the modes feel, through the node rows.
    pub fn loaded(&self) -> (&[usize], &[f64]) {
        (
            &self.loaded_nodes[..self.loaded_count],
            &self.loaded_forces_n[..self.loaded_count],
        )
    }

    /// Sets the nodes, their shapes and compliance, and the points' stencils and laws for the
    /// grid of `intervals` intervals on a string of `length` m. Returns false (and configures
    /// nothing) when the stencils reach more than [`NODE_CAPACITY`] nodes. Allocation-free.
    pub fn configure(
        &mut self,
        points: &ContactPoints,
        modes: &ModeSet,
        intervals: usize,
        length: f64,
    ) -> bool {
        self.node_count = 0;
        let count = points.len().min(self.stencil_nodes.len());
        let stencil = |x: f64| lagrange_stencil(x * intervals as f64 / length, intervals);
        // The interior nodes the stencils reach, in order.
        let mut node_count = 0;
        for i in 0..count {
            let (first, _) = stencil(points.positions_m[i]);
            for node in first..first + 4 {
                if node == 0 || node >= intervals || self.grid_nodes[..node_count].contains(&node) {
                    continue;
                }
                if node_count == NODE_CAPACITY {
                    return false;
                }
                self.grid_nodes[node_count] = node;
                node_count += 1;
            }
        }
        self.grid_nodes[..node_count].sort_unstable();
        self.node_count = node_count;
        self.point_count = count;
        let grid_nodes = &self.grid_nodes[..node_count];
        let local = |node: usize| {
            let interior = node.clamp(1, intervals - 1);
            grid_nodes.iter().position(|&n| n == interior).unwrap_or(0)
        };
        for i in 0..count {
            let (first, weights) = stencil(points.positions_m[i]);
            for (j, &weight) in weights.iter().enumerate() {
                let node = first + j;
                let support = node == 0 || node >= intervals;
                self.stencil_nodes[i][j] = local(node);
                self.weight_columns[j][i] = if support { 0.0 } else { weight };
                self.weight_rows[i][j] = self.weight_columns[j][i];
            }
            self.xis[i] = points.laws[i].xi;
            self.psis[i] = points.laws[i].psi;
            self.rest_forces_n[i] = points.rest_forces_n[i];
        }
        // The groups' bands (a point's stencil nodes do not decrease with j), each node's row
        // the sum of the weights the group's points put on it (a support's entry adds zero).
        self.group_count = count.div_ceil(LANES);
        let mut offset = 0;
        for group in 0..self.group_count {
            let points = group * LANES..((group + 1) * LANES).min(count);
            let first_node = points
                .clone()
                .map(|i| self.stencil_nodes[i][0])
                .min()
                .unwrap_or(0);
            let last_node = points
                .clone()
                .map(|i| self.stencil_nodes[i][3])
                .max()
                .unwrap_or(0);
            let nodes = last_node + 1 - first_node;
            let rows = &mut self.group_weights[offset..offset + nodes];
            rows.fill([0.0; LANES]);
            for i in points {
                for j in 0..4 {
                    rows[self.stencil_nodes[i][j] - first_node][i - group * LANES] +=
                        self.weight_columns[j][i];
                }
            }
            self.group_bands[group] = GroupBand {
                first_node,
                nodes,
                offset,
            };
            offset += nodes;
        }
        // The padding lanes never touch.
        self.far_offsets_m[count..].fill(f64::NEG_INFINITY);
        // V and G_N = V diag(b) Vᵀ.
        let modes_count = modes.count();
        for (j, &node) in self.grid_nodes[..node_count].iter().enumerate() {
            let row = &mut self.node_shapes[j * MODE_CAPACITY..(j + 1) * MODE_CAPACITY];
            write_node_row(node, intervals, modes, row);
        }
        let lanes = padded_lanes(modes_count);
        for j in 0..node_count {
            let row_j = &self.node_shapes[j * MODE_CAPACITY..j * MODE_CAPACITY + lanes];
            for ((weighted, v), b) in self.weighted_row.iter_mut().zip(row_j).zip(&modes.b) {
                *weighted = v * b;
            }
            self.kernels.leading_dots(
                &self.node_shapes,
                MODE_CAPACITY,
                &self.weighted_row[..lanes],
                &mut self.scratch[..=j],
            );
            for l in 0..=j {
                self.compliance[j * NODE_CAPACITY + l] = self.scratch[l];
                self.compliance[l * NODE_CAPACITY + j] = self.scratch[l];
            }
        }
        self.node_corrections_m.fill(0.0);
        self.set_changed = true;
        self.set_mask = 0;
        true
    }

    /// Sets the points' rest forces, N (after the rest state is solved for the configuration).
    pub fn set_rest_forces(&mut self, rest_forces_n: &[f64]) {
        let count = self.point_count.min(rest_forces_n.len());
        self.rest_forces_n[..count].copy_from_slice(&rest_forces_n[..count]);
    }

    /// Sets every point's gap from the nodes' displacements from rest `node_displacements_m`:
    /// `a_i = a_rest,i − l_i · y`.
    pub fn gaps_from_nodes(&mut self, rest_gaps_m: &[f64], node_displacements_m: &[f64]) {
        for i in 0..self.point_count {
            let displacement: f64 = (0..4)
                .map(|j| self.weight_columns[j][i] * node_displacements_m[self.stencil_nodes[i][j]])
                .sum();
            self.gaps_m[i] = rest_gaps_m[i] - displacement;
        }
    }

    /// Tracks the points within `band_m` of contact or loaded at rest, from scratch, with the
    /// gaps in `gaps_m` (exact on entry). Forgets the initial guesses.
    pub fn classify(&mut self, band_m: f64) {
        self.tracked_count = 0;
        for i in 0..self.point_count {
            let tracked = self.gaps_m[i] > -band_m || self.rest_forces_n[i] != 0.0;
            self.far_offsets_m[i] = if tracked { f64::NEG_INFINITY } else { 0.0 };
            if tracked {
                self.tracked[self.tracked_count] = i;
                self.tracked_count += 1;
            }
            self.point_forces[i] = self.rest_forces_n[i];
            self.cases[i] = OUT;
        }
        self.node_corrections_m.fill(0.0);
        self.loaded_count = 0;
        self.set_changed = true;
        self.set_mask = 0;
    }

    /// Forgets Newton's initial guesses.
    pub fn forget_corrections(&mut self) {
        self.node_corrections_m.fill(0.0);
    }

    /// S, the nodes the tracked points' stencils reach; the tracked points in order and in
    /// segments; and H = G_SS⁻¹ (by Cholesky; G_SS is a principal block of the positive
    /// definite G_N).
    fn form_set(&mut self) {
        // In order (insertion: the list is nearly sorted, points join and leave at its edges).
        let tracked = &mut self.tracked[..self.tracked_count];
        for t in 1..tracked.len() {
            let mut u = t;
            while u > 0 && tracked[u - 1] > tracked[u] {
                tracked.swap(u - 1, u);
                u -= 1;
            }
        }
        // S in node order, so that it and H are a function of the node set alone: H is formed
        // again only when the set changes, not with every point that joins or leaves.
        let mut mask = 0u64;
        for &i in &self.tracked[..self.tracked_count] {
            for &node in &self.stencil_nodes[i] {
                mask |= 1 << node;
            }
        }
        let new_set = mask != self.set_mask;
        if new_set {
            self.set_mask = mask;
            self.node_slots[..self.node_count].fill(UNSET);
            self.set_count = 0;
            for node in 0..self.node_count {
                if mask & (1 << node) != 0 {
                    self.node_slots[node] = self.set_count;
                    self.set_nodes[self.set_count] = node;
                    self.set_count += 1;
                }
            }
        }
        self.segment_count = 0;
        for t in 0..self.tracked_count {
            let i = self.tracked[t];
            let slots = self.stencil_nodes[i].map(|node| self.node_slots[node]);
            append_to_spans(&mut self.segments, &mut self.segment_count, i, slots);
        }
        self.set_changed = false;
        if new_set {
            self.invert_set_compliance();
        }
    }

    /// H = G_SS⁻¹ by Cholesky (G_SS is a principal block of the positive definite G_N).
    fn invert_set_compliance(&mut self) {
        let m = self.set_count;
        // Cholesky factor of G_SS in `matrix` (lower, stride m), then its inverse column by
        // column into `inverse`.
        for a in 0..m {
            for b in 0..=a {
                let mut sum =
                    self.compliance[self.set_nodes[a] * NODE_CAPACITY + self.set_nodes[b]];
                for k in 0..b {
                    sum -= self.matrix[a * m + k] * self.matrix[b * m + k];
                }
                self.matrix[a * m + b] = if a == b {
                    sum.max(f64::MIN_POSITIVE).sqrt()
                } else {
                    sum / self.matrix[b * m + b]
                };
            }
        }
        for column in 0..m {
            let x = &mut self.right_side;
            x[..m].fill(0.0);
            x[column] = 1.0;
            for a in 0..m {
                let mut sum = x[a];
                for k in 0..a {
                    sum -= self.matrix[a * m + k] * x[k];
                }
                x[a] = sum / self.matrix[a * m + a];
            }
            for a in (0..m).rev() {
                let mut sum = x[a];
                for k in a + 1..m {
                    sum -= self.matrix[k * m + a] * x[k];
                }
                x[a] = sum / self.matrix[a * m + a];
            }
            for a in 0..m {
                self.inverse[a * NODE_CAPACITY + column] = x[a];
            }
            let stored = &mut self.inverse_columns[column * NODE_CAPACITY..][..NODE_CAPACITY];
            stored[..m].copy_from_slice(&x[..m]);
            stored[m..].fill(0.0);
        }
    }

    /// Every tracked point's step, force, c and case at the iterate on S, in chunks of
    /// [`LANES`], and the nodal force change on S; the crossing points in `crossing_points`.
    /// Returns whether a point's case changed since the last evaluation, whether one of them
    /// had been in a linear case (in or out), and how many points cross.
    #[inline(always)]
    fn evaluate(&mut self) -> (bool, bool, usize) {
        self.slot_forces[..self.set_count].fill(0.0);
        let (mut changed, mut left_linear, mut crossings) = (false, false, 0);
        for index in 0..self.segment_count {
            let segment = self.segments[index];
            let y = segment.places.map(|slot| self.slot_steps[slot]);
            let mut force_sums = [0.0; 4];
            let mut start = segment.start;
            while start < segment.end {
                let valid = (segment.end - start).min(LANES);
                let gaps = chunk(&self.gaps_m, start);
                let weights = [
                    chunk(&self.weight_columns[0], start),
                    chunk(&self.weight_columns[1], start),
                    chunk(&self.weight_columns[2], start),
                    chunk(&self.weight_columns[3], start),
                ];
                let (xis, psis) = (chunk(&self.xis, start), chunk(&self.psis, start));
                let (mut steps, mut forces, mut stiffnesses, mut cases) =
                    ([0.0; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
                for l in 0..LANES {
                    let step = weights[0][l] * y[0]
                        + weights[1][l] * y[1]
                        + weights[2][l] * y[2]
                        + weights[3][l] * y[3];
                    (forces[l], stiffnesses[l], cases[l]) =
                        law_lane(gaps[l], step, xis[l], psis[l]);
                    steps[l] = step;
                }
                // Every lane is written (the arrays are padded): a lane past the segment holds
                // a later point, which its own segment writes again if it is tracked, and whose
                // values are not read if it is not.
                let lanes = start..start + LANES;
                self.point_steps[lanes.clone()].copy_from_slice(&steps);
                self.point_forces[lanes.clone()].copy_from_slice(&forces);
                self.point_stiffnesses[lanes].copy_from_slice(&stiffnesses);
                // The cases and the nodal force change of the segment's own lanes, in point
                // order. A point at its rest force adds a zero product, which leaves every sum
                // as it was.
                let rests = chunk(&self.rest_forces_n, start);
                for (l, previous) in self.cases[start..start + valid].iter_mut().enumerate() {
                    let case = cases[l];
                    changed |= case != *previous;
                    left_linear |= case != *previous && *previous != CROSSING;
                    if case == CROSSING {
                        if crossings < MOST_CROSSINGS {
                            self.crossing_points[crossings] = start + l;
                        }
                        crossings += 1;
                    }
                    *previous = case;
                    let change = forces[l] - rests[l];
                    for (sum, weight) in force_sums.iter_mut().zip(self.weight_rows[start + l]) {
                        *sum += weight * change;
                    }
                }
                start += LANES;
            }
            add_at_places(&mut self.slot_forces, segment.places, force_sums);
        }
        (changed, left_linear, crossings)
    }

    /// Each segment's `Σ c w_j w_l` at the last evaluation (only before an update: the
    /// evaluation that ends the iteration needs none), over the points with c > 0, as a whole
    /// 4 × 4 block (rows of four sums vectorise; [`NodalContact::add_stiffnesses`] reads the
    /// [`PAIRS`]), each product formed as `(c w_j) w_l`.
    #[inline(always)]
    fn sum_stiffnesses(&mut self) {
        for (segment, total) in self.segments[..self.segment_count]
            .iter()
            .zip(&mut self.segment_stiffness)
        {
            let mut sums = [[0.0; 4]; 4];
            for i in segment.start..segment.end {
                let stiffness = self.point_stiffnesses[i];
                if stiffness == 0.0 {
                    continue;
                }
                let weights = self.weight_rows[i];
                for (row, &weight) in sums.iter_mut().zip(&weights) {
                    let scaled = stiffness * weight;
                    for (sum, &other) in row.iter_mut().zip(&weights) {
                        *sum += scaled * other;
                    }
                }
            }
            *total = sums;
        }
    }

    /// Newton's iteration on S from the iterate in `slot_steps`. Returns (updates, converged).
    #[inline(always)]
    fn newton<S: Simd>(&mut self, simd: S, settings: &NewtonSettings) -> (u32, bool) {
        let mut time = step_timers::start();
        let (_, _, mut crossings) = self.evaluate();
        time = step_timers::add(StepPart::Evaluate, time);
        let mut updates = 0;
        loop {
            if updates >= settings.max_iterations {
                return (updates, false);
            }
            self.sum_stiffnesses();
            step_timers::add(StepPart::Stiffnesses, time);
            #[cfg(test)]
            let size = if self.general_path_only {
                usize::MAX
            } else {
                self.set_count
            };
            #[cfg(not(test))]
            let size = self.set_count;
            // A few points crossing the contact's edge and every other in a linear case: the
            // update finishes the step (`NodalContact::exact_departure`,
            // `NodalContact::solve_crossings`).
            let tolerance_m = settings.tolerance_m;
            let (largest, finished) = match size {
                0..=8 => self.update_in_lanes::<S, 8>(simd, crossings, tolerance_m),
                9..=16 => self.update_in_lanes::<S, 16>(simd, crossings, tolerance_m),
                _ => self.update_general(crossings, tolerance_m),
            };
            updates += 1;
            time = step_timers::start();
            let (changed, left_linear);
            (changed, left_linear, crossings) = self.evaluate();
            time = step_timers::add(StepPart::Evaluate, time);
            // A finish stands if every point that was in a linear case kept it: the crossing
            // points' law was solved whole, in whichever case each ends.
            if !(changed || crossings > 0)
                || largest <= settings.tolerance_m
                || (finished && !left_linear)
            {
                return (updates, true);
            }
        }
    }

    /// `l_c` of point `c` on the slots of S, into `column` (zeros elsewhere).
    #[inline(always)]
    fn crossing_column(&self, c: usize, column: &mut [f64]) {
        column.fill(0.0);
        for (j, &node) in self.stencil_nodes[c].iter().enumerate() {
            column[self.node_slots[node]] += self.weight_columns[j][c];
        }
    }

    /// `l_c · values` for point `c`: its stencil's four weights on the slots of S.
    #[inline(always)]
    fn along(&self, c: usize, values: &[f64]) -> f64 {
        (0..4)
            .map(|j| self.weight_columns[j][c] * values[self.node_slots[self.stencil_nodes[c][j]]])
            .sum()
    }

    /// The exact finish of a step whose one crossing point is `c` (section 4, in the nodes):
    /// with every other point in a linear case the scheme's equations are
    /// `A (Δy − Δy⁰) = ρ_N + l_c ρ(s_c)`, `A = H + Σ c l lᵀ` at the evaluation, where `ρ(s)` is
    /// the crossing law's departure from its tangent, so `Δy = Δy⁰ + δ + ρ w` with Newton's
    /// update δ and `w = A⁻¹ l_c` (`direction`), and the point's own equation
    /// `s = s⁰ + l_c·δ + (l_c·w) ρ(s)` is the point-level one (`block.rs`,
    /// [`exact_crossing_step`]). Returns ρ at its root, or `None` where neither case holds one.
    #[inline(always)]
    fn exact_departure(&self, c: usize, delta: &[f64], direction: &[f64]) -> Option<f64> {
        exact_crossing_step(CrossingPoint {
            gap: self.gaps_m[c],
            start: self.point_steps[c],
            law: HuntCrossley {
                xi: self.xis[c],
                psi: self.psis[c],
            },
            force: self.point_forces[c],
            stiffness: self.point_stiffnesses[c],
            direction: self.along(c, direction),
            delta: self.along(c, delta),
        })
        .map(|(_, departure)| departure)
        .filter(|departure| departure.is_finite())
    }

    /// Finishes the step whose evaluation found `crossings` points crossing (the rest in a
    /// linear case), given Newton's update `delta` (`m` = |S| entries, zeros after them) and
    /// `substitute`, which solves `A x = b` in place with the update's factors: one point by
    /// [`NodalContact::exact_departure`], two to [`MOST_CROSSINGS`] by
    /// [`NodalContact::solve_crossings`] (in as many lanes, up to six; in eight for seven or
    /// eight). Returns whether it did; `delta` then holds the finished update.
    #[inline(always)]
    fn finish_step<const N: usize>(
        &self,
        substitute: impl Fn(&mut [f64; N]),
        delta: &mut [f64; N],
        crossings: usize,
        tolerance_m: f64,
    ) -> bool {
        let m = self.set_count;
        if crossings == 1 {
            let mut direction = [0.0; N];
            self.crossing_column(self.crossing_points[0], &mut direction[..m]);
            substitute(&mut direction);
            return self.finish_one_crossing(delta, &direction);
        }
        #[cfg(test)]
        if self.iterate_over_crossings {
            return false;
        }
        match crossings {
            2 => self.finish_crossings_with::<N, 2>(&substitute, delta, 2, tolerance_m),
            3 => self.finish_crossings_with::<N, 3>(&substitute, delta, 3, tolerance_m),
            4 => self.finish_crossings_with::<N, 4>(&substitute, delta, 4, tolerance_m),
            5 => self.finish_crossings_with::<N, 5>(&substitute, delta, 5, tolerance_m),
            6 => self.finish_crossings_with::<N, 6>(&substitute, delta, 6, tolerance_m),
            7..=MOST_CROSSINGS => self.finish_crossings_with::<N, MOST_CROSSINGS>(
                &substitute,
                delta,
                crossings,
                tolerance_m,
            ),
            _ => false,
        }
    }

    /// The finish of a step with one crossing point, `crossing_points[0]`, given its direction
    /// `w = A⁻¹ l_c` ([`NodalContact::exact_departure`]). Returns whether it did; `delta` then
    /// holds `δ + ρ w`.
    #[inline(always)]
    fn finish_one_crossing<const N: usize>(
        &self,
        delta: &mut [f64; N],
        direction: &[f64; N],
    ) -> bool {
        let m = self.set_count;
        let c = self.crossing_points[0];
        let Some(departure) = self.exact_departure(c, &delta[..m], &direction[..m]) else {
            return false;
        };
        for (d, w) in delta[..m].iter_mut().zip(&direction[..m]) {
            *d += departure * w;
        }
        true
    }

    /// [`NodalContact::solve_crossings`] on the `k` crossing points' columns `l_d` and their
    /// directions `w_d = A⁻¹ l_d`, each solved by `substitute` (the general path's).
    // Out of line: one function per size, not all sizes in the step (`crate::unroll`).
    #[inline(never)]
    fn finish_crossings_with<const N: usize, const K: usize>(
        &self,
        substitute: &impl Fn(&mut [f64; N]),
        delta: &mut [f64; N],
        k: usize,
        tolerance_m: f64,
    ) -> bool {
        let m = self.set_count;
        let mut columns = [[0.0; N]; K];
        let mut directions = [[0.0; N]; K];
        for ((column, direction), &point) in columns
            .iter_mut()
            .zip(&mut directions)
            .zip(&self.crossing_points[..k])
        {
            self.crossing_column(point, &mut column[..m]);
            *direction = *column;
            substitute(direction);
        }
        self.solve_crossings::<N, K>(&columns, &directions, delta, k, tolerance_m)
    }

    /// Newton's update substituted through the fixed-lane factors `factors`, and the step
    /// finished where its evaluation found `crossings` points crossing
    /// ([`NodalContact::finish_step`]): the update and the crossing points' directions
    /// `w_d = A⁻¹ l_d` are substituted together ([`ldl_substitute_many`], one right side per
    /// vector, the same bits as one by one), so that their dependency chains overlap. Returns
    /// whether the step was finished; `delta` holds Newton's update, or the finished one.
    #[inline(always)]
    fn substitute_and_finish<S: Simd, const N: usize>(
        &self,
        simd: S,
        factors: &[[f64; N]; N],
        delta: &mut [f64; N],
        crossings: usize,
        tolerance_m: f64,
    ) -> bool {
        #[cfg(test)]
        let crossings = if self.iterate_over_crossings && crossings > 1 {
            0
        } else {
            crossings
        };
        match crossings {
            1 => self.finish_in_lanes::<N, 1, 2>(factors, delta, 1, tolerance_m),
            2 => self.finish_out_of_line::<S, N, 2, 3>(simd, factors, delta, 2, tolerance_m),
            3 => self.finish_out_of_line::<S, N, 3, 4>(simd, factors, delta, 3, tolerance_m),
            4 => self.finish_out_of_line::<S, N, 4, 5>(simd, factors, delta, 4, tolerance_m),
            5 => self.finish_out_of_line::<S, N, 5, 6>(simd, factors, delta, 5, tolerance_m),
            6 => self.finish_out_of_line::<S, N, 6, 7>(simd, factors, delta, 6, tolerance_m),
            7..=MOST_CROSSINGS => self
                .finish_out_of_line::<S, N, MOST_CROSSINGS, { MOST_CROSSINGS + 1 }>(
                    simd,
                    factors,
                    delta,
                    crossings,
                    tolerance_m,
                ),
            _ => {
                let time = step_timers::start();
                ldl_substitute_fixed(factors, delta);
                step_timers::add(StepPart::Substitute, time);
                false
            }
        }
    }

    /// [`NodalContact::finish_in_lanes`] for two or more crossing points, kept out of line: one
    /// function per size and vector unit. With every size written into the step, the step was
    /// one function holding them all, and LLVM (whose time on a function grows faster than its
    /// size) took 16 minutes over the core's release build (`crate::unroll`,
    /// `docs/performance.md`, stop 71). The finish of one crossing point stays written into the
    /// step. The call goes through [`Simd::vectorize`], so the finish out of line is compiled for
    /// the step's vector unit `simd`, as it was in the step: a plain call compiles it for the
    /// build's baseline (SSE2 on x86-64), which cost the fine tier 3–9 %.
    #[inline(never)]
    fn finish_out_of_line<S: Simd, const N: usize, const K: usize, const R: usize>(
        &self,
        simd: S,
        factors: &[[f64; N]; N],
        delta: &mut [f64; N],
        k: usize,
        tolerance_m: f64,
    ) -> bool {
        simd.vectorize(FinishInLanes::<N, K, R> {
            contact: self,
            factors,
            delta,
            k,
            tolerance_m,
        })
    }

    /// [`NodalContact::substitute_and_finish`] for `1 ≤ k ≤ K` crossing points in `K` lanes
    /// (`R = K + 1` right sides: Newton's update, then one direction per lane; the lanes past k
    /// substitute zeros, and their directions are kept exactly zero, as the finish one by one
    /// leaves them).
    #[inline(always)]
    fn finish_in_lanes<const N: usize, const K: usize, const R: usize>(
        &self,
        factors: &[[f64; N]; N],
        delta: &mut [f64; N],
        k: usize,
        tolerance_m: f64,
    ) -> bool {
        const { assert!(R == K + 1) };
        let time = step_timers::start();
        let m = self.set_count;
        let mut columns = [[0.0; N]; K];
        for (column, &point) in columns.iter_mut().zip(&self.crossing_points[..k]) {
            self.crossing_column(point, &mut column[..m]);
        }
        let mut sides = [[0.0; N]; R];
        sides[0] = *delta;
        sides[1..].copy_from_slice(&columns);
        ldl_substitute_many(factors, &mut sides);
        *delta = sides[0];
        let mut directions = [[0.0; N]; K];
        directions[..k].copy_from_slice(&sides[1..=k]);
        let time = step_timers::add(StepPart::Substitute, time);
        let finished = if k == 1 {
            self.finish_one_crossing(delta, &directions[0])
        } else {
            self.solve_crossings::<N, K>(&columns, &directions, delta, k, tolerance_m)
        };
        step_timers::add(StepPart::FinishCrossings, time);
        finished
    }

    /// The finish of a step whose `k ≥ 2` crossing points are `crossing_points[..k]`, given
    /// each one's column `l_d` on S (`columns`) and `w_d = A⁻¹ l_d` (`directions`; zero past k),
    /// in `K ≥ k` lanes (`docs/modal-tanpura.md`, section 12, "Several crossing points"): with
    /// every other point in a linear case, `A (Δy − Δy⁰) = ρ_N + Σ_d l_d ρ_d(s_d)`, so
    /// `Δy = Δy⁰ + δ + Σ_d ρ_d w_d` with `w_d = A⁻¹ l_d`, and the k crossing points' steps solve
    ///
    /// `s_c = ŝ_c + Σ_d W_cd ρ_d(s_d)`,   `ŝ_c = s⁰_c + l_c·δ`,   `W_cd = l_c·w_d`,
    ///
    /// where `ρ_d(s) = F_d(s) − F⁰_d + c⁰_d (s − s⁰_d)` is point d's law (in whichever case s puts
    /// it) less its tangent at the evaluation. Newton on these k unknowns from ŝ (Newton's own
    /// point): the Jacobian is `I − W diag(c⁰ − c(s))`, whose leading minors are positive (W is
    /// a principal block of `Lᵀ A⁻¹ L` with `A ⪰ H + L diag(c⁰) Lᵀ`, H positive definite, and
    /// c(s) ≥ 0), so Gaussian elimination needs no pivoting; a pivot that is not positive ends
    /// the finish. It stops when its update is at most `tolerance_m`, at most
    /// [`CROSSING_ITERATION_CAP`] updates, and the lanes past k hold the identity. Returns
    /// whether it converged; `delta` then holds `δ + Σ_d ρ_d w_d`.
    ///
    /// Each iteration costs O(K³) on a few registers, against an update on S (the evaluation
    /// of every tracked point, the stiffness sums and the factorisation) that it replaces.
    #[inline(always)]
    // At some indices of the written-out loops a guard or a range is constant; the compiler
    // folds it.
    #[allow(clippy::absurd_extreme_comparisons, clippy::reversed_empty_ranges)]
    fn solve_crossings<const N: usize, const K: usize>(
        &self,
        columns: &[[f64; N]; K],
        directions: &[[f64; N]; K],
        delta: &mut [f64; N],
        k: usize,
        tolerance_m: f64,
    ) -> bool {
        let m = self.set_count;
        let points = &self.crossing_points[..k];
        let dot = |a: &[f64; N], b: &[f64; N]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
        let mut coupling = [[0.0; K]; K];
        let mut newton_steps = [0.0; K];
        for (c, &point) in points.iter().enumerate() {
            for d in c..k {
                let value = dot(&columns[c], &directions[d]);
                coupling[c][d] = value;
                coupling[d][c] = value;
            }
            newton_steps[c] = self.point_steps[point] + dot(&columns[c], delta);
        }
        let mut steps = newton_steps;
        let mut departures = [0.0; K];
        let mut converged = false;
        for _ in 0..=CROSSING_ITERATION_CAP {
            // Each point's departure at its step, and its slope c⁰ − c(s).
            let mut slopes = [0.0; K];
            for (d, &point) in points.iter().enumerate() {
                let (force, stiffness, _) = law_lane(
                    self.gaps_m[point],
                    steps[d],
                    self.xis[point],
                    self.psis[point],
                );
                let tangent = self.point_stiffnesses[point];
                departures[d] = force - self.point_forces[point]
                    + tangent * (steps[d] - self.point_steps[point]);
                slopes[d] = tangent - stiffness;
            }
            if converged {
                break;
            }
            // The residual and the Jacobian; the padding lanes solve x = 0.
            let mut jacobian = [[0.0; K]; K];
            let mut residual = [0.0; K];
            for c in 0..K {
                let mut value = steps[c] - newton_steps[c];
                for d in 0..K {
                    value -= coupling[c][d] * departures[d];
                    jacobian[c][d] = -coupling[c][d] * slopes[d];
                }
                jacobian[c][c] += 1.0;
                residual[c] = value;
            }
            // Gaussian elimination and back substitution, written out at compile time
            // (`crate::unroll`) so that the K × K system stays in registers.
            let mut smallest_pivot = f64::INFINITY;
            for_each_index!(ascending COLUMN => {
                if const { COLUMN < K } {
                    let pivot = jacobian[COLUMN][COLUMN];
                    smallest_pivot = smallest_pivot.min(pivot);
                    let inverse = 1.0 / pivot;
                    for_each_index!(ascending ROW => {
                        if const { COLUMN < ROW && ROW < K } {
                            let factor = jacobian[ROW][COLUMN] * inverse;
                            for entry in COLUMN + 1..K {
                                jacobian[ROW][entry] -= factor * jacobian[COLUMN][entry];
                            }
                            residual[ROW] -= factor * residual[COLUMN];
                        }
                    });
                }
            });
            // Also ends it on a NaN pivot.
            if smallest_pivot.is_nan() || smallest_pivot <= 0.0 {
                return false;
            }
            let mut largest = 0.0f64;
            for_each_index!(descending ROW => {
                if const { ROW < K } {
                    let mut value = residual[ROW];
                    for entry in ROW + 1..K {
                        value -= jacobian[ROW][entry] * residual[entry];
                    }
                    residual[ROW] = value / jacobian[ROW][ROW];
                    steps[ROW] -= residual[ROW];
                    largest = largest.max(residual[ROW].abs());
                }
            });
            if !largest.is_finite() {
                return false;
            }
            converged = largest <= tolerance_m;
        }
        if !converged || departures.iter().any(|departure| !departure.is_finite()) {
            return false;
        }
        for (departure, direction) in departures.iter().zip(directions) {
            for (value, &w) in delta[..m].iter_mut().zip(direction) {
                *value += departure * w;
            }
        }
        true
    }

    /// One update (N1), `(H + Σ c l lᵀ) δ = f − H (Δy − Δy_free)`, applied to the iterate, in
    /// `N ≥ |S|` fixed lanes padded with the identity (the padding solves δ = 0). Up to 8 and up
    /// to 16 nodes (every step of the bench's scenes). Returns max|δ|, and whether the step was
    /// finished where its evaluation found `crossings` points crossing
    /// ([`NodalContact::finish_step`]).
    #[inline(always)]
    fn update_in_lanes<S: Simd, const N: usize>(
        &mut self,
        simd: S,
        crossings: usize,
        tolerance_m: f64,
    ) -> (f64, bool) {
        let time = step_timers::start();
        let m = self.set_count;
        let mut matrix = [[0.0; N]; N];
        let mut delta = [0.0; N];
        // Δy − Δy_free on S.
        let mut moved = [0.0; N];
        for ((value, step), free) in moved
            .iter_mut()
            .zip(&self.slot_steps[..m])
            .zip(&self.slot_free[..m])
        {
            *value = step - free;
        }
        for (a, row) in matrix.iter_mut().enumerate() {
            if a >= m {
                row[a] = 1.0;
                continue;
            }
            row[..m].copy_from_slice(&self.inverse[a * NODE_CAPACITY..a * NODE_CAPACITY + m]);
        }
        // The right side f − H (Δy − Δy_free) by H's columns: each entry less H_ab (Δy −
        // Δy_free)_b for b in order, the products a row's dot would take in its order, but in N
        // lanes at once: one chain of |S| vector steps instead of |S| chains of |S| dependent
        // scalar ones, which the update waited on (stop 48 in `docs/performance.md`). The
        // padding stays zero.
        delta[..m].copy_from_slice(&self.slot_forces[..m]);
        for (b, &change) in moved[..m].iter().enumerate() {
            let column = &self.inverse_columns[b * NODE_CAPACITY..][..N];
            for (value, &h) in delta.iter_mut().zip(column) {
                *value -= h * change;
            }
        }
        self.add_stiffnesses_fixed(&mut matrix);
        let time = step_timers::add(StepPart::UpdateSetup, time);
        ldl_factor_fixed(&mut matrix);
        step_timers::add(StepPart::Factorise, time);
        let finished =
            self.substitute_and_finish(simd, &matrix, &mut delta, crossings, tolerance_m);
        (self.apply_update(&delta[..m]), finished)
    }

    /// [`NodalContact::update_in_lanes`] on any number of nodes (stride m, lower triangle).
    fn update_general(&mut self, crossings: usize, tolerance_m: f64) -> (f64, bool) {
        let time = step_timers::start();
        let m = self.set_count;
        for a in 0..m {
            let mut rhs = self.slot_forces[a];
            for b in 0..m {
                let h = self.inverse[a * NODE_CAPACITY + b];
                rhs -= h * (self.slot_steps[b] - self.slot_free[b]);
                self.matrix[a * m + b] = h;
            }
            self.right_side[a] = rhs;
        }
        let mut matrix = std::mem::take(&mut self.matrix);
        self.add_stiffnesses(|a, b, value| matrix[a * m + b] += value);
        self.matrix = matrix;
        let time = step_timers::add(StepPart::UpdateSetup, time);
        // The factorisation and the substitution in one.
        ldl_solve_in_place(
            &mut self.matrix[..m * m],
            m,
            &mut self.right_side[..m],
            &mut self.scratch[..m],
        );
        let time = step_timers::add(StepPart::Factorise, time);
        let mut delta = [0.0; NODE_CAPACITY];
        delta[..m].copy_from_slice(&self.right_side[..m]);
        let finished = crossings > 0
            && self.finish_step(
                |x: &mut [f64; NODE_CAPACITY]| {
                    ldl_substitute_in_place(&self.matrix[..m * m], m, &mut x[..m]);
                },
                &mut delta,
                crossings,
                tolerance_m,
            );
        step_timers::add(StepPart::FinishCrossings, time);
        (self.apply_update(&delta[..m]), finished)
    }

    /// Adds each segment's `Σ c w_j w_l` to a fixed-lane matrix (upper triangle: `matrix[b][a]`,
    /// a ≥ b). A segment whose places are four consecutive slots adds its whole 4 × 4 block row
    /// by row (vector adds; the entries below the diagonal that this fills never reach the
    /// factors or the solution: [`ldl_factor_fixed`] forms those lanes and drops them, and
    /// [`ldl_substitute_fixed`] selects them away); one whose stencil names a node twice (a
    /// support's entry) adds its pairs one by one. Every other entry receives the same sums in
    /// the same order as through [`NodalContact::add_stiffnesses`].
    #[inline(always)]
    fn add_stiffnesses_fixed<const N: usize>(&self, matrix: &mut [[f64; N]; N]) {
        for (segment, sums) in self.segments[..self.segment_count]
            .iter()
            .zip(&self.segment_stiffness)
        {
            match consecutive_start(segment.places) {
                Some(first) if first + 4 <= N => {
                    for (row, row_sums) in matrix[first..first + 4].iter_mut().zip(sums) {
                        for (value, sum) in row[first..first + 4].iter_mut().zip(row_sums) {
                            *value += sum;
                        }
                    }
                }
                _ => add_pairs(segment.places, sums, |a, b, value| matrix[b][a] += value),
            }
        }
    }

    /// Calls `add(a, b, value)` with each segment's `Σ c w_j w_l` at its slots, a ≥ b: entry
    /// (a, b) of the symmetric matrix, which the fixed-lane solver reads in its upper triangle
    /// and the general one in its lower.
    #[inline(always)]
    fn add_stiffnesses(&self, mut add: impl FnMut(usize, usize, f64)) {
        for (segment, sums) in self.segments[..self.segment_count]
            .iter()
            .zip(&self.segment_stiffness)
        {
            add_pairs(segment.places, sums, &mut add);
        }
    }

    /// Adds `delta` to the iterate on S; returns max|δ|.
    #[inline(always)]
    fn apply_update(&mut self, delta: &[f64]) -> f64 {
        let mut largest = 0.0f64;
        for (step, &change) in self.slot_steps.iter_mut().zip(delta) {
            *step += change;
            largest = largest.max(change.abs());
        }
        largest
    }

    /// One step's contact with the nodes' free steps in `node_free_steps_m`: Newton on S, then
    /// every point's step, a far point that would touch joining and the solve redone; the gaps
    /// move and the tracking follows (`band_m`, `release_m`). Leaves the nodal force changes in
    /// [`NodalContact::loaded`].
    #[inline(always)]
    pub fn step<S: Simd>(
        &mut self,
        simd: S,
        settings: &NewtonSettings,
        track_energy: bool,
        band_m: f64,
        release_m: f64,
    ) -> NodalOutcome {
        let n = self.node_count;
        let mut iterations = 0;
        let mut converged = true;
        loop {
            let time = step_timers::start();
            if self.set_changed {
                self.form_set();
            }
            step_timers::add(StepPart::FormSet, time);
            let m = self.set_count;
            for slot in 0..m {
                let node = self.set_nodes[slot];
                self.slot_free[slot] = self.node_free_steps_m[node];
                self.slot_steps[slot] =
                    self.node_free_steps_m[node] + self.node_corrections_m[node];
            }
            if self.tracked_count > 0 {
                let (updates, done) = self.newton(simd, settings);
                iterations += updates;
                converged &= done;
            }
            let time = step_timers::start();
            // Every node's step: S's from Newton, the others' from the forces on S.
            for node in 0..n {
                let slot = self.node_slots[node];
                self.node_steps_m[node] = if slot != UNSET {
                    self.slot_steps[slot]
                } else {
                    let coupled: f64 = (0..m)
                        .map(|s| {
                            self.compliance[node * NODE_CAPACITY + self.set_nodes[s]]
                                * self.slot_forces[s]
                        })
                        .sum();
                    self.node_free_steps_m[node] + coupled
                };
            }
            // Every point's gap after the step; whether an untracked one would touch, and
            // whether one then lies within the band.
            // Each lane's largest `a_i` among the untracked points (the tracked ones' offset is
            // −∞): one of them touches if it is positive, lies within the band if above −band.
            let time = step_timers::add(StepPart::NodeSteps, time);
            let mut reach = [f64::NEG_INFINITY; LANES];
            for (group, band) in self.group_bands[..self.group_count].iter().enumerate() {
                let start = group * LANES;
                // Each point's step summed over the band's nodes in order: the zero weights
                // add exact zeros, so the sum is its stencil's four products, left to right.
                let mut steps = [0.0; LANES];
                let rows = &self.group_weights[band.offset..band.offset + band.nodes];
                let nodes = &self.node_steps_m[band.first_node..band.first_node + band.nodes];
                for (row, &y) in rows.iter().zip(nodes) {
                    for (step, &weight) in steps.iter_mut().zip(row) {
                        *step += weight * y;
                    }
                }
                let (gaps, offsets) = (
                    chunk(&self.gaps_m, start),
                    chunk(&self.far_offsets_m, start),
                );
                let mut next = [0.0; LANES];
                for l in 0..LANES {
                    next[l] = gaps[l] - steps[l];
                    reach[l] = reach[l].max(next[l] + offsets[l]);
                }
                self.next_gaps_m[start..start + LANES].copy_from_slice(&next);
            }
            step_timers::add(StepPart::PointPass, time);
            let touches = reach.iter().any(|&r| r > 0.0);
            let near = reach.iter().any(|&r| r > -band_m);
            self.far_point_near = near;
            if !touches {
                break;
            }
            for i in 0..self.point_count {
                if self.far_offsets_m[i] == 0.0 && self.next_gaps_m[i] > 0.0 {
                    self.far_offsets_m[i] = f64::NEG_INFINITY;
                    self.tracked[self.tracked_count] = i;
                    self.tracked_count += 1;
                    self.point_forces[i] = 0.0;
                    self.cases[i] = OUT;
                }
            }
            // The redone solve starts from this one's nodal steps.
            for node in 0..n {
                self.node_corrections_m[node] =
                    self.node_steps_m[node] - self.node_free_steps_m[node];
            }
            self.set_changed = true;
        }
        let time = step_timers::start();
        // The outcome, the nodal loads and the initial guess of the next step.
        let mut damping_loss_j = 0.0;
        let mut penetration_m = 0.0f64;
        let mut force_change_n = 0.0;
        for &i in &self.tracked[..self.tracked_count] {
            force_change_n += self.point_forces[i] - self.rest_forces_n[i];
            if track_energy {
                let law = HuntCrossley {
                    xi: self.xis[i],
                    psi: self.psis[i],
                };
                damping_loss_j += law.linear_damping_loss(self.gaps_m[i], self.point_steps[i]);
            }
            // The tracked points' gaps from Newton's steps (the pass's arithmetic too).
            let gap = self.gaps_m[i] - self.point_steps[i];
            self.next_gaps_m[i] = gap;
            penetration_m = penetration_m.max(gap);
        }
        std::mem::swap(&mut self.gaps_m, &mut self.next_gaps_m);
        self.loaded_count = 0;
        for slot in 0..self.set_count {
            let force = self.slot_forces[slot];
            if force != 0.0 {
                self.loaded_nodes[self.loaded_count] = self.set_nodes[slot];
                self.loaded_forces_n[self.loaded_count] = force;
                self.loaded_count += 1;
            }
        }
        for node in 0..n {
            self.node_corrections_m[node] = if self.node_slots[node] != UNSET {
                self.node_steps_m[node] - self.node_free_steps_m[node]
            } else {
                0.0
            };
        }
        let time = step_timers::add(StepPart::Outcome, time);
        self.update_tracking(band_m, release_m);
        step_timers::add(StepPart::Tracking, time);
        NodalOutcome {
            iterations,
            converged,
            damping_loss_j,
            penetration_m,
            force_change_n,
        }
    }

    /// Tracked points farther than `release_m` from contact with no force now and none at rest
    /// leave; untracked points within `band_m` join.
    fn update_tracking(&mut self, band_m: f64, release_m: f64) {
        let mut t = 0;
        while t < self.tracked_count {
            let i = self.tracked[t];
            let far = self.gaps_m[i] < -release_m
                && self.point_forces[i] == 0.0
                && self.rest_forces_n[i] == 0.0;
            if far {
                self.tracked_count -= 1;
                self.tracked[t] = self.tracked[self.tracked_count];
                self.far_offsets_m[i] = 0.0;
                self.set_changed = true;
            } else {
                t += 1;
            }
        }
        if self.far_point_near {
            for i in 0..self.point_count {
                if self.far_offsets_m[i] == 0.0 && self.gaps_m[i] > -band_m {
                    self.far_offsets_m[i] = f64::NEG_INFINITY;
                    self.tracked[self.tracked_count] = i;
                    self.tracked_count += 1;
                    self.point_forces[i] = 0.0;
                    self.cases[i] = OUT;
                }
            }
            self.set_changed = true;
        }
    }
}

/// [`NodalContact::finish_in_lanes`] as an operation for [`Simd::vectorize`]
/// ([`NodalContact::finish_out_of_line`]).
struct FinishInLanes<'a, const N: usize, const K: usize, const R: usize> {
    contact: &'a NodalContact,
    factors: &'a [[f64; N]; N],
    delta: &'a mut [f64; N],
    k: usize,
    tolerance_m: f64,
}

impl<const N: usize, const K: usize, const R: usize> WithSimd for FinishInLanes<'_, N, K, R> {
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) -> bool {
        self.contact
            .finish_in_lanes::<N, K, R>(self.factors, self.delta, self.k, self.tolerance_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The node rows read from the grid's sines are the recurrence's, to round-off, at every
    /// node of the reference's grid (N = 200, the fine tier's) and of an odd one; a row read at
    /// another index than `k n mod 2N` fails.
    #[test]
    fn node_rows_from_the_grid_sines_are_the_recurrences() {
        for intervals in [200, 37] {
            let mut config = super::super::tests::grid_mode_config(0.36e-3, 0.2e-3, true);
            if let Some(grid) = &mut config.grid_modes {
                grid.intervals = intervals;
            }
            let string = super::super::ModalString::<f64>::new(config);
            let modes = &string.modes;
            assert!(modes.grid_sines(intervals).is_some());
            assert!(modes.count() > intervals / 2);
            // A sine times its mode's 1/√κ is at most the largest of those.
            let largest = modes
                .inverse_root_stiffness
                .iter()
                .fold(0.0f64, |m, v| m.max(*v));
            let (mut table, mut recurrence) = (vec![0.0; MODE_CAPACITY], vec![0.0; MODE_CAPACITY]);
            for node in 0..=intervals {
                write_node_row(node, intervals, modes, &mut table);
                write_node_row_by_recurrence(node, intervals, modes, &mut recurrence);
                for (k, (a, b)) in table.iter().zip(&recurrence).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-12 * largest,
                        "N = {intervals}, node {node}, mode {}: {a:e} against {b:e}",
                        k + 1
                    );
                }
            }
        }
    }

    /// The branch-free law is `contact.rs`'s mid-point force with the linearly implicit damping
    /// in each of its four cases (staying in, leaving, entering, staying out), force and
    /// stiffness, to round-off; and it names the case.
    #[test]
    fn the_lane_law_is_the_contact_law() {
        let law = HuntCrossley {
            xi: 1.3e3,
            psi: 40.0,
        };
        for (gap, step, case) in [
            (2e-6, 0.5e-6, IN),
            (2e-6, -3e-6, IN),
            (1e-6, 3e-6, CROSSING),
            (-1e-6, -2.5e-6, CROSSING),
            (-1e-6, 0.5e-6, OUT),
            (-1e-6, 0.0, OUT),
        ] {
            let expected = law.midpoint_force_linear_damping(gap, step);
            let (force, stiffness, named) = law_lane(gap, step, law.xi, law.psi);
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-30);
            assert!(
                close(force, expected.force),
                "{gap} {step}: {force} {}",
                expected.force
            );
            assert!(
                close(stiffness, expected.stiffness),
                "{gap} {step}: {stiffness} {}",
                expected.stiffness
            );
            assert_eq!(named, case, "{gap} {step}");
        }
    }

    /// The fixed-lane matrix gets each segment's block as the pair-by-pair scatter gives it,
    /// bit for bit on every entry the factorisation reads (the upper triangle): four consecutive
    /// places by rows, a stencil that names a support's node twice pair by pair, at the edge of
    /// the lanes too; and the slots' force sums likewise.
    #[test]
    fn whole_row_scatter_is_the_pairwise_scatter() {
        let mut contact = NodalContact::new(8);
        let places = [
            [0, 1, 2, 3],
            [1, 2, 3, 4],
            [0, 0, 1, 2],
            [4, 5, 6, 7],
            [5, 6, 7, 7],
        ];
        contact.segment_count = places.len();
        for (s, places) in places.into_iter().enumerate() {
            contact.segments[s] = Span {
                start: s,
                end: s + 1,
                places,
            };
            // Weights of a cubic stencil with the point's own offset, c of the point's own size.
            let offset = 0.1 + 0.17 * s as f64;
            let weights = [
                -offset * (1.0 - offset) * (2.0 - offset) / 6.0,
                (1.0 + offset) * (1.0 - offset) * (2.0 - offset) / 2.0,
                (1.0 + offset) * offset * (2.0 - offset) / 2.0,
                -(1.0 + offset) * offset * (1.0 - offset) / 6.0,
            ];
            let stiffness = 1.3e5 * (1.0 + s as f64);
            contact.segment_stiffness[s] =
                weights.map(|w_j| weights.map(|w_l| stiffness * w_j * w_l));
        }
        let start: [[f64; 8]; 8] =
            std::array::from_fn(|b| std::array::from_fn(|a| 1.0 / (1.0 + a as f64 + b as f64)));
        let (mut by_rows, mut by_pairs) = (start, start);
        contact.add_stiffnesses_fixed(&mut by_rows);
        contact.add_stiffnesses(|a, b, value| by_pairs[b][a] += value);
        for b in 0..8 {
            for a in b..8 {
                assert_eq!(
                    by_rows[b][a].to_bits(),
                    by_pairs[b][a].to_bits(),
                    "({a}, {b})"
                );
            }
        }
        let mut sliced = [0.25; 8];
        let mut one_by_one = sliced;
        for (s, places) in places.into_iter().enumerate() {
            let sums = [1.0, -2.0, 3.0, -4.0].map(|v| v / (3.0 + s as f64));
            add_at_places(&mut sliced, places, sums);
            for (place, sum) in places.into_iter().zip(sums) {
                one_by_one[place] += sum;
            }
        }
        assert_eq!(sliced.map(f64::to_bits), one_by_one.map(f64::to_bits));
    }

    /// The pass after Newton that forms every point's gap by groups of [`LANES`] over bands of
    /// nodes: over two plucks on the fine tier's points, after every step each point's gap is
    /// its gap before less its stencil's four products with the nodes' steps, left to right,
    /// bit for bit (the band's other nodes add exact zeros); every point left untracked lies
    /// farther than the tracking band from contact (the lane maxima flagged the ones that came
    /// near, and they joined); and untracked points did join during the run. With the flag
    /// switched off, it fails at step 161 (point 35 left untracked 1.1 µm from contact).
    #[test]
    fn the_gap_pass_by_groups_forms_each_points_stencil_step() {
        use super::super::tests::grid_mode_config;
        use super::super::{ModalString, TRACKING_BAND_M};
        use crate::tanpura::excitation::Pluck;
        let mut string = ModalString::<f64>::new(grid_mode_config(0.36e-3, 0.2e-3, true));
        assert!(string.nodal_in_use);
        let count = string.nodal.point_count;
        assert!(count > 2 * LANES, "{count} points");
        let (mut joined, mut checked) = (0, 0);
        for amplitude_m in [2e-3, 4e-3] {
            string.pluck(&Pluck {
                amplitude_m,
                ..Pluck::default()
            });
            for step in 0..4410 {
                let before = string.nodal.gaps_m[..count].to_vec();
                let untracked_before: Vec<bool> = (0..count)
                    .map(|i| string.nodal.far_offsets_m[i] == 0.0)
                    .collect();
                string.step();
                let nodal = &string.nodal;
                for i in 0..count {
                    let moved = (0..4).fold(0.0, |sum, j| {
                        sum + nodal.weight_columns[j][i]
                            * nodal.node_steps_m[nodal.stencil_nodes[i][j]]
                    });
                    let expected = before[i] - moved;
                    assert_eq!(
                        nodal.gaps_m[i].to_bits(),
                        expected.to_bits(),
                        "step {step}, point {i}: {} against {expected}",
                        nodal.gaps_m[i]
                    );
                    let untracked = nodal.far_offsets_m[i] == 0.0;
                    assert!(
                        !untracked || nodal.gaps_m[i] <= -TRACKING_BAND_M,
                        "step {step}, point {i} untracked at gap {}",
                        nodal.gaps_m[i]
                    );
                    joined += usize::from(untracked_before[i] && !untracked);
                    checked += 1;
                }
            }
        }
        assert!(joined > 0 && checked > 0, "{joined} joins");
    }
}
