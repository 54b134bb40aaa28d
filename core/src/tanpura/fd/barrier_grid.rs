//! A barrier (bridge, thread or finger) on its own fine grid, tied to the string grid by
//! third-order Lagrange interpolation.
//!
//! Source: seed 000, eq. 17–25. Each barrier point `x_i` (spacing Δx_b) has a height
//! `y_barrier(x_i)`; the string's displacement and step there are `ỹ = I y` and `s̃ = I s`,
//! with `I` the four-point (cubic) Lagrange interpolation from the string nodes (eq. 17, 23).
//! Forces go back with the scaled transpose `I* = (Δx_b/Δx) Iᵀ` (eq. 20–21), which makes the
//! work done on the string, `Δx (I* f̃)·s = Δx_b f̃·s̃`, equal to the work done by the barrier:
//! the energy balance stays exact. The barrier's Jacobian contribution is `I* C I` (eq. 24) with
//! `C = diag(c_i)`, `c_i = −∂f̃_i/∂s̃_i ≥ 0` (eq. 25), symmetric and positive semi-definite.
//!
//! Stencils that reach the fixed end nodes read their boundary values (the lowered support);
//! forces and Jacobian entries at fixed nodes are dropped, since those nodes do not move and
//! their step is zero, which costs nothing in the energy balance. Each point therefore keeps a
//! second, "free" copy of its stencil for everything that acts on the step `s` (zero at the
//! fixed nodes): the weights of fixed nodes set to zero and the four nodes shifted inside
//! `1..=N−1`, so that the per-iteration loops need no boundary tests (`s̃ = I s` is unchanged,
//! since the dropped terms multiply zeros).

use crate::banded::SymmetricBanded;
use crate::tanpura::contact::{potential_density, HuntCrossley};
use crate::tanpura::fd::kernels::{Kernels, StencilSegment};
use pulp::{Simd, WithSimd};

/// One barrier: its points, shape, contact law and per-step work arrays.
#[derive(Debug, Clone)]
pub struct BarrierGrid {
    spacing_m: f64,
    count: usize,
    /// N of the string grid (nodes 0 and N are fixed).
    string_intervals: usize,
    /// Δx_b/Δx, the factor of the scaled transpose (eq. 21).
    transpose_scale: f64,
    stiffness_n_m2: f64,
    damping_s_m: f64,
    law: HuntCrossley,
    positions_m: Vec<f64>,
    heights_m: Vec<f64>,
    stencil_first_node: Vec<usize>,
    stencil_weights: Vec<[f64; 4]>,
    /// The same weights by column (`weight_columns[j][i] = stencil_weights[i][j]`), and the runs
    /// of consecutive points that share a stencil: the layout of the vectorised gap pass.
    weight_columns: [Vec<f64>; 4],
    segments: Vec<StencilSegment>,
    segment_count: usize,
    /// Per segment, what bounds its points' gaps from above without visiting them
    /// ([`SegmentBound`]), and the segments the current step visits.
    segment_bounds: Vec<SegmentBound>,
    near_segments: Vec<StencilSegment>,
    near_segment_count: usize,
    kernels: Kernels,
    /// The free stencil: first node in `1..=N−4` and weights with fixed nodes zeroed.
    free_first_node: Vec<usize>,
    free_weights: Vec<[f64; 4]>,
    /// Per point, the free stencil's terms of `I* C I` and `I* f̃` for unit `c` and `f̃`
    /// ([`StencilProducts`]).
    stencil_products: Vec<StencilProducts>,
    /// a_i = y_barrier − ỹ^n: positive means the string penetrates the barrier.
    gaps_m: Vec<f64>,
    steps_m: Vec<f64>,
    forces: Vec<f64>,
    jacobian: Vec<f64>,
    squared_gap_changes: Vec<f64>,
    /// Points that may touch during the current step (see [`BarrierGrid::begin_step`]).
    candidates: Vec<usize>,
    candidate_count: usize,
    /// The free nodes the candidates' stencils reach, `first..=last` (empty: first > last).
    candidate_nodes: (usize, usize),
    /// max_i Σ_j |w_ij|: bounds |s̃_i| ≤ lebesgue · max_m |s_m| over the stencil nodes.
    lebesgue: f64,
}

/// The interpolated step `w · s[first..first + 4]` of a free stencil.
#[inline(always)]
fn step_at(weights: &[f64; 4], step: &[f64], first: usize) -> f64 {
    dot4(weights, &step[first..])
}

/// `w · v[..4]`, the four-point stencil sum (one bounds check, the products in order).
#[inline(always)]
fn dot4(weights: &[f64; 4], values: &[f64]) -> f64 {
    let v = &values[..4];
    weights[0] * v[0] + weights[1] * v[1] + weights[2] * v[2] + weights[3] * v[3]
}

/// Entries of the lower triangle of a four-node stencil's `w wᵀ`, in the order (0,0), (1,0),
/// (1,1), (2,0), …, (3,3): entry (j, k) at `j(j+1)/2 + k`.
const TRIANGLE_TERMS: usize = 10;

/// What one barrier point adds to the condensed Newton system per unit of its law's results,
/// on the four nodes of its free stencil: the lower triangle of `I* C I` for `c = 1`
/// (`scale · w_j w_k`, [`TRIANGLE_TERMS`] of them) and then `I* f̃` for `f̃ = 1`
/// (`scale · w_j`), padded to sixteen: two AVX-512 vectors (four AVX2), so that a point's
/// contribution is three (five) multiply-adds into running sums ([`ContactIntoBand`]).
#[derive(Debug, Clone, Copy, Default)]
#[repr(align(64))]
struct StencilProducts([f64; 16]);

impl StencilProducts {
    fn of(weights: &[f64; 4], scale: f64) -> Self {
        let mut terms = [0.0; 16];
        let mut index = 0;
        for j in 0..4 {
            for k in 0..=j {
                terms[index] = scale * weights[j] * weights[k];
                index += 1;
            }
        }
        for (term, weight) in terms[TRIANGLE_TERMS..].iter_mut().zip(weights) {
            *term = scale * weight;
        }
        Self(terms)
    }
}

/// The fused contact pass of the condensed Newton update ([`BarrierGrid::evaluate_into_band`]):
/// the law at every candidate, and `I* f̃`, `I* C I` summed over the points that share a free
/// stencil (they are consecutive: candidates are in order along the string) before each sum is
/// added to the node forces and the band, instead of each point's fourteen terms being added
/// to memory one point after the other. The running sums are vector registers: with eight
/// lanes, the triangle's sixteen terms in two and the forces' in one (lanes 8..16 of
/// [`StencilProducts`]); with four, the triangle in three and the forces in two. Other units
/// add each point's terms as before ([`ContactIntoBand::sum_by_point`]). The law itself stays
/// scalar. With this pass the reference tier's whole step runs 10 % faster at key 64
/// (`docs/performance.md`, "Stop 31"); kept as fourteen scalar sums in the generic build, it
/// was slower (stop 26: they spill from SSE2's sixteen registers).
struct ContactIntoBand<'a> {
    grid: &'a BarrierGrid,
    step: &'a [f64],
    node_forces: &'a mut [f64],
    band: &'a mut [[f64; 4]],
    band_first_node: usize,
}

impl ContactIntoBand<'_> {
    /// Adds the sums of the points whose free stencil starts at `first`: the triangle's from
    /// `stiffness_sums`, the node forces' from `force_sums` (both laid out as
    /// [`StencilProducts`]).
    #[inline(always)]
    fn add_stencil_sums(
        &mut self,
        first: usize,
        stiffness_sums: &[f64; 16],
        force_sums: &[f64; 16],
    ) {
        let nodes = &mut self.node_forces[first..first + 4];
        for (node, sum) in nodes.iter_mut().zip(&force_sums[TRIANGLE_TERMS..]) {
            *node += sum;
        }
        // Row j of the block holds entry (j, k) at offset j − k.
        let rows = &mut self.band[first - self.band_first_node..][..4];
        let mut index = 0;
        for (j, row) in rows.iter_mut().enumerate() {
            for k in 0..=j {
                row[j - k] += stiffness_sums[index];
                index += 1;
            }
        }
    }
}

impl WithSimd for ContactIntoBand<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(mut self, simd: S) {
        let grid = self.grid;
        let step = self.step;
        let candidates = &grid.candidates[..grid.candidate_count];
        let (free_first, free_weights) = (&grid.free_first_node[..], &grid.free_weights[..]);
        let (gaps, products, law) = (&grid.gaps_m[..], &grid.stencil_products[..], grid.law);
        // Sixteen terms in two vectors of eight lanes or four of four; other units add each
        // point's terms as scalars.
        let lanes = S::F64_LANES;
        if lanes != 8 && lanes != 4 {
            return self.sum_by_point(law);
        }
        let zero = simd.splat_f64s(0.0);
        let (mut c0, mut c1, mut c2) = (zero, zero, zero);
        let (mut f1, mut f2, mut f3) = (zero, zero, zero);
        let mut summed_stencil = None;
        for &i in candidates {
            let first = free_first[i];
            let point_step = step_at(&free_weights[i], step, first);
            let contact = law.midpoint_force(gaps[i], point_step);
            if contact.stiffness == 0.0 && contact.force == 0.0 {
                continue;
            }
            if summed_stencil != Some(first) {
                if let Some(previous) = summed_stencil {
                    self.flush::<S>(previous, [c0, c1, c2], [f1, f2, f3]);
                    (c0, c1, c2, f1, f2, f3) = (zero, zero, zero, zero, zero, zero);
                }
                summed_stencil = Some(first);
            }
            let (terms, _) = S::as_simd_f64s(&products[i].0);
            let stiffness = simd.splat_f64s(contact.stiffness);
            let force = simd.splat_f64s(contact.force);
            if lanes == 8 {
                // Terms 0..8 and 8..16: the triangle in both, the forces in the second.
                c0 = simd.mul_add_e_f64s(stiffness, terms[0], c0);
                c1 = simd.mul_add_e_f64s(stiffness, terms[1], c1);
                f1 = simd.mul_add_e_f64s(force, terms[1], f1);
            } else {
                // Terms 0..4, 4..8, 8..12, 12..16: the triangle in the first three, the forces
                // in the last two.
                c0 = simd.mul_add_e_f64s(stiffness, terms[0], c0);
                c1 = simd.mul_add_e_f64s(stiffness, terms[1], c1);
                c2 = simd.mul_add_e_f64s(stiffness, terms[2], c2);
                f2 = simd.mul_add_e_f64s(force, terms[2], f2);
                f3 = simd.mul_add_e_f64s(force, terms[3], f3);
            }
        }
        if let Some(previous) = summed_stencil {
            self.flush::<S>(previous, [c0, c1, c2], [f1, f2, f3]);
        }
    }
}

impl ContactIntoBand<'_> {
    /// Stores the vector sums in [`StencilProducts`]'s layout and adds them: with eight lanes,
    /// `stiffness_sums[0..2]` are chunks 0–1 and `force_sums[0]` is chunk 1; with four,
    /// `stiffness_sums` are chunks 0–2 and `force_sums[1..3]` are chunks 2–3.
    #[inline(always)]
    fn flush<S: Simd>(
        &mut self,
        first: usize,
        stiffness_sums: [S::f64s; 3],
        force_sums: [S::f64s; 3],
    ) {
        let (mut stiffness, mut force) = ([0.0; 16], [0.0; 16]);
        let lanes = S::F64_LANES;
        {
            let (stiffness_out, _) = S::as_mut_simd_f64s(&mut stiffness);
            let (force_out, _) = S::as_mut_simd_f64s(&mut force);
            if lanes == 8 {
                stiffness_out[0] = stiffness_sums[0];
                stiffness_out[1] = stiffness_sums[1];
                force_out[1] = force_sums[0];
            } else {
                stiffness_out[..3].copy_from_slice(&stiffness_sums);
                force_out[2] = force_sums[1];
                force_out[3] = force_sums[2];
            }
        }
        self.add_stencil_sums(first, &stiffness, &force);
    }

    /// The same sums one point at a time, for units of other widths than eight or four lanes.
    fn sum_by_point(&mut self, law: HuntCrossley) {
        let grid = self.grid;
        for &i in &grid.candidates[..grid.candidate_count] {
            let first = grid.free_first_node[i];
            let point_step = step_at(&grid.free_weights[i], self.step, first);
            let contact = law.midpoint_force(grid.gaps_m[i], point_step);
            if contact.stiffness == 0.0 && contact.force == 0.0 {
                continue;
            }
            let terms = &grid.stencil_products[i].0;
            let mut stiffness = [0.0; 16];
            let mut force = [0.0; 16];
            for k in 0..16 {
                stiffness[k] = contact.stiffness * terms[k];
                force[k] = contact.force * terms[k];
            }
            self.add_stencil_sums(first, &stiffness, &force);
        }
    }
}

/// Added to a segment's gap bound before it is compared with the candidate margin: far above
/// the round-off of the bound and of the gaps themselves (about 1e-19 m for millimetre
/// displacements). It only makes a segment count as near sooner, never skips a candidate.
const GAP_BOUND_SLACK_M: f64 = 1e-12;

/// An upper bound on the gaps `a_i = h_i − Σ_j w_ij y_j` of a segment's points (one stencil,
/// nodes `y_0..y_3`) from four node values. With `y_j = y_1 + d_j`,
/// `Σ_j w_ij y_j = y_1 Σ_j w_ij + Σ_j w_ij d_j ≥ min(y_1 σ_min, y_1 σ_max) + Σ_j min(w_j,min d_j,
/// w_j,max d_j)`, where `σ` is the weights' sum and `w_j,min`, `w_j,max` the extremes of column
/// j over the segment; so `a_i ≤ h_max − that`. Relative to node 1 the terms are the string's
/// local differences, so the bound is tight where the string is smooth.
#[derive(Debug, Clone, Copy, Default)]
struct SegmentBound {
    height_max: f64,
    sum_min: f64,
    sum_max: f64,
    weight_min: [f64; 4],
    weight_max: [f64; 4],
}

impl SegmentBound {
    fn of(heights: &[f64], weights: &[[f64; 4]]) -> Self {
        let mut bound = Self {
            height_max: f64::NEG_INFINITY,
            sum_min: f64::INFINITY,
            sum_max: f64::NEG_INFINITY,
            weight_min: [f64::INFINITY; 4],
            weight_max: [f64::NEG_INFINITY; 4],
        };
        for (height, w) in heights.iter().zip(weights) {
            bound.height_max = bound.height_max.max(*height);
            let sum: f64 = w.iter().sum();
            bound.sum_min = bound.sum_min.min(sum);
            bound.sum_max = bound.sum_max.max(sum);
            for j in 0..4 {
                bound.weight_min[j] = bound.weight_min[j].min(w[j]);
                bound.weight_max[j] = bound.weight_max[j].max(w[j]);
            }
        }
        bound
    }

    /// The bound on the segment's gaps for the stencil's node values `nodes` (four).
    #[inline(always)]
    fn largest_gap(&self, nodes: &[f64]) -> f64 {
        let reference = nodes[1];
        let mut lowest = (reference * self.sum_min).min(reference * self.sum_max);
        for j in 0..4 {
            let difference = nodes[j] - reference;
            lowest += (self.weight_min[j] * difference).min(self.weight_max[j] * difference);
        }
        self.height_max - lowest
    }
}

/// The stencil `first, weights` restricted to the free nodes `1..=N−1` of a string of
/// `intervals` intervals: weights on fixed nodes zeroed, the four nodes shifted inside.
/// Needs N ≥ 5, so that four free nodes exist.
fn free_stencil(first: usize, weights: [f64; 4], intervals: usize) -> (usize, [f64; 4]) {
    debug_assert!(intervals >= 5, "a free stencil needs four free nodes");
    let last_free = intervals - 1;
    let free_first = first.clamp(1, last_free.saturating_sub(3).max(1));
    let mut free = [0.0; 4];
    for (j, weight) in weights.iter().enumerate() {
        let node = first + j;
        if (1..=last_free).contains(&node) && node >= free_first && node < free_first + 4 {
            free[node - free_first] = *weight;
        }
    }
    (free_first, free)
}

/// Cubic Lagrange weights on the nodes `first..first + 4` for the point `x` (in units of Δx).
/// The stencil is the two nodes on each side where possible, shifted inwards at the ends.
pub fn lagrange_stencil(position_in_intervals: f64, intervals: usize) -> (usize, [f64; 4]) {
    let below = position_in_intervals.floor() as isize;
    let first = (below - 1).clamp(0, intervals as isize - 3) as usize;
    let t = position_in_intervals - first as f64;
    let mut weights = [0.0; 4];
    for (j, weight) in weights.iter_mut().enumerate() {
        let mut value = 1.0;
        for k in 0..4 {
            if k != j {
                value *= (t - k as f64) / (j as f64 - k as f64);
            }
        }
        *weight = value;
    }
    (first, weights)
}

impl BarrierGrid {
    /// Room for up to `capacity` points on a string of `string_intervals` intervals. Allocates.
    pub fn with_capacity(capacity: usize, string_intervals: usize) -> Self {
        Self {
            spacing_m: 0.0,
            count: 0,
            string_intervals,
            transpose_scale: 0.0,
            stiffness_n_m2: 0.0,
            damping_s_m: 0.0,
            law: HuntCrossley { xi: 0.0, psi: 0.0 },
            positions_m: vec![0.0; capacity],
            heights_m: vec![0.0; capacity],
            stencil_first_node: vec![0; capacity],
            stencil_weights: vec![[0.0; 4]; capacity],
            weight_columns: std::array::from_fn(|_| vec![0.0; capacity]),
            segments: vec![StencilSegment::default(); capacity],
            segment_count: 0,
            segment_bounds: vec![SegmentBound::default(); capacity],
            near_segments: vec![StencilSegment::default(); capacity],
            near_segment_count: 0,
            kernels: Kernels::detect(),
            free_first_node: vec![1; capacity],
            free_weights: vec![[0.0; 4]; capacity],
            stencil_products: vec![StencilProducts::default(); capacity],
            gaps_m: vec![0.0; capacity],
            steps_m: vec![0.0; capacity],
            forces: vec![0.0; capacity],
            jacobian: vec![0.0; capacity],
            squared_gap_changes: vec![0.0; capacity],
            candidates: vec![0; capacity],
            candidate_count: 0,
            candidate_nodes: (1, 0),
            lebesgue: 1.0,
        }
    }

    pub fn capacity(&self) -> usize {
        self.positions_m.len()
    }

    /// Places `count` points from `first_m` with spacing `spacing_m` (clamped to capacity) and
    /// samples the barrier shape `height_at(x)`. Allocation-free.
    pub fn place(
        &mut self,
        first_m: f64,
        spacing_m: f64,
        count: usize,
        string_spacing_m: f64,
        height_at: impl Fn(f64) -> f64,
    ) {
        let count = count.min(self.capacity());
        self.count = count;
        self.spacing_m = spacing_m;
        self.transpose_scale = spacing_m / string_spacing_m;
        self.lebesgue = 1.0;
        self.candidate_count = 0;
        for i in 0..count {
            let x = first_m + i as f64 * spacing_m;
            self.positions_m[i] = x;
            self.heights_m[i] = height_at(x);
            let (first, weights) = lagrange_stencil(x / string_spacing_m, self.string_intervals);
            self.stencil_first_node[i] = first;
            self.stencil_weights[i] = weights;
            for (column, weight) in self.weight_columns.iter_mut().zip(weights) {
                column[i] = weight;
            }
            let (free_first, free_weights) = free_stencil(first, weights, self.string_intervals);
            self.free_first_node[i] = free_first;
            self.free_weights[i] = free_weights;
            self.stencil_products[i] = StencilProducts::of(&free_weights, self.transpose_scale);
            self.lebesgue = self
                .lebesgue
                .max(weights.iter().map(|w| w.abs()).sum::<f64>());
        }
        // Points are placed in order, so each stencil's points form one run.
        self.segment_count = 0;
        for i in 0..count {
            let first_node = self.stencil_first_node[i];
            match self.segment_count.checked_sub(1) {
                Some(last) if self.segments[last].first_node == first_node => {
                    self.segments[last].end = i + 1;
                }
                _ => {
                    self.segments[self.segment_count] = StencilSegment {
                        first_node,
                        start: i,
                        end: i + 1,
                    };
                    self.segment_count += 1;
                }
            }
        }
        for (bound, segment) in self
            .segment_bounds
            .iter_mut()
            .zip(&self.segments[..self.segment_count])
        {
            *bound = SegmentBound::of(
                &self.heights_m[segment.start..segment.end],
                &self.stencil_weights[segment.start..segment.end],
            );
        }
    }

    /// The nodes `first..=last` that this barrier's stencils reach (None when empty).
    pub fn stencil_node_range(&self) -> Option<(usize, usize)> {
        if self.count == 0 {
            return None;
        }
        let first = self.stencil_first_node[..self.count].iter().min()?;
        let last = self.stencil_first_node[..self.count].iter().max()? + 3;
        Some((*first, last))
    }

    /// max_i Σ_j |w_ij| of the placed points (≥ 1; 1.25 at most for cubic Lagrange).
    pub fn lebesgue_constant(&self) -> f64 {
        self.lebesgue
    }

    /// Sets the contact law (k in N/m², r in s/m) for a scheme of step Δt and density ρA.
    pub fn set_law(
        &mut self,
        stiffness_n_m2: f64,
        damping_s_m: f64,
        time_step_s: f64,
        linear_density_kg_m: f64,
    ) {
        self.stiffness_n_m2 = stiffness_n_m2;
        self.damping_s_m = damping_s_m;
        self.law = HuntCrossley::scaled(
            stiffness_n_m2,
            damping_s_m,
            time_step_s,
            linear_density_kg_m,
        );
    }

    /// Whether this barrier can exert any force (points placed and k > 0).
    pub fn is_active(&self) -> bool {
        self.count > 0 && self.stiffness_n_m2 > 0.0
    }

    pub fn len(&self) -> usize {
        self.count
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    pub fn stiffness_n_m2(&self) -> f64 {
        self.stiffness_n_m2
    }

    pub fn positions_m(&self) -> &[f64] {
        &self.positions_m[..self.count]
    }

    pub fn heights_m(&self) -> &[f64] {
        &self.heights_m[..self.count]
    }

    /// `(I v)_i`: the full-node vector `values` interpolated at point `i`.
    #[inline]
    pub fn interpolate(&self, values: &[f64], i: usize) -> f64 {
        dot4(
            &self.stencil_weights[i],
            &values[self.stencil_first_node[i]..],
        )
    }

    /// `(I s)_i` for a step `s` that is zero at the fixed nodes, through the free stencil.
    #[inline]
    fn interpolate_step(&self, step: &[f64], i: usize) -> f64 {
        dot4(&self.free_weights[i], &step[self.free_first_node[i]..])
    }

    /// Records the gaps `a_i = y_barrier(x_i) − ỹ_i` for the displacement before the step and
    /// selects as candidates the points with `a_i > −margin_m`. A point outside the candidates
    /// stays out of contact for any step with `|s̃_i| < margin_m`, so the caller must check
    /// that bound on its accepted step ([`BarrierGrid::lebesgue_constant`]) or pass an infinite
    /// margin.
    ///
    /// Also records the free nodes the candidates' stencils reach
    /// ([`BarrierGrid::candidate_node_range`]). The per-point results of the last evaluation
    /// are only meaningful for the candidates, and only after an evaluation.
    pub fn begin_step(&mut self, displacement: &[f64], margin_m: f64) {
        // Segments whose gaps are all at most −margin (by their bound) hold no candidate: only
        // the others are visited. The bound's slack is far above the gaps' round-off, so the
        // candidates are exactly those of a pass over every point.
        let mut near_count = 0;
        for (segment, bound) in self.segments[..self.segment_count]
            .iter()
            .zip(&self.segment_bounds)
        {
            let nodes = &displacement[segment.first_node..segment.first_node + 4];
            let far = bound.largest_gap(nodes) + GAP_BOUND_SLACK_M <= -margin_m;
            self.near_segments[near_count] = *segment;
            near_count += (!far) as usize;
        }
        self.near_segment_count = near_count;
        let [w0, w1, w2, w3] = &self.weight_columns;
        let count = self.count;
        self.kernels.barrier_gaps(
            &self.heights_m[..count],
            [&w0[..count], &w1[..count], &w2[..count], &w3[..count]],
            &self.near_segments[..near_count],
            displacement,
            &mut self.gaps_m[..count],
        );
        let mut candidate_count = 0;
        for segment in &self.near_segments[..near_count] {
            for (i, gap) in self.gaps_m[segment.start..segment.end].iter().enumerate() {
                // Branch-free compaction: the slot is written always, kept only for candidates.
                self.candidates[candidate_count] = segment.start + i;
                candidate_count += (*gap > -margin_m) as usize;
            }
        }
        self.candidate_count = candidate_count;
        // Points are in order along the string, so their free stencils are too.
        self.candidate_nodes = match self.candidates[..candidate_count] {
            [] => (1, 0),
            [first, .., last] => (self.free_first_node[first], self.free_first_node[last] + 3),
            [only] => (self.free_first_node[only], self.free_first_node[only] + 3),
        };
    }

    /// The free string nodes `first..=last` that the current candidates' stencils reach, or
    /// None without candidates: the only nodes on which this barrier can act during the step.
    pub fn candidate_node_range(&self) -> Option<(usize, usize)> {
        let (first, last) = self.candidate_nodes;
        (first <= last).then_some((first, last))
    }

    fn candidate_indices(&self) -> &[usize] {
        &self.candidates[..self.candidate_count]
    }

    /// How many points may touch during this step.
    pub fn candidate_count(&self) -> usize {
        self.candidate_count
    }

    /// Whether any point can be in contact during the step `step` (full-node vector): a point
    /// exerts a force only if its gap is positive before or after the step.
    pub fn touches_during(&self, step: &[f64]) -> bool {
        self.candidate_indices().iter().any(|&i| {
            let gap = self.gaps_m[i];
            gap > 0.0 || gap - self.interpolate_step(step, i) > 0.0
        })
    }

    /// Evaluates the mid-point forces and Jacobian entries for the step `step`.
    pub fn evaluate(&mut self, step: &[f64]) {
        for index in 0..self.candidate_count {
            let i = self.candidates[index];
            let point_step = self.interpolate_step(step, i);
            let contact = self.law.midpoint_force(self.gaps_m[i], point_step);
            self.steps_m[i] = point_step;
            self.forces[i] = contact.force;
            self.jacobian[i] = contact.stiffness;
            self.squared_gap_changes[i] = contact.squared_gap_change;
        }
    }

    /// Evaluates the contact law of every candidate at the step `step` and adds, in the same
    /// pass, `I* f̃` into the full-node vector `node_forces` and `I* C I` into the banded block
    /// `band` (`band[r][k]` is the entry of string nodes `first_node + r` and
    /// `first_node + r − k`, the lower triangle), which must hold
    /// [`BarrierGrid::candidate_node_range`]. The per-point results are not kept (the
    /// accepted step's come from [`BarrierGrid::evaluate_forces_into`]): the fused loop of the
    /// condensed Newton update (`condensed.rs`).
    pub fn evaluate_into_band(
        &self,
        step: &[f64],
        node_forces: &mut [f64],
        band: &mut [[f64; 4]],
        first_node: usize,
    ) {
        self.kernels.arch.dispatch(ContactIntoBand {
            grid: self,
            step,
            node_forces,
            band,
            band_first_node: first_node,
        });
    }

    /// Evaluates the candidates at the step `step` (as [`BarrierGrid::evaluate`]) and adds
    /// `I* f̃` into the full-node vector `node_forces`, in one pass.
    ///
    /// The forces of points that share a stencil are summed before they are added to the
    /// nodes, as in [`BarrierGrid::evaluate_into_band`].
    pub fn evaluate_forces_into(&mut self, step: &[f64], node_forces: &mut [f64]) {
        let mut sums = [0.0; 4];
        let mut summed_stencil = None;
        let add_sums = |node_forces: &mut [f64], first: usize, sums: &mut [f64; 4]| {
            for (node, sum) in node_forces[first..first + 4].iter_mut().zip(&*sums) {
                *node += sum;
            }
            *sums = [0.0; 4];
        };
        for &i in &self.candidates[..self.candidate_count] {
            let first = self.free_first_node[i];
            let w = &self.free_weights[i];
            let point_step = dot4(w, &step[first..]);
            let contact = self.law.midpoint_force(self.gaps_m[i], point_step);
            self.steps_m[i] = point_step;
            self.forces[i] = contact.force;
            self.jacobian[i] = contact.stiffness;
            self.squared_gap_changes[i] = contact.squared_gap_change;
            if contact.force != 0.0 {
                if summed_stencil != Some(first) {
                    if let Some(previous) = summed_stencil {
                        add_sums(node_forces, previous, &mut sums);
                    }
                    summed_stencil = Some(first);
                }
                let force = self.transpose_scale * contact.force;
                for (sum, weight) in sums.iter_mut().zip(w) {
                    *sum += weight * force;
                }
            }
        }
        if let Some(previous) = summed_stencil {
            add_sums(node_forces, previous, &mut sums);
        }
    }

    /// Adds `I* f̃` (scaled forces on the string nodes) into the full-node vector `output`.
    pub fn spread_forces(&self, output: &mut [f64]) {
        let last_free = self.string_intervals - 1;
        for &i in self.candidate_indices() {
            let force = self.transpose_scale * self.forces[i];
            if force == 0.0 {
                continue;
            }
            let first = self.stencil_first_node[i];
            for (j, weight) in self.stencil_weights[i].iter().enumerate() {
                let node = first + j;
                if (1..=last_free).contains(&node) {
                    output[node] += weight * force;
                }
            }
        }
    }

    /// Calls `add(row_node, column_node, value)` for every entry of `I* C I` on free nodes
    /// (both triangles), from the candidates' Jacobian entries `c_i`.
    #[inline]
    fn for_each_jacobian_entry(&self, mut add: impl FnMut(usize, usize, f64)) {
        let last_free = self.string_intervals - 1;
        for &i in self.candidate_indices() {
            let stiffness = self.transpose_scale * self.jacobian[i];
            if stiffness == 0.0 {
                continue;
            }
            let first = self.stencil_first_node[i];
            let w = &self.stencil_weights[i];
            for j in 0..4 {
                let row_node = first + j;
                if !(1..=last_free).contains(&row_node) {
                    continue;
                }
                for k in 0..4 {
                    let column_node = first + k;
                    if (1..=last_free).contains(&column_node) {
                        add(row_node, column_node, stiffness * w[j] * w[k]);
                    }
                }
            }
        }
    }

    /// Adds `I* C I` into `jacobian`, whose row r is string node r + 1.
    pub fn add_jacobian(&self, jacobian: &mut SymmetricBanded) {
        // The banded storage holds each symmetric pair once: add the lower triangle only.
        self.for_each_jacobian_entry(|row_node, column_node, value| {
            if column_node <= row_node {
                jacobian.add(row_node - 1, column_node - 1, value);
            }
        });
    }

    /// Whether the last [`evaluate`](Self::evaluate) found any point exerting a force.
    pub fn has_force(&self) -> bool {
        self.candidate_indices()
            .iter()
            .any(|&i| self.forces[i] != 0.0)
    }

    /// The barrier's potential energy `Δx_b Σ k/2 ⌊a_i⌋²` (J) for a displacement.
    pub fn potential_energy_j(&self, displacement: &[f64]) -> f64 {
        let sum: f64 = (0..self.count)
            .map(|i| {
                let gap = self.heights_m[i] - self.interpolate(displacement, i);
                potential_density(self.stiffness_n_m2, gap)
            })
            .sum();
        self.spacing_m * sum
    }

    /// Energy (J) dissipated by the contact damping r over the last evaluated step:
    /// `Δx_b Σ −(r/Δt)(k/2) Φ_i s̃_i ≥ 0`.
    pub fn step_loss_j(&self, time_step_s: f64) -> f64 {
        let sum: f64 = self
            .candidate_indices()
            .iter()
            .map(|&i| -self.squared_gap_changes[i] * self.steps_m[i])
            .sum();
        self.spacing_m * self.damping_s_m * 0.5 * self.stiffness_n_m2 * sum / time_step_s
    }

    /// The total force on the barrier over the last evaluated step (eq. 12), N:
    /// `Δx_b Σ F_i` with the physical density `F_i = f̃_i · 2ρA/Δt²`.
    pub fn total_force_n(&self, time_step_s: f64, linear_density_kg_m: f64) -> f64 {
        let sum: f64 = self
            .candidate_indices()
            .iter()
            .map(|&i| self.forces[i])
            .sum();
        self.spacing_m * sum * 2.0 * linear_density_kg_m / (time_step_s * time_step_s)
    }

    /// The deepest penetration after the last evaluated step, m (0 when nothing touches).
    pub fn max_penetration_after_step_m(&self) -> f64 {
        self.candidate_indices()
            .iter()
            .map(|&i| self.gaps_m[i] - self.steps_m[i])
            .fold(0.0, f64::max)
    }

    /// Static contact at displacement `y`: adds the spring force `I* k⌊a⌋` (N/m) into
    /// `force` and `I* k H(a) I` into `jacobian` (for the static equilibrium solve).
    pub fn add_static_contact(
        &self,
        displacement: &[f64],
        force: &mut [f64],
        jacobian: &mut SymmetricBanded,
    ) {
        let last_free = self.string_intervals - 1;
        for i in 0..self.count {
            let gap = self.heights_m[i] - self.interpolate(displacement, i);
            if gap <= 0.0 {
                continue;
            }
            let first = self.stencil_first_node[i];
            let w = &self.stencil_weights[i];
            let point_force = self.transpose_scale * self.stiffness_n_m2 * gap;
            let point_stiffness = self.transpose_scale * self.stiffness_n_m2;
            for j in 0..4 {
                let row_node = first + j;
                if !(1..=last_free).contains(&row_node) {
                    continue;
                }
                force[row_node] += w[j] * point_force;
                for k in 0..=j {
                    let column_node = first + k;
                    if (1..=last_free).contains(&column_node) {
                        jacobian.add(row_node - 1, column_node - 1, point_stiffness * w[j] * w[k]);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_interpolation_is_exact_for_cubics() {
        let intervals = 20;
        let dx = 0.01;
        let cubic = |x: f64| 2.0 - 3.0 * x + 40.0 * x * x - 900.0 * x * x * x;
        let values: Vec<f64> = (0..=intervals).map(|m| cubic(m as f64 * dx)).collect();
        let mut grid = BarrierGrid::with_capacity(50, intervals);
        // Points across the whole string, including the end intervals with shifted stencils.
        grid.place(0.0003, 0.0041, 49, dx, |_| 0.0);
        for i in 0..grid.len() {
            let x = grid.positions_m()[i];
            assert!(
                (grid.interpolate(&values, i) - cubic(x)).abs() < 1e-12,
                "x = {x}"
            );
        }
    }

    /// The segments' gap bounds hold for every point, and the step's candidates are exactly
    /// those of a pass over every point, while the far segments are skipped.
    #[test]
    fn far_segments_are_skipped_and_the_candidates_stay_the_same() {
        let intervals = 40;
        let dx = 0.005;
        let mut grid = BarrierGrid::with_capacity(200, intervals);
        // A curved barrier under the first part of the string, from the fixed end inwards.
        grid.place(0.0007, 0.0009, 150, dx, |x| 1e-3 * (1.0 - 30.0 * x));
        let mut skipped = 0;
        for shape in 0..40 {
            let phase = 0.37 * shape as f64;
            let amplitude = 2e-4 * (1.0 + (1.3 * phase).sin());
            let displacement: Vec<f64> = (0..=intervals)
                .map(|m| {
                    let x = m as f64 * dx;
                    1e-3 * (1.0 - 30.0 * x) + amplitude * (40.0 * x + phase).sin() - 5e-5
                })
                .collect();
            for margin in [1e-6, 2e-5, 3e-4] {
                grid.begin_step(&displacement, margin);
                let expected: Vec<usize> = (0..grid.len())
                    .filter(|&i| grid.heights_m()[i] - grid.interpolate(&displacement, i) > -margin)
                    .collect();
                assert_eq!(
                    grid.candidate_indices(),
                    &expected[..],
                    "shape {shape}, margin {margin}"
                );
                skipped += grid.segment_count - grid.near_segment_count;
            }
            for (segment, bound) in grid.segments[..grid.segment_count]
                .iter()
                .zip(&grid.segment_bounds)
            {
                let nodes = &displacement[segment.first_node..segment.first_node + 4];
                for i in segment.start..segment.end {
                    let gap = grid.heights_m()[i] - grid.interpolate(&displacement, i);
                    assert!(gap <= bound.largest_gap(nodes) + 1e-18, "point {i}");
                }
            }
        }
        assert!(skipped > 0, "no segment was ever skipped");
    }

    #[test]
    fn weights_sum_to_one_and_hit_nodes_exactly() {
        for &position in &[3.0, 3.25, 0.4, 19.9, 7.999] {
            let (first, weights) = lagrange_stencil(position, 20);
            assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!(first + 3 <= 20);
        }
        let (first, weights) = lagrange_stencil(5.0, 20);
        assert_eq!(first, 4);
        assert_eq!(weights, [0.0, 1.0, 0.0, 0.0]);
    }

    #[test]
    fn scaled_transpose_preserves_work() {
        // Δx (I* f̃)·s must equal Δx_b f̃·s̃ for any forces and steps.
        let intervals = 30;
        let dx = 0.02;
        let mut grid = BarrierGrid::with_capacity(40, intervals);
        grid.place(0.05, 0.0037, 40, dx, |x| 1e-4 * (x * 50.0).sin());
        grid.set_law(1e8, 0.0, 1e-5, 5e-4);
        let displacement = vec![0.0; intervals + 1];
        grid.begin_step(&displacement, f64::INFINITY);
        let mut step: Vec<f64> = (0..=intervals)
            .map(|m| -2e-4 * (m as f64 * 0.3).cos())
            .collect();
        step[0] = 0.0;
        step[intervals] = 0.0;
        grid.evaluate(&step);
        assert!(grid.has_force());
        let mut spread = vec![0.0; intervals + 1];
        grid.spread_forces(&mut spread);
        let string_work: f64 = dx * spread.iter().zip(&step).map(|(f, s)| f * s).sum::<f64>();
        let barrier_work: f64 = 0.0037
            * (0..grid.len())
                .map(|i| grid.forces[i] * grid.steps_m[i])
                .sum::<f64>();
        assert!((string_work - barrier_work).abs() < 1e-12 * barrier_work.abs());
    }

    /// The fused pass of the condensed update adds the same `I* f̃` and `I* C I` as the per-point
    /// assembly, on every vector width its sums are written for (one point at a time, four and
    /// eight lanes, and the units of this machine), with stencils that reach the fixed end.
    #[test]
    fn the_fused_pass_matches_the_per_point_assembly_on_every_vector_unit() {
        let intervals = 40;
        let dx = 0.005;
        let mut grid = BarrierGrid::with_capacity(120, intervals);
        grid.place(0.0004, 0.0011, 110, dx, |x| 2e-4 * (1.0 - 20.0 * x));
        grid.set_law(1e9, 1e-3, 1e-5, 5e-4);
        // A string across the barrier: some points stay in contact, some enter, some leave.
        let displacement: Vec<f64> = (0..=intervals)
            .map(|m| {
                let x = m as f64 * dx;
                if m == 0 || m == intervals {
                    0.0
                } else {
                    2e-4 * (1.0 - 20.0 * x) + 3e-5 * (90.0 * x).sin()
                }
            })
            .collect();
        grid.begin_step(&displacement, 1e-4);
        let mut step: Vec<f64> = (0..=intervals)
            .map(|m| 2e-5 * (m as f64 * 0.9).cos())
            .collect();
        (step[0], step[intervals]) = (0.0, 0.0);
        let (first, last) = grid.candidate_node_range().expect("candidates");
        assert!(first == 1, "the test's stencils must reach the fixed end");

        grid.evaluate(&step);
        let mut expected_forces = vec![0.0; intervals + 1];
        grid.spread_forces(&mut expected_forces);
        let mut expected_band = vec![[0.0; 4]; last - first + 1];
        grid.for_each_jacobian_entry(|row, column, value| {
            if column <= row {
                expected_band[row - first][row - column] += value;
            }
        });
        let cases = (0..grid.len()).filter(|&i| grid.forces[i] != 0.0).count();
        assert!(cases > 10, "only {cases} points exert a force");

        let check_forces = |unit: &str, forces: &[f64]| {
            let scale = expected_forces.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
            for (node, (got, want)) in forces.iter().zip(&expected_forces).enumerate() {
                assert!((got - want).abs() <= 1e-13 * scale, "{unit}: node {node}");
            }
        };
        let check = |unit: &str, forces: &[f64], band: &[[f64; 4]]| {
            check_forces(unit, forces);
            let scale = expected_band
                .iter()
                .flatten()
                .fold(0.0_f64, |m, c| m.max(c.abs()));
            for (row, (got, want)) in band.iter().zip(&expected_band).enumerate() {
                for k in 0..4 {
                    let error = (got[k] - want[k]).abs();
                    assert!(error <= 1e-13 * scale, "{unit}: row {row}, offset {k}");
                }
            }
        };
        let run = |unit: &str, vectorize: &dyn Fn(ContactIntoBand)| {
            let mut forces = vec![0.0; intervals + 1];
            let mut band = vec![[0.0; 4]; last - first + 1];
            vectorize(ContactIntoBand {
                grid: &grid,
                step: &step,
                node_forces: &mut forces,
                band: &mut band,
                band_first_node: first,
            });
            check(unit, &forces, &band);
        };
        run("scalar", &|op| pulp::Scalar.vectorize(op));
        run("two lanes", &|op| pulp::Scalar128b.vectorize(op));
        run("four lanes", &|op| pulp::Scalar256b.vectorize(op));
        run("eight lanes", &|op| pulp::Scalar512b.vectorize(op));
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(simd) = pulp::x86::V3::try_new() {
                run("AVX2", &|op| Simd::vectorize(simd, op));
            }
            if let Some(simd) = pulp::x86::V4::try_new() {
                run("AVX-512", &|op| Simd::vectorize(simd, op));
            }
        }
        let mut forces = vec![0.0; intervals + 1];
        let mut band = vec![[0.0; 4]; last - first + 1];
        grid.evaluate_into_band(&step, &mut forces, &mut band, first);
        check("dispatched", &forces, &band);

        let mut forces = vec![0.0; intervals + 1];
        grid.evaluate_forces_into(&step, &mut forces);
        check_forces("forces only", &forces);
    }
}
