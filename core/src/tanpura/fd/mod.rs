//! The seed's finite-difference scheme: one tanpura string in distributed contact with a curved
//! bridge and a cotton thread, stepped one sample of the internal (oversampled) rate at a time.
//! The discretisation of the reference tier (and of the studio tier until stop 57, when it became
//! the fine tier's modal string at the reference's step, `quality.rs`).
//!
//! Source: seed 000 (van Walstijn & Chatziioannou, ISMA 2014), eq. 5–25, restated in
//! `shared/notes/tanpura-model.md`; configuration "B" of its Figure 2 (the string runs from the
//! tuning bead at x = 0, over the thread and the bridge, to the nut at x = L).
//!
//! - `operator.rs`: the string's FD operator (eq. 14–16) on the grid Δx, its energy and nut force;
//! - `barrier_grid.rs`: bridge, thread and finger on their own fine grids, tied to the string by
//!   cubic Lagrange interpolation and its scaled transpose (eq. 17–25);
//! - `condensed.rs`: Newton reduced to the contact nodes through a Schur complement;
//! - `decimator.rs`: the Kaiser FIR from the internal rate to the output rate;
//! - `kernels.rs`: the passes over the whole string (predictor right-hand side, contact
//!   correction, state update) as runtime-dispatched SIMD kernels.
//!
//! Each step finds `s = yⁿ⁺¹ − yⁿ` as the root of eq. 22 and updates `yⁿ⁺¹ = yⁿ + s`,
//! `qⁿ⁺¹ = s − qⁿ` (eq. 16). The step first solves the linear part alone with the prefactorised
//! `A` (the string without contact): the one banded solve of the step. If no barrier point has a
//! positive gap before or after that step, no contact force acts and the linear step *is* the
//! exact root: Newton is skipped. Otherwise a bounded Newton iteration (`newton.rs`) starts from
//! it, on the contact nodes only (`condensed.rs`), and the precomputed influence columns of
//! those nodes add the contact correction to the whole string. The barrier profiles are those of
//! `geometry.rs`; the finger's grid is 1 mm.
//!
//! Work that only tools need is not done per step: the loss ledger is booked only with
//! `track_energy` on (the energy-balance tests and `xtask simulate` turn it on), and the
//! deepest penetration is computed when asked for from what the last step left in the barrier
//! grids.
//!
//! **Rest preload** (not in the seed; the FD studio tier's until stop 57, when the studio tier
//! became modal). A tier that raises EI to cancel its coarser time step's dispersion would also
//! change the string's static shape near the thread by micrometres, and with it which keys rest on
//! the bridge's crest. With [`FdStringConfig::rest_bending_stiffness_n_m2`] the rest state `ȳ` is
//! solved with the true EI and a constant force density `p = g(ȳ) − g_true(ȳ)` (`g = K y − b` of
//! `operator.rs`) is added, so that `g(ȳ) − p` is the true string's restoring force at rest: `ȳ` is
//! an equilibrium of the scheme and the raised EI acts on the motion about it. `p` is constant, so
//! the potential gains `−Δx Σ p_m y_m` (its gradient is exact) and the energy balance below holds
//! unchanged (tested).
//!
//! Energy (eq. 8–9): `H = Σ Δx [p²/2ρA] + V_string + Δx_b Σ k_b/2⌊a⌋² + Δx_c Σ k_c/2⌊a⌋²`.
//! The scheme gives `Hⁿ⁺¹ − Hⁿ = −(losses over the step)` exactly; a pluck changes H by the
//! work the finger does, which is booked as external work. So at every step
//! `H(n) + cumulative losses − external work = H(0)` to round-off.

use crate::banded::{BandedLdlt, SymmetricBanded};
use crate::newton::{solve_bounded, NewtonSettings, NewtonStats, NewtonSystem};
use crate::tanpura::excitation::{finger_height_m, first_mode_shape, Pluck};
use crate::tanpura::geometry::{grid_points, BridgeSettings, FingerSettings, ThreadSettings};
use crate::tanpura::string::StringParameters;
use barrier_grid::{lagrange_stencil, BarrierGrid};
use condensed::ContactCondensation;
use kernels::Kernels;
use operator::StringOperator;

pub mod barrier_grid;
pub mod condensed;
pub mod decimator;
pub mod kernels;
pub mod operator;

/// How the Newton iteration of each step is solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolverKind {
    /// Newton on all N − 1 unknowns with a banded LDLᵀ Jacobian: the plain reference path.
    FullNewton,
    /// The same Newton iterates on the contact region only, through the precomputed Schur
    /// complement of the linear part (`condensed.rs`), and only for barrier points that can
    /// touch during the step.
    Condensed,
}

/// Everything that defines one simulated string.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdStringConfig {
    pub string: StringParameters,
    /// N, grid intervals over the length (200 gives the seed's Δx = 3⅓ mm, to 0.2 %).
    pub intervals: usize,
    /// Δt, s. Seed: 1/176 400 (4 × 44.1 kHz).
    pub time_step_s: f64,
    pub bridge: BridgeSettings,
    /// `None`: no thread, and no thread grid work at all.
    pub thread: Option<ThreadSettings>,
    pub finger: FingerSettings,
    pub newton: NewtonSettings,
    pub solver: SolverKind,
    /// Book the losses of every step into [`FdString::cumulative_losses_j`] (costs a few O(N)
    /// passes per step; the energy-balance tests and research tools turn it on, the audio path
    /// leaves it off). Also switchable on a built string with [`FdString::set_track_energy`].
    pub track_energy: bool,
    /// The bending stiffness the rest state is solved with, N·m², where it differs from the
    /// string's (`None`: the string's own). The FD studio tier of stops 34–56 raised EI so that
    /// its vibration had the reference's dispersion; with the true EI here its string still
    /// rested where the reference's rests (see [`FdString`]'s rest preload). No tier sets it now;
    /// the invariant tests keep it working.
    pub rest_bending_stiffness_n_m2: Option<f64>,
}

impl FdStringConfig {
    /// The seed's section 5: the reference configuration.
    pub const REFERENCE: FdStringConfig = FdStringConfig {
        string: StringParameters::SEED,
        intervals: 200,
        time_step_s: 1.0 / 176_400.0,
        bridge: BridgeSettings::SEED,
        thread: Some(ThreadSettings::SEED),
        finger: FingerSettings::SEED,
        newton: NewtonSettings::REFERENCE,
        solver: SolverKind::Condensed,
        track_energy: false,
        rest_bending_stiffness_n_m2: None,
    };

    /// The same with all losses off (γ = η = r_b = r_c = 0).
    pub fn lossless(mut self) -> Self {
        self.string.gamma_per_s = 0.0;
        self.string.eta_s = 0.0;
        self.bridge.damping_s_m = 0.0;
        if let Some(thread) = &mut self.thread {
            thread.damping_s_m = 0.0;
        }
        self
    }

    /// Where the speaking length starts: the thread if present, else the bridge crest.
    pub fn speaking_start_m(&self) -> f64 {
        match self.thread {
            Some(thread) => thread.position_m,
            None => self.bridge.crest_position_m,
        }
    }
}

impl Default for FdStringConfig {
    fn default() -> Self {
        Self::REFERENCE
    }
}

/// Largest fingertip the finger grid has room for, m.
const MAX_FINGER_WIDTH_M: f64 = 0.040;
/// Static equilibrium: Newton on a piecewise-linear problem ends once the contact set settles.
const STATIC_MAX_ITERATIONS: u32 = 200;
const STATIC_TOLERANCE_M: f64 = 1e-16;
/// Smallest candidate margin, m: keeps points at round-off distance from contact in play.
const CANDIDATE_MARGIN_FLOOR_M: f64 = 1e-12;

/// The per-step solver state: the linear step matrix, the Jacobian and the barriers.
#[derive(Debug, Clone)]
struct StepSolver {
    intervals: usize,
    /// A of eq. 15, and its factorisation for the contact-free predictor.
    step_matrix: SymmetricBanded,
    step_factor: BandedLdlt,
    jacobian: SymmetricBanded,
    jacobian_factor: BandedLdlt,
    /// s, full-node vector (zero at the fixed ends).
    step: Vec<f64>,
    /// The predictor's right-hand side −2(D yⁿ − d_b − qⁿ): minus the constant part of the
    /// residual.
    predictor_rhs: Vec<f64>,
    /// Σ I* f̃ on the string nodes.
    contact: Vec<f64>,
    residual: Vec<f64>,
    bridge: BarrierGrid,
    thread: BarrierGrid,
    finger: BarrierGrid,
    kind: SolverKind,
    /// The contact region's Schur complement (None when no barrier can ever touch).
    condensation: Option<ContactCondensation>,
}

impl StepSolver {
    /// One Newton update on the active contact block only (see `condensed.rs`).
    fn condensed_update(&mut self) -> Option<f64> {
        let condensation = self.condensation.as_mut()?;
        let (band, first, size) = condensation.contact_band_reset();
        self.contact[first..first + size].fill(0.0);
        for barrier in [&self.bridge, &self.thread] {
            if barrier.is_active() {
                barrier.evaluate_into_band(&self.step, &mut self.contact, band, first);
            }
        }
        condensation.update(&mut self.step, &self.contact)
    }

    /// The free nodes that the active barriers' candidates can act on this step.
    fn candidate_node_range(&self) -> Option<(usize, usize)> {
        [&self.bridge, &self.thread]
            .into_iter()
            .filter(|barrier| barrier.is_active())
            .filter_map(|barrier| barrier.candidate_node_range())
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// The condensed Newton solve of a step with contact (`condensed.rs`), from the predictor
    /// in `step`, ending with the whole step in `step` and the forces of the accepted step in
    /// the barrier grids. Points farther from contact than `margin` were left out of the
    /// candidates; if the accepted step reaches that far (`lebesgue` bounds the interpolated
    /// step), the solve is redone with every point (counted in `stats.redone_steps`). Returns
    /// (updates, converged).
    fn solve_condensed(
        &mut self,
        kernels: &Kernels,
        displacement: &[f64],
        settings: &NewtonSettings,
        mut margin: f64,
        lebesgue: f64,
        stats: &mut NewtonStats,
    ) -> (u32, bool) {
        let mut outcome = (0, true);
        loop {
            let Some((first, last)) = self.candidate_node_range() else {
                return outcome;
            };
            let Some(condensation) = self.condensation.as_mut() else {
                return (0, false);
            };
            if !condensation.set_active_block(first, last) {
                // A principal block of A⁻¹ that round-off made indefinite: fail soft with the
                // contact-free step (its forces only reported), counted as a cap hit.
                for barrier in [&mut self.bridge, &mut self.thread] {
                    if barrier.is_active() {
                        barrier.evaluate(&self.step);
                    }
                }
                return (outcome.0, false);
            }
            condensation.apply_initial_guess(&mut self.step);
            let attempt = solve_bounded(self, settings);
            outcome = (outcome.0 + attempt.0, attempt.1);
            // Forces at the accepted step, for the recovery, the outputs and the ledger.
            let condensation = self.condensation.as_mut().expect("checked above");
            let (first, size) = condensation.active_block();
            self.contact[first..first + size].fill(0.0);
            for barrier in [&mut self.bridge, &mut self.thread] {
                if barrier.is_active() {
                    barrier.evaluate_forces_into(&self.step, &mut self.contact);
                }
            }
            let reach = lebesgue * condensation.block_step_max_abs(&self.contact);
            if reach < margin {
                condensation.recover_step(kernels, &mut self.step, &self.contact);
                return outcome;
            }
            // The step went farther than the candidate margin: redo with every point.
            stats.redone_steps += 1;
            margin = f64::INFINITY;
            for barrier in [&mut self.bridge, &mut self.thread] {
                if barrier.is_active() {
                    barrier.begin_step(displacement, margin);
                }
            }
        }
    }
}

impl NewtonSystem for StepSolver {
    fn newton_update(&mut self) -> Option<f64> {
        if self.kind == SolverKind::Condensed && self.condensation.is_some() {
            return self.condensed_update();
        }
        let n = self.intervals;
        self.contact.fill(0.0);
        self.jacobian.copy_from(&self.step_matrix);
        for barrier in [&mut self.bridge, &mut self.thread, &mut self.finger] {
            if barrier.is_active() {
                barrier.evaluate(&self.step);
                barrier.spread_forces(&mut self.contact);
                barrier.add_jacobian(&mut self.jacobian);
            }
        }
        // F(s) = A s + 2(D yⁿ − d_b − qⁿ) − Σ I* f̃ (eq. 22), the constant part being −rhs.
        self.step_matrix
            .multiply(&self.step[1..n], &mut self.residual[..n - 1]);
        for m in 1..n {
            self.residual[m - 1] -= self.predictor_rhs[m] + self.contact[m];
        }
        self.jacobian_factor.factorise(&self.jacobian).ok()?;
        self.jacobian_factor
            .solve_in_place(&mut self.residual[..n - 1]);
        let mut largest = 0.0f64;
        for m in 1..n {
            let delta = self.residual[m - 1];
            self.step[m] -= delta;
            largest = largest.max(delta.abs());
        }
        Some(largest)
    }
}

/// One tanpura string; allocation-free after [`FdString::new`].
#[derive(Debug, Clone)]
pub struct FdString {
    config: FdStringConfig,
    operator: StringOperator,
    solver: StepSolver,
    /// y, full-node vector: y[0] = y_TB, y[N] = 0.
    displacement: Vec<f64>,
    /// q = (Δt/2ρA) p, full-node vector, zero at the ends.
    scaled_momentum: Vec<f64>,
    /// The static equilibrium on bridge and thread (no finger, no motion).
    rest_displacement: Vec<f64>,
    /// The rest preload `p` (N/m, full-node vector, zero at the ends; zero unless
    /// [`FdStringConfig::rest_bending_stiffness_n_m2`] is set): a constant force density that
    /// makes the rest state of the true EI an equilibrium of the string's own operator.
    preload: Vec<f64>,
    /// Whether `preload` is not all zero (the step then adds it).
    preloaded: bool,
    scratch: Vec<f64>,
    kernels: Kernels,
    /// Whether the last step had contact (the barrier grids then hold its forces and steps).
    touched_last_step: bool,
    stats: NewtonStats,
    nut_force_n: f64,
    bridge_force_n: f64,
    rest_nut_force_n: f64,
    rest_bridge_force_n: f64,
    cumulative_losses_j: f64,
    external_work_j: f64,
    static_solve_failures: u64,
    non_finite_resets: u64,
}

impl FdString {
    /// Builds the string and settles it at rest on bridge and thread. Allocates.
    pub fn new(config: FdStringConfig) -> Self {
        let n = config.intervals;
        let operator = StringOperator::new(config.string, n, config.time_step_s);
        let bridge_capacity = grid_points(
            config.bridge.start_m,
            config.bridge.end_m,
            config.bridge.spacing_m,
        );
        let thread_capacity = match config.thread {
            Some(thread) => grid_points(0.0, 2.0 * thread.half_width_m(), thread.spacing_m),
            None => 0,
        };
        let finger_capacity = grid_points(0.0, MAX_FINGER_WIDTH_M, config.finger.spacing_m);
        let solver = StepSolver {
            intervals: n,
            step_matrix: SymmetricBanded::zeros(n - 1, 2),
            step_factor: BandedLdlt::with_shape(n - 1, 2),
            jacobian: SymmetricBanded::zeros(n - 1, 3),
            jacobian_factor: BandedLdlt::with_shape(n - 1, 3),
            step: vec![0.0; n + 1],
            predictor_rhs: vec![0.0; n + 1],
            contact: vec![0.0; n + 1],
            residual: vec![0.0; n + 1],
            bridge: BarrierGrid::with_capacity(bridge_capacity, n),
            thread: BarrierGrid::with_capacity(thread_capacity, n),
            finger: BarrierGrid::with_capacity(finger_capacity, n),
            kind: config.solver,
            condensation: contact_node_range(&config, operator.spacing_m())
                .map(|(first, last)| ContactCondensation::new(first, last, n - 1)),
        };
        let mut string = Self {
            config,
            operator,
            solver,
            displacement: vec![0.0; n + 1],
            scaled_momentum: vec![0.0; n + 1],
            rest_displacement: vec![0.0; n + 1],
            preload: vec![0.0; n + 1],
            preloaded: false,
            scratch: vec![0.0; n + 1],
            kernels: Kernels::detect(),
            touched_last_step: false,
            stats: NewtonStats::default(),
            nut_force_n: 0.0,
            bridge_force_n: 0.0,
            rest_nut_force_n: 0.0,
            rest_bridge_force_n: 0.0,
            cumulative_losses_j: 0.0,
            external_work_j: 0.0,
            static_solve_failures: 0,
            non_finite_resets: 0,
        };
        string.apply_config();
        string.reset();
        string
    }

    /// Changes the configuration without reallocating. The grid (`intervals`) and string
    /// length must stay as built, and a thread can only be moved or removed if the
    /// string was built with one (its grid needs room). Returns false, changing nothing, when
    /// the new configuration does not fit. The string keeps vibrating; its rest state is
    /// recomputed.
    pub fn set_config(&mut self, config: FdStringConfig) -> bool {
        let thread_fits = config.thread.is_none_or(|thread| {
            grid_points(0.0, 2.0 * thread.half_width_m(), thread.spacing_m)
                <= self.solver.thread.capacity()
        });
        let bridge_fits = grid_points(
            config.bridge.start_m,
            config.bridge.end_m,
            config.bridge.spacing_m,
        ) <= self.solver.bridge.capacity();
        let fits = config.intervals == self.config.intervals
            && config.time_step_s > 0.0
            && config.string.length_m == self.config.string.length_m
            && thread_fits
            && bridge_fits;
        if !fits {
            return false;
        }
        if config != self.config {
            self.config = config;
            self.apply_config();
            self.update_rest_state();
        }
        true
    }

    fn apply_config(&mut self) {
        let config = self.config;
        let dt = config.time_step_s;
        let density = config.string.linear_density_kg_m;
        self.operator.set_parameters(config.string);
        self.operator.step_matrix_into(&mut self.solver.step_matrix);
        self.solver
            .step_factor
            .factorise(&self.solver.step_matrix)
            .expect("the string's step matrix is positive definite for positive T, EI, ρA");
        self.solver.kind = config.solver;
        if let Some(condensation) = &mut self.solver.condensation {
            condensation
                .prepare(&self.solver.step_factor, &mut self.scratch)
                .expect("a principal block of A⁻¹ is positive definite");
        }
        let dx = self.operator.spacing_m();

        let bridge = config.bridge;
        let bridge_end = match (bridge.beyond_thread, config.thread) {
            (false, Some(thread)) => bridge.end_m.min(thread.position_m),
            _ => bridge.end_m,
        };
        let bridge_points = if bridge.stiffness_n_m2 > 0.0 && bridge_end > bridge.start_m {
            grid_points(bridge.start_m, bridge_end, bridge.spacing_m)
        } else {
            0
        };
        self.solver
            .bridge
            .place(bridge.start_m, bridge.spacing_m, bridge_points, dx, |x| {
                bridge.height_m(x)
            });
        self.solver
            .bridge
            .set_law(bridge.stiffness_n_m2, bridge.damping_s_m, dt, density);

        match config.thread {
            Some(thread) => {
                let (first_m, points) = thread.barrier_lattice(thread.spacing_m);
                self.solver
                    .thread
                    .place(first_m, thread.spacing_m, points, dx, |x| {
                        thread.height_over(&bridge, x)
                    });
                self.solver
                    .thread
                    .set_law(thread.stiffness_n_m2, thread.damping_s_m, dt, density);
            }
            None => {
                self.solver.thread.place(0.0, 1.0, 0, dx, |_| 0.0);
                self.solver.thread.set_law(0.0, 0.0, dt, density);
            }
        }
        // The finger only acts while pressing (`pluck`); between plucks k_f = 0.
        self.solver.finger.place(0.0, 1.0, 0, dx, |_| 0.0);
        self.solver.finger.set_law(0.0, 0.0, dt, density);
    }

    /// Puts the string at rest on bridge and thread and clears every statistic and ledger.
    pub fn reset(&mut self) {
        self.update_rest_state();
        self.displacement.copy_from_slice(&self.rest_displacement);
        self.scaled_momentum.fill(0.0);
        self.stats = NewtonStats::default();
        self.nut_force_n = self.rest_nut_force_n;
        self.bridge_force_n = self.rest_bridge_force_n;
        self.touched_last_step = false;
        self.cumulative_losses_j = 0.0;
        self.external_work_j = 0.0;
        self.static_solve_failures = 0;
        self.non_finite_resets = 0;
    }

    /// Recomputes the static rest state (and the forces it puts on nut and bridge) for the
    /// current configuration, leaving the moving string untouched.
    fn update_rest_state(&mut self) {
        let n = self.config.intervals;
        let left = self.config.string.left_support_m;
        let mut rest = std::mem::take(&mut self.rest_displacement);
        // Start from the straight line between the supports.
        for (m, y) in rest.iter_mut().enumerate() {
            *y = left * (1.0 - m as f64 / n as f64);
        }
        self.preload.fill(0.0);
        self.preloaded = false;
        let vibrating = self.config.string;
        let rest_stiffness = self
            .config
            .rest_bending_stiffness_n_m2
            .filter(|&stiffness| stiffness != vibrating.bending_stiffness_n_m2);
        if let Some(rest_stiffness) = rest_stiffness {
            self.operator.set_parameters(StringParameters {
                bending_stiffness_n_m2: rest_stiffness,
                ..vibrating
            });
        }
        if !self.solve_static(&mut rest) {
            self.static_solve_failures += 1;
        }
        if rest_stiffness.is_some() {
            // The preload p = g_vibrating(y_rest) − g_true(y_rest) makes the rest state of the
            // true EI an equilibrium of the string's own operator: g_vibrating(y_rest) − p =
            // g_true(y_rest) = the contact force at rest.
            self.operator.restoring_force(&rest, &mut self.scratch);
            self.operator.set_parameters(vibrating);
            self.operator.restoring_force(&rest, &mut self.preload);
            for (preload, true_force) in self.preload.iter_mut().zip(&self.scratch) {
                *preload -= true_force;
            }
            self.preloaded = self.preload.iter().all(|p| p.is_finite());
            if !self.preloaded {
                self.preload.fill(0.0);
            }
        }
        self.rest_nut_force_n = self.operator.nut_force_n(&rest);
        self.rest_bridge_force_n = self.static_barrier_force_n(&rest);
        self.rest_displacement = rest;
    }

    /// The total static force of bridge and thread on the string at `displacement`, N.
    fn static_barrier_force_n(&self, displacement: &[f64]) -> f64 {
        [&self.solver.bridge, &self.solver.thread]
            .iter()
            .filter(|barrier| barrier.is_active())
            .map(|barrier| {
                let stiffness = barrier.stiffness_n_m2();
                let spacing = if barrier.len() > 1 {
                    barrier.positions_m()[1] - barrier.positions_m()[0]
                } else {
                    0.0
                };
                (0..barrier.len())
                    .map(|i| {
                        let gap = barrier.heights_m()[i] - barrier.interpolate(displacement, i);
                        stiffness * gap.max(0.0)
                    })
                    .sum::<f64>()
                    * spacing
            })
            .sum()
    }

    /// Solves the static equilibrium `K y − b = Σ I* k⌊y_barrier − I y⌋` (every active barrier,
    /// the finger included) by Newton's method from `displacement`, in place. The contact law
    /// is piecewise linear, so Newton ends exactly once the contact set stops changing.
    /// Returns whether it converged within the cap.
    fn solve_static(&mut self, displacement: &mut [f64]) -> bool {
        let n = self.config.intervals;
        displacement[0] = self.config.string.left_support_m;
        displacement[n] = 0.0;
        for _ in 0..STATIC_MAX_ITERATIONS {
            let solver = &mut self.solver;
            self.operator
                .restoring_force(displacement, &mut solver.residual);
            solver.contact.fill(0.0);
            solver.jacobian.copy_from(self.operator.stiffness_matrix());
            for barrier in [&solver.bridge, &solver.thread, &solver.finger] {
                if barrier.is_active() {
                    barrier.add_static_contact(
                        displacement,
                        &mut solver.contact,
                        &mut solver.jacobian,
                    );
                }
            }
            // G(y) on the interior, shifted down one index for the solver.
            for m in 1..n {
                solver.residual[m - 1] = solver.residual[m] - self.preload[m] - solver.contact[m];
            }
            if solver.jacobian_factor.factorise(&solver.jacobian).is_err() {
                return false;
            }
            solver
                .jacobian_factor
                .solve_in_place(&mut solver.residual[..n - 1]);
            let largest = solver.residual[..n - 1]
                .iter()
                .fold(0.0f64, |a, d| a.max(d.abs()));
            if !largest.is_finite() {
                return false;
            }
            if largest <= STATIC_TOLERANCE_M {
                for m in 1..n {
                    displacement[m] -= self.solver.residual[m - 1];
                }
                return true;
            }
            // Backtracking on the static energy, which is convex: the full Newton step can
            // overshoot when the contact set changes (stiff barriers, coarse grids), a shorter
            // one cannot fail to decrease it, so the iteration converges from any start.
            let current = self.static_energy_j(displacement);
            let mut fraction = 1.0;
            loop {
                self.scratch.copy_from_slice(displacement);
                for m in 1..n {
                    self.scratch[m] -= fraction * self.solver.residual[m - 1];
                }
                let trial = self.static_energy_j(&self.scratch);
                // Round-off in E near the minimum must not reject a converging step.
                if trial <= current + 1e-13 * current.abs() || fraction < 1e-6 {
                    break;
                }
                fraction *= 0.5;
            }
            displacement.copy_from_slice(&self.scratch);
        }
        false
    }

    /// The energy whose minimum is the static equilibrium: the string's potential plus every
    /// active barrier's (the finger's too while it presses), J.
    fn static_energy_j(&self, displacement: &[f64]) -> f64 {
        let mut energy = self.string_potential_energy_j(displacement);
        for barrier in [
            &self.solver.bridge,
            &self.solver.thread,
            &self.solver.finger,
        ] {
            if barrier.is_active() {
                energy += barrier.potential_energy_j(displacement);
            }
        }
        energy
    }

    /// Forgets what the solver carried over from earlier steps (Newton's initial guess), so
    /// that a new excitation evolves exactly as it would on a freshly built string.
    fn forget_motion_history(&mut self) {
        if let Some(condensation) = &mut self.solver.condensation {
            condensation.clear_correction();
        }
    }

    /// The seed's finger pluck: press the finger (k_f > 0) until the string is in static
    /// equilibrium against finger, bridge and thread, then release it (k_f → 0). The string's
    /// previous motion is stopped by the finger. The energy this adds is booked as external
    /// work. Allocation-free.
    pub fn pluck(&mut self, pluck: &Pluck) {
        self.forget_motion_history();
        let energy_before = self.energy_j();
        let length = self.config.string.length_m;
        let width = pluck.width_m.clamp(
            Pluck::WIDTH_RANGE_M.0,
            Pluck::WIDTH_RANGE_M.1.min(MAX_FINGER_WIDTH_M),
        );
        let amplitude = pluck
            .amplitude_m
            .clamp(Pluck::AMPLITUDE_RANGE_M.0, Pluck::AMPLITUDE_RANGE_M.1);
        let half_width = 0.5 * width;
        let lowest = self.config.speaking_start_m() + half_width + 1e-3;
        let highest = length - half_width - 1e-3;
        let centre = pluck.position_m.clamp(lowest, highest.max(lowest));
        let dx = self.operator.spacing_m();
        // The finger's top sits `amplitude` above the rest shape under its centre.
        let rest_under_centre = interpolate_full(&self.rest_displacement, centre / dx);
        let top = rest_under_centre + amplitude;
        let spacing = self.config.finger.spacing_m;
        let points = grid_points(0.0, width, spacing);
        self.solver
            .finger
            .place(centre - half_width, spacing, points, dx, |x| {
                finger_height_m(x, centre, width, top)
            });
        self.solver.finger.set_law(
            self.config.finger.stiffness_n_m2,
            self.config.finger.damping_s_m,
            self.config.time_step_s,
            self.config.string.linear_density_kg_m,
        );
        let mut pressed = std::mem::take(&mut self.displacement);
        if !self.solve_static(&mut pressed) {
            self.static_solve_failures += 1;
        }
        self.displacement = pressed;
        self.scaled_momentum.fill(0.0);
        // Release.
        self.solver.finger.place(0.0, 1.0, 0, dx, |_| 0.0);
        self.solver.finger.set_law(
            0.0,
            0.0,
            self.config.time_step_s,
            self.config.string.linear_density_kg_m,
        );
        self.external_work_j += self.energy_j() - energy_before;
        self.refresh_outputs_at_rest_of_motion();
    }

    /// The seed's "first mode" initial condition: the rest shape plus `amplitude_m` times the
    /// first mode of the speaking length, released from rest. Allocation-free.
    pub fn excite_first_mode(&mut self, amplitude_m: f64) {
        self.forget_motion_history();
        let energy_before = self.energy_j();
        let start = self.config.speaking_start_m();
        let length = self.config.string.length_m;
        let dx = self.operator.spacing_m();
        for (m, y) in self.displacement.iter_mut().enumerate() {
            let x = m as f64 * dx;
            *y = self.rest_displacement[m] + amplitude_m * first_mode_shape(x, start, length);
        }
        self.scaled_momentum.fill(0.0);
        self.external_work_j += self.energy_j() - energy_before;
        self.refresh_outputs_at_rest_of_motion();
    }

    fn refresh_outputs_at_rest_of_motion(&mut self) {
        self.nut_force_n = self.operator.nut_force_n(&self.displacement);
        self.bridge_force_n = self.static_barrier_force_n(&self.displacement);
    }

    /// Advances one time step Δt. Allocation-free; never panics.
    pub fn step(&mut self) {
        let n = self.config.intervals;
        let parameters = *self.operator.parameters();
        let dx = self.operator.spacing_m();
        let inverse_dx2 = 1.0 / (dx * dx);
        let kernels = self.kernels;
        let solver = &mut self.solver;
        // Contact-free predictor: A s = −2(D yⁿ − d_b − qⁿ) = 2qⁿ − (Δt²/2ρA)(K yⁿ − b).
        kernels.predictor_rhs(
            &self.displacement,
            &self.scaled_momentum,
            inverse_dx2,
            parameters.tension_n,
            parameters.bending_stiffness_n_m2 * inverse_dx2,
            2.0 * self.operator.force_scale(),
            &mut self.scratch,
            &mut solver.predictor_rhs,
        );
        if self.preloaded {
            // The rest preload enters the constant part: −2(D yⁿ − d_b − qⁿ) + 2(Δt²/4ρA) p.
            kernels.axpy(
                2.0 * self.operator.force_scale(),
                &self.preload,
                &mut solver.predictor_rhs,
            );
        }
        solver.step.copy_from_slice(&solver.predictor_rhs);
        solver.step_factor.solve_in_place(&mut solver.step[1..n]);

        // Points farther from contact than any step can reach are left out of the Newton
        // iteration; the bound is checked on the accepted step. The margin is twice what
        // Newton's initial guess reaches (the predictor plus the extrapolated contact
        // correction): the accepted step lies close to the guess, and the contact holds it far
        // below the contact-free predictor (after the default pluck at the reference grid, no
        // step is redone: test `condensed_candidate_margin_rarely_redoes_a_step`).
        let condensed = solver.kind == SolverKind::Condensed && solver.condensation.is_some();
        let lebesgue = solver
            .bridge
            .lebesgue_constant()
            .max(solver.thread.lebesgue_constant());
        let margin = match &mut solver.condensation {
            Some(condensation) if condensed => {
                condensation.set_predictor(&solver.step);
                2.0 * lebesgue * condensation.guess_max_abs() + CANDIDATE_MARGIN_FLOOR_M
            }
            _ => f64::INFINITY,
        };
        let mut touching = false;
        for barrier in [&mut solver.bridge, &mut solver.thread] {
            if barrier.is_active() {
                barrier.begin_step(&self.displacement, margin);
                touching |= barrier.touches_during(&solver.step);
            }
        }
        let (iterations, converged) = if !touching {
            if let Some(condensation) = &mut solver.condensation {
                condensation.clear_correction();
            }
            (0, true)
        } else if condensed {
            solver.solve_condensed(
                &kernels,
                &self.displacement,
                &self.config.newton,
                margin,
                lebesgue,
                &mut self.stats,
            )
        } else {
            let outcome = solve_bounded(solver, &self.config.newton);
            // Forces at the accepted step, for the outputs and the energy ledger.
            for barrier in [&mut solver.bridge, &mut solver.thread] {
                if barrier.is_active() {
                    barrier.evaluate(&solver.step);
                }
            }
            outcome
        };
        self.stats.record(iterations, converged);
        self.touched_last_step = touching;

        if self.config.track_energy {
            let mut loss = self.operator.step_loss_j(&solver.step, &mut self.scratch);
            if touching {
                for barrier in [&solver.bridge, &solver.thread] {
                    if barrier.is_active() {
                        loss += barrier.step_loss_j(self.config.time_step_s);
                    }
                }
            }
            self.cumulative_losses_j += loss;
        }

        let finite = kernels.advance_state(
            &solver.step,
            &mut self.displacement,
            &mut self.scaled_momentum,
        );

        let dt = self.config.time_step_s;
        let density = self.config.string.linear_density_kg_m;
        self.nut_force_n = self.operator.nut_force_n(&self.displacement);
        self.bridge_force_n = if touching {
            solver.bridge.total_force_n(dt, density) + solver.thread.total_force_n(dt, density)
        } else {
            0.0
        };
        if !finite || !self.nut_force_n.is_finite() {
            // Fail soft: a non-finite state cannot recover, so silence the string at rest.
            self.non_finite_resets += 1;
            self.displacement.copy_from_slice(&self.rest_displacement);
            self.scaled_momentum.fill(0.0);
            self.nut_force_n = self.rest_nut_force_n;
            self.bridge_force_n = self.rest_bridge_force_n;
            self.touched_last_step = false;
        }
    }

    /// Turns the loss ledger on or off on a built string (see
    /// [`FdStringConfig::track_energy`]); the ledger keeps what it booked so far.
    pub fn set_track_energy(&mut self, track_energy: bool) {
        self.config.track_energy = track_energy;
    }

    /// The string's potential energy at a full-node displacement, J: V of eq. 8–9 and, with a
    /// rest preload, its work `−Δx Σ p_m y_m` (so that `g − p` stays the gradient).
    fn string_potential_energy_j(&self, displacement: &[f64]) -> f64 {
        let mut energy = self.operator.potential_energy_j(displacement);
        if self.preloaded {
            let work: f64 = self
                .preload
                .iter()
                .zip(displacement)
                .map(|(p, y)| p * y)
                .sum();
            energy -= self.operator.spacing_m() * work;
        }
        energy
    }

    /// The discrete energy H (eq. 8–9) of the current state, J.
    pub fn energy_j(&self) -> f64 {
        let mut energy = self.string_potential_energy_j(&self.displacement)
            + self.operator.kinetic_energy_j(&self.scaled_momentum);
        for barrier in [&self.solver.bridge, &self.solver.thread] {
            if barrier.is_active() {
                energy += barrier.potential_energy_j(&self.displacement);
            }
        }
        energy
    }

    /// H at the rest state, J: what a silent string holds (tension over the bridge).
    pub fn rest_energy_j(&self) -> f64 {
        let mut energy = self.string_potential_energy_j(&self.rest_displacement);
        for barrier in [&self.solver.bridge, &self.solver.thread] {
            if barrier.is_active() {
                energy += barrier.potential_energy_j(&self.rest_displacement);
            }
        }
        energy
    }

    /// The force on the nut after the last step (eq. 13), N.
    pub fn nut_force_n(&self) -> f64 {
        self.nut_force_n
    }

    /// The total force of bridge and thread on the string over the last step (eq. 12), N.
    pub fn bridge_force_n(&self) -> f64 {
        self.bridge_force_n
    }

    /// The nut force at rest, N (subtract it for an audio signal without DC).
    pub fn rest_nut_force_n(&self) -> f64 {
        self.rest_nut_force_n
    }

    /// The bridge force at rest, N.
    pub fn rest_bridge_force_n(&self) -> f64 {
        self.rest_bridge_force_n
    }

    /// Energy dissipated since the last reset (γ, η, r_b, r_c), J. Booked only when
    /// `track_energy` is on.
    pub fn cumulative_losses_j(&self) -> f64 {
        self.cumulative_losses_j
    }

    /// Energy added by plucks since the last reset, J.
    pub fn external_work_j(&self) -> f64 {
        self.external_work_j
    }

    pub fn newton_stats(&self) -> &NewtonStats {
        &self.stats
    }

    /// Deepest penetration into bridge or thread after the last step, m (0 when it had no
    /// contact). Computed on request from the last step's gaps and steps, not per step.
    pub fn max_penetration_m(&self) -> f64 {
        if !self.touched_last_step {
            return 0.0;
        }
        [&self.solver.bridge, &self.solver.thread]
            .into_iter()
            .filter(|barrier| barrier.is_active())
            .map(|barrier| barrier.max_penetration_after_step_m())
            .fold(0.0, f64::max)
    }

    /// Static solves (rest state or pluck) that hit their cap; 0 in normal operation.
    pub fn static_solve_failures(&self) -> u64 {
        self.static_solve_failures
    }

    /// Steps whose state became non-finite and were reset to rest; 0 in normal operation.
    pub fn non_finite_resets(&self) -> u64 {
        self.non_finite_resets
    }

    /// y on the full grid (nodes 0..=N), m.
    pub fn displacement_m(&self) -> &[f64] {
        &self.displacement
    }

    /// The rest shape on the full grid, m.
    pub fn rest_displacement_m(&self) -> &[f64] {
        &self.rest_displacement
    }

    pub fn config(&self) -> &FdStringConfig {
        &self.config
    }

    pub fn operator(&self) -> &StringOperator {
        &self.operator
    }

    /// The bridge's points and heights, m (for plotting the contact region).
    pub fn bridge_grid(&self) -> &BarrierGrid {
        &self.solver.bridge
    }

    /// The thread's points and heights, m (empty without a thread).
    pub fn thread_grid(&self) -> &BarrierGrid {
        &self.solver.thread
    }

    /// The fundamental frequency of small vibrations about the rest state, Hz, with every barrier
    /// point in contact at rest acting as a spring of its contact stiffness: the lowest
    /// eigenvalue of `(K + Σ I* k H(a) I) v = ω² ρA v`, found by inverse iteration with the
    /// banded solver. Allocation-free; costs about 30 banded solves.
    pub fn linearised_fundamental_hz(&mut self) -> f64 {
        let n = self.config.intervals;
        let solver = &mut self.solver;
        solver.contact.fill(0.0);
        solver.jacobian.copy_from(self.operator.stiffness_matrix());
        for barrier in [&solver.bridge, &solver.thread] {
            if barrier.is_active() {
                barrier.add_static_contact(
                    &self.rest_displacement,
                    &mut solver.contact,
                    &mut solver.jacobian,
                );
            }
        }
        if solver.jacobian_factor.factorise(&solver.jacobian).is_err() {
            return f64::NAN;
        }
        let iterate = &mut solver.residual[..n - 1];
        let start = self.config.speaking_start_m();
        let dx = self.operator.spacing_m();
        for (i, value) in iterate.iter_mut().enumerate() {
            *value =
                first_mode_shape((i + 1) as f64 * dx, start, self.config.string.length_m) + 1e-3;
        }
        for _ in 0..30 {
            solver.jacobian_factor.solve_in_place(iterate);
            let norm = iterate.iter().map(|v| v * v).sum::<f64>().sqrt();
            for value in iterate.iter_mut() {
                *value /= norm;
            }
        }
        let product = &mut self.scratch[..n - 1];
        solver.jacobian.multiply(iterate, product);
        let rayleigh: f64 = iterate
            .iter()
            .zip(product.iter())
            .map(|(x, kx)| x * kx)
            .sum();
        (rayleigh / self.config.string.linear_density_kg_m).sqrt() / (2.0 * std::f64::consts::PI)
    }

    /// The point nearest the nut where the string touches bridge or thread at rest, m: the
    /// start of the speaking length. `None` when nothing touches.
    pub fn rest_contact_end_m(&self) -> Option<f64> {
        let rest = &self.rest_displacement;
        [&self.solver.bridge, &self.solver.thread]
            .iter()
            .filter(|barrier| barrier.is_active())
            .flat_map(|barrier| {
                (0..barrier.len())
                    .filter(move |&i| barrier.heights_m()[i] - barrier.interpolate(rest, i) > 0.0)
                    .map(move |i| barrier.positions_m()[i])
            })
            .reduce(f64::max)
    }

    /// The vibrational energy above the rest state, J (used to decide when a string sleeps).
    pub fn vibration_energy_j(&self) -> f64 {
        self.energy_j() - self.rest_energy_j()
    }

    /// Puts a decayed string exactly at rest (the sleeping state), keeping the ledgers.
    pub fn settle_to_rest(&mut self) {
        let energy_before = self.energy_j();
        self.displacement.copy_from_slice(&self.rest_displacement);
        self.scaled_momentum.fill(0.0);
        self.external_work_j += self.energy_j() - energy_before;
        self.nut_force_n = self.rest_nut_force_n;
        self.bridge_force_n = self.rest_bridge_force_n;
        self.touched_last_step = false;
    }
}

/// The string nodes that any bridge or thread stencil can reach, for every thread position in
/// its range: the block the condensed solver iterates on.
fn contact_node_range(config: &FdStringConfig, spacing_m: f64) -> Option<(usize, usize)> {
    let n = config.intervals;
    let thread_reach = ThreadSettings::SEED
        .half_width_m()
        .max(config.thread.map_or(0.0, |thread| thread.half_width_m()));
    let lowest = config
        .bridge
        .start_m
        .min(ThreadSettings::POSITION_RANGE_M.0 - thread_reach);
    let highest = config
        .bridge
        .end_m
        .max(ThreadSettings::POSITION_RANGE_M.1 + thread_reach);
    let first = lagrange_stencil(lowest / spacing_m, n).0.max(1);
    let last = (lagrange_stencil(highest / spacing_m, n).0 + 3).min(n - 1);
    (first <= last).then_some((first, last))
}

/// Cubic Lagrange interpolation of a full-node vector at a position in grid units.
fn interpolate_full(values: &[f64], position_in_intervals: f64) -> f64 {
    let intervals = values.len() - 1;
    let (first, weights) = lagrange_stencil(position_in_intervals, intervals);
    (0..4).map(|j| weights[j] * values[first + j]).sum()
}
