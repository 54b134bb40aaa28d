//! The static problems of a grid-mode string solved on the grid's nodes (`docs/modal-tanpura.md`,
//! section 11): the rest state on bridge and thread, the finger's press of a pluck, and the
//! linearised fundamental the voice tunes by (section 5), with every point seen through its cubic
//! stencil, `Ψ_i = l_iᵀ V`, as the condensed step (`nodal.rs`) sees it.
//!
//! **Static equilibrium.** In the scaled modal coordinates (unit stiffness) forces `F_i` at the
//! points displace the modes by `r = Σ_i F_i Ψ_i = Vᵀ f`, with the nodal force `f = Σ_i F_i l_i`,
//! and the nodes by `y = V r = G f`, `G = V Vᵀ` (the nodes' static compliance, positive
//! definite: the nodes are distinct and every grid mode is kept). A point moves by
//! `u_i = l_i · y`. The equilibrium with the linear springs `k_i` of section 5
//! (`F_i = k_i ⌊g_i − u_i⌋`, `g_i` the free gap) minimises the convex, piecewise-quadratic
//!
//! `Π(y) = ½ yᵀ K y + Σ_i ½ k_i ⌊g_i − l_i · y⌋²`,   `K = G⁻¹`,
//!
//! over the n nodes the stencils reach: 11 for the seed's bridge and thread at 0.36/0.2 mm,
//! where the point-level solve (`solve.rs`, the same Π in the forces) works on about a hundred
//! points over 199 modes. Newton's step for the contact set A of the iterate is the exact
//! minimiser of the quadratic model, `(K + Σ_A k_i l_i l_iᵀ) y = Σ_A k_i g_i l_i`; a backtracking
//! line search on Π makes it converge from any start, and it ends exactly once a full step keeps
//! its contact set. Then `r = Vᵀ f`. The two solves give the same state up to round-off (tested).
//!
//! **Linearised fundamental.** The springs of the points in contact at rest add `Vᵀ C V` to the
//! modes' unit stiffness, `C = Σ_A k_i l_i l_iᵀ` (n × n). Inverse iteration, as `solve.rs` does,
//! on `(I + Vᵀ C V) x = ω² diag(1/ω_k²) x`, with the inverse by the Woodbury identity in the form
//! `(I + Vᵀ C V)⁻¹ = I − Vᵀ [C − C (K + C)⁻¹ C] V` (C may be singular: nodes no point at rest
//! touches), so that one factorisation of the n × n matrix `K + C` serves every iteration and an
//! iteration costs three passes of n rows over the modes.
//!
//! Hand-written rather than on a linear-algebra crate: the systems have at most
//! [`STATIC_NODE_CAPACITY`] unknowns and are solved on the audio thread at every retune and
//! pluck; nothing here allocates after [`NodalStatics::new`].

use super::lanes::{padded_lanes, Kernels};
use super::modes::{ModeSet, MODE_CAPACITY};
use super::nodal::{write_node_row, NODE_CAPACITY};
use super::points::ContactPoints;
use crate::dense::DenseCholesky;
use crate::tanpura::fd::barrier_grid::lagrange_stencil;

/// The most nodes a static problem may reach: the contact's ([`NODE_CAPACITY`]) and a finger's
/// (at most 40 mm wide: 20 nodes on the finest valid grid, 2.6 mm).
pub const STATIC_NODE_CAPACITY: usize = NODE_CAPACITY + 24;
/// Newton updates a static solve may take (each ends a contact set of the piecewise-quadratic
/// problem; the line search makes up to this many safe).
const STATIC_MAX_ITERATIONS: usize = 100;
const UNSET: usize = usize::MAX;

/// Why a static problem on the nodes could not be posed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodalStaticsError {
    /// The points reach more than [`STATIC_NODE_CAPACITY`] nodes, or there are more points than
    /// the solver holds.
    OutOfRoom,
    /// G or the Newton matrix was not positive definite (a non-finite configuration).
    NotPositiveDefinite,
    /// The string does not take a grid's modes, so it has no nodes.
    NoGrid,
}

/// The static solver on the nodes of a grid-mode string; allocation-free after
/// [`NodalStatics::new`].
#[derive(Debug, Clone)]
pub struct NodalStatics {
    /// The inverse iterations the last linearised fundamental took.
    pub(super) fundamental_iterations: usize,
    intervals: usize,
    length_m: f64,
    /// The grid nodes (1 … N − 1) the loaded points reach, in the order they were met, and each
    /// grid node's local index (or UNSET).
    node_count: usize,
    grid_nodes: Vec<usize>,
    local_index: Vec<usize>,
    /// V rows, `STATIC_NODE_CAPACITY × MODE_CAPACITY`, zero beyond the modes.
    shapes: Vec<f64>,
    /// K = G⁻¹ (stride STATIC_NODE_CAPACITY).
    stiffness: Vec<f64>,
    point_count: usize,
    /// Per point: its stencil's local nodes and weights (a support's weight is 0).
    stencils: Vec<[usize; 4]>,
    weights: Vec<[f64; 4]>,
    free_gaps_m: Vec<f64>,
    springs_n_m: Vec<f64>,
    /// Per point after a solve: the force, N, and the displacement, m.
    pub forces_n: Vec<f64>,
    pub displacements_m: Vec<f64>,
    /// The modal state after a solve, r = Vᵀ f (MODE_CAPACITY long).
    pub modal: Vec<f64>,
    /// Per node: the iterate, the trial, the nodal force; per point: in contact.
    nodes_m: Vec<f64>,
    trial_m: Vec<f64>,
    nodal_forces: Vec<f64>,
    active: Vec<bool>,
    previous_active: Vec<bool>,
    /// Dense n × n scratch (stride n) and its factor; C for the tuning (stride
    /// STATIC_NODE_CAPACITY).
    matrix: Vec<f64>,
    springs_on_nodes: Vec<f64>,
    factor: DenseCholesky,
    column: Vec<f64>,
    scratch: Vec<f64>,
    /// After [`Self::prepare_shift`]: per point the penetration `g − u` at the solution and its
    /// rate under the shift; per mode the modal state's rate.
    penetrations_m: Vec<f64>,
    penetration_rates: Vec<f64>,
    modal_rates: Vec<f64>,
    /// Whether they are the loaded problem's (a new problem, [`Self::begin`], ends them).
    shift_ready: bool,
    /// Mode-length scratch for the tuning's iteration.
    product: Vec<f64>,
    iterate: Vec<f64>,
    inverse_squares: Vec<f64>,
    kernels: Kernels,
}

impl NodalStatics {
    /// Room for `point_capacity` points. Allocates.
    pub fn new(point_capacity: usize) -> Self {
        let zeros = |n: usize| vec![0.0; n];
        let nodes = STATIC_NODE_CAPACITY;
        Self {
            fundamental_iterations: 0,
            intervals: 0,
            length_m: 0.0,
            node_count: 0,
            grid_nodes: vec![0; nodes],
            local_index: vec![UNSET; MODE_CAPACITY + 2],
            shapes: zeros(nodes * MODE_CAPACITY),
            stiffness: zeros(nodes * nodes),
            point_count: 0,
            stencils: vec![[0; 4]; point_capacity],
            weights: vec![[0.0; 4]; point_capacity],
            free_gaps_m: zeros(point_capacity),
            springs_n_m: zeros(point_capacity),
            forces_n: zeros(point_capacity),
            displacements_m: zeros(point_capacity),
            modal: zeros(MODE_CAPACITY),
            nodes_m: zeros(nodes),
            trial_m: zeros(nodes),
            nodal_forces: zeros(nodes),
            active: vec![false; point_capacity],
            previous_active: vec![false; point_capacity],
            matrix: zeros(nodes * nodes),
            springs_on_nodes: zeros(nodes * nodes),
            factor: DenseCholesky::with_capacity(nodes),
            column: zeros(nodes),
            scratch: zeros(nodes),
            penetrations_m: zeros(point_capacity),
            penetration_rates: zeros(point_capacity),
            modal_rates: zeros(MODE_CAPACITY),
            shift_ready: false,
            product: zeros(MODE_CAPACITY),
            iterate: zeros(MODE_CAPACITY),
            inverse_squares: zeros(MODE_CAPACITY),
            kernels: Kernels::detect(),
        }
    }

    /// Starts a problem on the grid of `intervals` intervals over a string of `length_m`.
    /// `intervals` must be a valid grid's (`GridModes::is_valid`).
    pub fn begin(&mut self, intervals: usize, length_m: f64) {
        for &node in &self.grid_nodes[..self.node_count] {
            self.local_index[node] = UNSET;
        }
        self.intervals = intervals.min(MODE_CAPACITY + 1);
        self.length_m = length_m;
        self.node_count = 0;
        self.point_count = 0;
        self.shift_ready = false;
    }

    /// Adds a point at `x_m` with free gap `free_gap_m`, spring `spring_n_m` and the force
    /// `force_n` the solve starts from.
    pub fn add_point(
        &mut self,
        x_m: f64,
        free_gap_m: f64,
        spring_n_m: f64,
        force_n: f64,
    ) -> Result<(), NodalStaticsError> {
        let i = self.point_count;
        if i == self.stencils.len() {
            return Err(NodalStaticsError::OutOfRoom);
        }
        let intervals = self.intervals;
        let (first, weights) = lagrange_stencil(x_m * intervals as f64 / self.length_m, intervals);
        let mut stencil = [0; 4];
        let mut kept_weights = [0.0; 4];
        for j in 0..4 {
            let node = first + j;
            if node == 0 || node >= intervals {
                // A support: no displacement, weight 0 (any local node will do).
                continue;
            }
            if self.local_index[node] == UNSET {
                if self.node_count == STATIC_NODE_CAPACITY {
                    return Err(NodalStaticsError::OutOfRoom);
                }
                self.local_index[node] = self.node_count;
                self.grid_nodes[self.node_count] = node;
                self.node_count += 1;
            }
            stencil[j] = self.local_index[node];
            kept_weights[j] = weights[j];
        }
        self.stencils[i] = stencil;
        self.weights[i] = kept_weights;
        self.free_gaps_m[i] = free_gap_m;
        self.springs_n_m[i] = spring_n_m;
        self.forces_n[i] = force_n;
        self.point_count += 1;
        Ok(())
    }

    /// Adds the bridge's and thread's points with their free gaps and springs, starting from
    /// their rest forces.
    pub fn add_contact_points(&mut self, points: &ContactPoints) -> Result<(), NodalStaticsError> {
        for i in 0..points.len() {
            self.add_point(
                points.positions_m[i],
                points.free_gaps_m[i],
                points.springs_n_m[i],
                points.rest_forces_n[i],
            )?;
        }
        Ok(())
    }

    /// V on the nodes (the sampled sines over √κ, by recurrence over the modes) and K = G⁻¹.
    pub fn prepare(&mut self, modes: &ModeSet) -> Result<(), NodalStaticsError> {
        let n = self.node_count;
        let count = modes.count();
        let lanes = padded_lanes(count);
        for (j, &node) in self.grid_nodes[..n].iter().enumerate() {
            let row = &mut self.shapes[j * MODE_CAPACITY..(j + 1) * MODE_CAPACITY];
            write_node_row(node, self.intervals, modes, row);
        }
        // G = V Vᵀ (lower triangle by rows, mirrored), factorised, and K = G⁻¹ column by column.
        for j in 0..n {
            self.kernels.leading_dots(
                &self.shapes,
                MODE_CAPACITY,
                &self.shapes[j * MODE_CAPACITY..j * MODE_CAPACITY + lanes],
                &mut self.column[..=j],
            );
            for l in 0..=j {
                self.matrix[j * n + l] = self.column[l];
                self.matrix[l * n + j] = self.column[l];
            }
        }
        self.factor
            .factorise(&self.matrix[..n * n], n)
            .map_err(|_| NodalStaticsError::NotPositiveDefinite)?;
        for l in 0..n {
            self.column[..n].fill(0.0);
            self.column[l] = 1.0;
            self.factor.solve_in_place(&mut self.column[..n]);
            for j in 0..n {
                self.stiffness[j * STATIC_NODE_CAPACITY + l] = self.column[j];
            }
        }
        Ok(())
    }

    /// `l_i · y` for the nodal values `y`.
    #[inline]
    fn at_point(&self, i: usize, y: &[f64]) -> f64 {
        let (stencil, weights) = (&self.stencils[i], &self.weights[i]);
        (0..4).map(|j| weights[j] * y[stencil[j]]).sum()
    }

    /// Π(y).
    fn energy(&self, y: &[f64]) -> f64 {
        let n = self.node_count;
        let mut strain = 0.0;
        for j in 0..n {
            let row = &self.stiffness[j * STATIC_NODE_CAPACITY..j * STATIC_NODE_CAPACITY + n];
            strain += y[j] * row.iter().zip(&y[..n]).map(|(k, v)| k * v).sum::<f64>();
        }
        let contact: f64 = (0..self.point_count)
            .map(|i| {
                let penetration = (self.free_gaps_m[i] - self.at_point(i, y)).max(0.0);
                self.springs_n_m[i] * penetration * penetration
            })
            .sum();
        0.5 * (strain + contact)
    }

    /// Solves the equilibrium of the loaded points from their forces; on success the forces,
    /// displacements and the modal state r = Vᵀ f are in [`Self::forces_n`],
    /// [`Self::displacements_m`] and [`Self::modal`] (after [`Self::prepare`]).
    pub fn solve(&mut self, modes: &ModeSet) -> Result<bool, NodalStaticsError> {
        let n = self.node_count;
        let count = self.point_count;
        // The start: y = G f for the starting forces (G = K⁻¹ by the factor of `prepare`, which
        // still holds G's).
        self.spread_forces();
        self.nodes_m[..n].copy_from_slice(&self.nodal_forces[..n]);
        self.apply_compliance();
        let mut energy = self.energy(&self.nodes_m);
        let mut last_step_full = false;
        let mut converged = false;
        for iteration in 0..STATIC_MAX_ITERATIONS {
            for i in 0..count {
                self.active[i] = self.free_gaps_m[i] - self.at_point(i, &self.nodes_m) > 0.0;
            }
            let same_set = iteration > 0 && self.active[..count] == self.previous_active[..count];
            if same_set && last_step_full {
                converged = true;
                break;
            }
            // The minimiser of the quadratic model on the current contact set.
            for j in 0..n {
                self.matrix[j * n..(j + 1) * n].copy_from_slice(
                    &self.stiffness[j * STATIC_NODE_CAPACITY..j * STATIC_NODE_CAPACITY + n],
                );
            }
            self.trial_m[..n].fill(0.0);
            for i in 0..count {
                if self.active[i] {
                    let spring = self.springs_n_m[i];
                    let (stencil, weights) = (self.stencils[i], self.weights[i]);
                    add_outer(&stencil, &weights, spring, &mut self.matrix, n);
                    for j in 0..4 {
                        self.trial_m[stencil[j]] += spring * self.free_gaps_m[i] * weights[j];
                    }
                }
            }
            if n > 0 {
                self.factor
                    .factorise(&self.matrix[..n * n], n)
                    .map_err(|_| NodalStaticsError::NotPositiveDefinite)?;
                self.factor.solve_in_place(&mut self.trial_m[..n]);
            }
            // Backtracking on the convex Π along the Newton direction.
            let mut fraction = 1.0;
            loop {
                for j in 0..n {
                    self.scratch[j] =
                        self.nodes_m[j] + fraction * (self.trial_m[j] - self.nodes_m[j]);
                }
                let trial_energy = self.energy(&self.scratch);
                // Round-off in Π near the minimum must not reject a converging step.
                if trial_energy <= energy + 1e-13 * energy.abs() || fraction < 1e-6 {
                    last_step_full = fraction == 1.0;
                    self.nodes_m[..n].copy_from_slice(&self.scratch[..n]);
                    energy = trial_energy;
                    break;
                }
                fraction *= 0.5;
            }
            self.previous_active[..count].copy_from_slice(&self.active[..count]);
        }
        for i in 0..count {
            let displacement = self.at_point(i, &self.nodes_m);
            self.displacements_m[i] = displacement;
            self.forces_n[i] = self.springs_n_m[i] * (self.free_gaps_m[i] - displacement).max(0.0);
        }
        self.spread_forces();
        self.modal_from_nodal_forces(modes);
        Ok(converged)
    }

    /// After a [`Self::solve`] that converged: how its solution moves when the free gaps of the
    /// points from `first_shifted` on rise together by t (a finger's points when its top
    /// rises by t). On the solution's contact set A the problem is linear:
    /// `(K + Σ_A k_i l_i l_iᵀ) ẏ = Σ_A k_i ġ_i l_i` with the factor of the solve's last Newton
    /// step (whose contact set was A), each point's penetration `p_i = g_i − l_i · y` moves by
    /// `ṗ_i = ġ_i − l_i · ẏ`, and the modal state by `ṙ = Vᵀ Σ_A k_i ṗ_i l_i`.
    /// [`Self::shifted_modal`] then gives the shifted problem's solution while A holds.
    pub fn prepare_shift(&mut self, first_shifted: usize, modes: &ModeSet) {
        let (n, count) = (self.node_count, self.point_count);
        let rises = |i: usize| if i >= first_shifted { 1.0 } else { 0.0 };
        self.trial_m[..n].fill(0.0);
        for i in 0..count {
            let displacement = self.displacements_m[i];
            self.penetrations_m[i] = self.free_gaps_m[i] - displacement;
            if self.penetrations_m[i] > 0.0 {
                let scaled = self.springs_n_m[i] * rises(i);
                for j in 0..4 {
                    self.trial_m[self.stencils[i][j]] += scaled * self.weights[i][j];
                }
            }
        }
        if n > 0 {
            self.factor.solve_in_place(&mut self.trial_m[..n]);
        }
        self.nodal_forces[..n].fill(0.0);
        for i in 0..count {
            let rate = rises(i) - self.at_point(i, &self.trial_m);
            self.penetration_rates[i] = rate;
            if self.penetrations_m[i] > 0.0 {
                let scaled = self.springs_n_m[i] * rate;
                for j in 0..4 {
                    self.nodal_forces[self.stencils[i][j]] += scaled * self.weights[i][j];
                }
            }
        }
        self.shift_ready = true;
        let modes = modes.count();
        self.modal_rates[..modes].fill(0.0);
        for j in 0..n {
            let rate = self.nodal_forces[j];
            let row = &self.shapes[j * MODE_CAPACITY..j * MODE_CAPACITY + modes];
            for (value, v) in self.modal_rates[..modes].iter_mut().zip(row) {
                *value += rate * v;
            }
        }
    }

    /// The modal state of [`Self::prepare_shift`]'s problem shifted by `t`, `r + t ṙ` from the
    /// solved state `modal` (its [`Self::modal`]), into `shifted`, if every point keeps its
    /// contact there (`p_i + t ṗ_i > 0` exactly where `p_i > 0`): the solution of the shifted
    /// problem, the same as its own solve's to round-off. Returns false, writing nothing, where a
    /// point would change its contact, or the loaded problem is no longer the one prepared. One
    /// pass over the points and one over the modes.
    pub fn shifted_modal(&self, t: f64, modal: &[f64], shifted: &mut [f64]) -> bool {
        if !self.shift_ready {
            return false;
        }
        let count = self.point_count;
        let keeps = self.penetrations_m[..count]
            .iter()
            .zip(&self.penetration_rates[..count])
            .all(|(&penetration, &rate)| (penetration + t * rate > 0.0) == (penetration > 0.0));
        if !(keeps && t.is_finite()) {
            return false;
        }
        for ((value, &base), &rate) in shifted.iter_mut().zip(modal).zip(&self.modal_rates) {
            *value = base + t * rate;
        }
        true
    }

    /// Whether the loaded problem is still the one [`Self::prepare_shift`] prepared (its nodes'
    /// rows and stiffness prepared, its last solution in place).
    pub fn holds_prepared_shift(&self) -> bool {
        self.shift_ready
    }

    /// Sets point `i`'s free gap, for a [`Self::solve`] of the same points again (from the
    /// forces of the last solution).
    pub fn set_free_gap(&mut self, i: usize, free_gap_m: f64) {
        if i < self.point_count {
            self.free_gaps_m[i] = free_gap_m;
            self.shift_ready = false;
        }
    }

    /// The string free of every point (no force, no displacement, r = 0): the state a problem
    /// that could not be posed leaves.
    pub fn clear_solution(&mut self) {
        let count = self.point_count;
        self.forces_n[..count].fill(0.0);
        self.displacements_m[..count].fill(0.0);
        self.modal.fill(0.0);
    }

    /// f = Σ_i F_i l_i into `nodal_forces`.
    fn spread_forces(&mut self) {
        self.nodal_forces[..self.node_count].fill(0.0);
        for i in 0..self.point_count {
            let force = self.forces_n[i];
            if force != 0.0 {
                let (stencil, weights) = (&self.stencils[i], &self.weights[i]);
                for j in 0..4 {
                    self.nodal_forces[stencil[j]] += force * weights[j];
                }
            }
        }
    }

    /// `nodes_m ← G nodes_m`, G = V Vᵀ applied as two passes over the modes.
    fn apply_compliance(&mut self) {
        let n = self.node_count;
        self.product.fill(0.0);
        for j in 0..n {
            let force = self.nodes_m[j];
            if force != 0.0 {
                let row = &self.shapes[j * MODE_CAPACITY..(j + 1) * MODE_CAPACITY];
                for (value, v) in self.product.iter_mut().zip(row) {
                    *value += force * v;
                }
            }
        }
        for j in 0..n {
            let row = &self.shapes[j * MODE_CAPACITY..(j + 1) * MODE_CAPACITY];
            self.nodes_m[j] = row.iter().zip(&self.product).map(|(v, r)| v * r).sum();
        }
    }

    /// r = Vᵀ f.
    fn modal_from_nodal_forces(&mut self, modes: &ModeSet) {
        let count = modes.count();
        self.modal.fill(0.0);
        for j in 0..self.node_count {
            let force = self.nodal_forces[j];
            let row = &self.shapes[j * MODE_CAPACITY..j * MODE_CAPACITY + count];
            for (value, v) in self.modal[..count].iter_mut().zip(row) {
                *value += force * v;
            }
        }
    }

    /// The lowest eigenfrequency of the modes with a spring `k_i` at every loaded point whose
    /// force `rest_forces_n[i]` is positive, rad/s, by at most `iterations` steps of inverse
    /// iteration, fewer once the Rayleigh quotient has settled within `settled_below` of itself
    /// (`super::rayleigh_settled`), after [`Self::prepare`] on the same points. NaN when `K + C`
    /// is not positive definite.
    pub fn linearised_fundamental(
        &mut self,
        rest_forces_n: &[f64],
        omega: &[f64],
        modes: usize,
        iterations: usize,
        settled_below: f64,
    ) -> f64 {
        let n = self.node_count;
        let lanes = padded_lanes(modes);
        let stride = STATIC_NODE_CAPACITY;
        // C = Σ_A k_i l_i l_iᵀ, and K + C factorised.
        for row in self.springs_on_nodes.chunks_mut(stride).take(n) {
            row[..n].fill(0.0);
        }
        for (i, &force) in rest_forces_n[..self.point_count].iter().enumerate() {
            if force > 0.0 {
                add_outer(
                    &self.stencils[i],
                    &self.weights[i],
                    self.springs_n_m[i],
                    &mut self.springs_on_nodes,
                    stride,
                );
            }
        }
        for j in 0..n {
            for l in 0..n {
                self.matrix[j * n + l] =
                    self.stiffness[j * stride + l] + self.springs_on_nodes[j * stride + l];
            }
        }
        if n > 0 && self.factor.factorise(&self.matrix[..n * n], n).is_err() {
            return f64::NAN;
        }
        let springs = &self.springs_on_nodes;
        let apply_springs = |x: &[f64], out: &mut [f64]| {
            for j in 0..n {
                out[j] = springs[j * stride..j * stride + n]
                    .iter()
                    .zip(&x[..n])
                    .map(|(c, v)| c * v)
                    .sum();
            }
        };
        // V x into `projection` and C V x into `sprung`.
        let (kernels, shapes) = (&self.kernels, &self.shapes);
        let project_and_spring = |x: &[f64], projection: &mut [f64], sprung: &mut [f64]| {
            kernels.leading_dots(shapes, MODE_CAPACITY, x, &mut projection[..n]);
            apply_springs(projection, sprung);
        };
        // M = diag(1/ω²) in `inverse_squares`; x₀ = 1/ω and v = M x₀.
        let (x, product) = (&mut self.iterate, &mut self.product);
        let inverse_squares = &mut self.inverse_squares;
        x.fill(0.0);
        product.fill(0.0);
        inverse_squares.fill(0.0);
        for k in 0..modes {
            inverse_squares[k] = 1.0 / (omega[k] * omega[k]);
            x[k] = 1.0 / omega[k];
            product[k] = x[k] * inverse_squares[k];
        }
        let mut rayleigh = 0.0;
        let (mut squared, mut mass) = ([0.0], [0.0]);
        self.fundamental_iterations = 0;
        for _ in 0..iterations {
            self.fundamental_iterations += 1;
            // x ← v − Vᵀ [C − C (K + C)⁻¹ C] V v.
            project_and_spring(&product[..lanes], &mut self.column, &mut self.scratch);
            self.column[..n].copy_from_slice(&self.scratch[..n]);
            if n > 0 {
                self.factor.solve_in_place(&mut self.column[..n]);
            }
            apply_springs(&self.column, &mut self.trial_m);
            for j in 0..n {
                self.scratch[j] -= self.trial_m[j];
            }
            x[..lanes].copy_from_slice(&product[..lanes]);
            for j in 0..n {
                let weight = self.scratch[j];
                let row = &self.shapes[j * MODE_CAPACITY..j * MODE_CAPACITY + lanes];
                for (value, v) in x[..lanes].iter_mut().zip(row) {
                    *value -= weight * v;
                }
            }
            // Rayleigh quotient xᵀ K_m x / xᵀ M x, K_m x = x + Vᵀ C V x; M x is the next v.
            for k in 0..lanes {
                product[k] = x[k] * inverse_squares[k];
            }
            kernels.dots_pair(
                &x[..lanes],
                lanes,
                &[0],
                &x[..lanes],
                &product[..lanes],
                &mut squared,
                &mut mass,
            );
            project_and_spring(&x[..lanes], &mut self.column, &mut self.scratch);
            let stiffness = squared[0]
                + (0..n)
                    .map(|j| self.column[j] * self.scratch[j])
                    .sum::<f64>();
            let previous = std::mem::replace(&mut rayleigh, stiffness / mass[0]);
            if super::rayleigh_settled(previous, rayleigh, settled_below) {
                break;
            }
            let inverse_norm = 1.0 / squared[0].sqrt();
            for (value, scaled) in x[..lanes].iter_mut().zip(product[..lanes].iter_mut()) {
                *value *= inverse_norm;
                *scaled *= inverse_norm;
            }
        }
        rayleigh.sqrt()
    }
}

/// Adds `scale · l lᵀ` for the stencil `(stencil, weights)` to `matrix` (row stride `stride`).
fn add_outer(
    stencil: &[usize; 4],
    weights: &[f64; 4],
    scale: f64,
    matrix: &mut [f64],
    stride: usize,
) {
    for a in 0..4 {
        for b in 0..4 {
            matrix[stencil[a] * stride + stencil[b]] += scale * weights[a] * weights[b];
        }
    }
}
