//! The modal discretisation of the tanpura string: the discretisation of the fast tiers.
//!
//! Derived in `docs/modal-tanpura.md`; the equation labels below are that document's. The same
//! continuous model as the seed's FD scheme (seed 000, eq. 5–9, `shared/notes/tanpura-model.md`)
//! and the same bridge and thread profiles (`geometry.rs`), discretised differently:
//!
//! - `modes.rs`: the string's eigenmodes with the lowered support (section 1), each advanced by an
//!   exact two-pole recursion in mid-point form at the output rate (eq. M1–M2): exact partial
//!   frequencies and decay rates σ = γ/2 + ηω²/2 at any sample rate, no oversampling, no
//!   dispersion, no decimator. Modes below min(20 kHz, 0.45 f_s) are kept. Optionally
//!   ([`ModalStringConfig::residual_modes`], section 8) a few residual modes follow them: the
//!   truncated modes' static compliance on the contact points, as resonators at 0.475 f_s. Or
//!   ([`ModalStringConfig::grid_modes`], section 10) every mode of the seed's FD grid, at the FD
//!   scheme's own frequencies, seen at the points through its cubic interpolation: the FD string
//!   in space, advanced exactly in time.
//! - `points.rs`: the bridge and thread as a few contact points, coupled to the modes through the
//!   mode shapes there, with the seed's mid-point Hunt–Crossley force (eq. 4, `contact.rs`).
//! - `solve.rs`: Newton's method on the points that touch (section 4), the static problems of
//!   the rest state and the pluck, and the linearised fundamental the tuning uses (section 5).
//!   Newton iterates only on the points within [`TRACKING_BAND_M`] of contact; every point's
//!   free step is computed each step, so a far point's step follows exactly from the converged
//!   forces, and one that would touch joins before the step is taken: the solve stays exact for
//!   every point (`step.rs`).
//! - `lanes.rs`: the three passes over the modes as SIMD kernels, dispatched at run time.
//!
//! Energy (eq. M3): `H = Σ_k [r_k²/2 + (a_k/2b_k) p_k²] + Σ_i V_i(a_i)` changes over a step by
//! exactly minus the losses of the modes and of the contact damping, so the lossless scheme
//! conserves H and the lossy one never increases it, for any step, any modes and any points. A
//! pluck's work is booked as external work, as in the FD tiers.
//!
//! The state is carried as the deviation from the rest state (`r̃ = r − r_rest`, section 4), so a
//! string at rest is an exact fixed point in any precision. `T` is the precision of the mode
//! arrays (f32 for the fast tier, f64 for the plain reference path); the contact solves and all
//! static problems run in f64.

mod block;
pub mod lanes;
pub mod modes;
pub mod nodal;
pub mod nodal_statics;
pub mod points;
pub mod solve;
pub mod step;

use crate::newton::{NewtonSettings, NewtonStats};
use crate::simd::CacheAligned;
use crate::step_timers::{self, StepPart};
use crate::tanpura::excitation::{finger_height_m, Pluck};
use crate::tanpura::geometry::grid_points;
use crate::tanpura::geometry::{BridgeSettings, FingerSettings, ThreadSettings};
use crate::tanpura::string::StringParameters;
use crate::tanpura::tier_string::weighted_pickup_n;
use lanes::{padded_lanes, AdvanceAndPrepare, Dots, Kernels, LeadingDots, Real, LANE_PADDING};
pub use modes::GridModes;
use modes::{ModeSet, AUDIBLE_LIMIT_HZ, MODE_CAPACITY};
use nodal::{NodalContact, NODE_CAPACITY};
use nodal_statics::{NodalStatics, NodalStaticsError};
use points::ContactPoints;
use pulp::{Simd, WithSimd};
use solve::{linearised_fundamental, StaticSolver};
use std::f64::consts::PI;
use step::ContactStep;

const _: () = assert!(MODE_CAPACITY.is_multiple_of(LANE_PADDING));

/// Largest fingertip the finger's points have room for, m.
const MAX_FINGER_WIDTH_M: f64 = 0.040;
/// The residual modes ring at this fraction of the sample rate: above the kept modes (at most
/// 0.45 of it) and below Nyquist.
const RESIDUAL_MODE_RATE_FRACTION: f64 = 0.475;
/// The thread's lattices tried, in order, as the spacing of its points in fractions of the
/// configured spacing and their offset from the thread's top in fractions of that spacing:
/// the configured lattice with a point on the top, two coarser ones on the top, and the
/// configured one straddling the top; [`ModalString::place_thread_lattice`].
const THREAD_LATTICES: [ThreadLattice; 4] = [
    ThreadLattice {
        spacing: 1.0,
        offset: 0.0,
    },
    ThreadLattice {
        spacing: 1.1,
        offset: 0.0,
    },
    ThreadLattice {
        spacing: 1.2,
        offset: 0.0,
    },
    ThreadLattice {
        spacing: 1.0,
        offset: 0.5,
    },
];

/// A lattice of the thread's points: their spacing, in fractions of the configured spacing, and
/// their offset from the thread's top, in fractions of that spacing.
#[derive(Debug, Clone, Copy)]
struct ThreadLattice {
    spacing: f64,
    offset: f64,
}

/// The first lattice whose thread points all lie at least this far from the rest state's
/// contact edges ([`ModalString::thread_edge_margin`]) is kept.
const THREAD_EDGE_MARGIN: f64 = 0.35;
/// Far points are put to sleep this often (the check costs a pass over the modes and points).
const SLEEP_CHECK_STEPS: usize = 256;
/// Inverse iterations for the linearised fundamental at most (the eigenvector's error falls by
/// (f₁/f₂)² ≈ 1/4 each, the Rayleigh quotient's by its square); the iteration stops sooner once
/// the quotient has settled ([`rayleigh_settled`]).
const TUNING_ITERATIONS: usize = 30;
/// The relative change of the Rayleigh quotient ω² between two inverse iterations below which
/// it has settled: falling about sixteenfold an iteration, its remaining error is then near
/// 1e-14 of ω², a pitch error near 1e-11 cents. At the fine tier the quotient settles after 12
/// iterations, where 30 fixed ones spent the rest on round-off (`docs/performance.md`, stop 55).
const RAYLEIGH_SETTLED: f64 = 1e-13;

/// Whether the Rayleigh quotient `current` of an inverse iteration has settled after `previous`:
/// changed by at most `tolerance` of itself ([`RAYLEIGH_SETTLED`]; 0 runs every iteration unless
/// two quotients are equal).
#[inline]
pub(super) fn rayleigh_settled(previous: f64, current: f64, tolerance: f64) -> bool {
    (current - previous).abs() <= tolerance * current.abs()
}

/// Points whose gap lies within this distance of contact are tracked: Newton iterates on them.
/// Every other point's step follows from the converged forces, and a point that would touch joins
/// before the step is taken (`ModalString::step`), so the band is only a matter of cost: a point
/// tracked but not touching costs a row in every Newton update (docs/performance.md).
pub const TRACKING_BAND_M: f64 = 2e-6;

/// Everything that defines one modal string.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalStringConfig {
    pub string: StringParameters,
    /// Δt, s: the output rate's sample period.
    pub time_step_s: f64,
    /// The bridge profile and law; its contact points cover `start_m..end_m`.
    pub bridge: BridgeSettings,
    /// `None`: no thread.
    pub thread: Option<ThreadSettings>,
    pub finger: FingerSettings,
    /// Modes are kept below this frequency (and below 0.45 of the sample rate), Hz.
    pub highest_mode_hz: f64,
    /// Spacing of the contact points on the bridge and on the thread, m.
    pub bridge_point_spacing_m: f64,
    pub thread_point_spacing_m: f64,
    pub newton: NewtonSettings,
    /// Book the losses of every step (tests and research tools; costs a pass over the modes).
    pub track_energy: bool,
    /// Add the truncated modes' static flexibility to the static problems (section 8 of the
    /// derivation): the rest state and the pressed shape become the continuous string's, and the
    /// string vibrates in its kept modes about that rest state. Off (the tiers' setting): the kept
    /// modes alone. On, the rest state and the linear pitch match the FD string's, but the
    /// residual displacement stays frozen at its rest value while the string moves, which
    /// distorts the contact near the crest (the formant stops falling between 0.5 and 1.5 s).
    pub static_flexibility: bool,
    /// Residual modes (section 8): resonators above the kept modes that carry the truncated
    /// modes' static compliance on the contact points, so that the string rests where the
    /// continuous string rests and energy taken into the truncated modes comes back. 0: none.
    pub residual_modes: usize,
    /// Skip the free steps of the far points that provably cannot touch before the next
    /// excitation (section 7); the output is the same bit for bit either way.
    pub sleep_far_points: bool,
    /// Take every mode of this FD grid instead of the continuous string's modes below
    /// `highest_mode_hz` (section 10): the string is then the seed's FD string in space, advanced
    /// exactly in time. Excludes the static flexibility and residual modes (both are the
    /// continuous string's truncated part; the grid's modes are all kept). `None`: the tiers'.
    pub grid_modes: Option<GridModes>,
}

impl ModalStringConfig {
    /// The configuration the string runs: grid modes only when valid ([`GridModes::is_valid`]),
    /// and with them neither the static flexibility nor residual modes.
    fn sanitised(mut self) -> Self {
        self.grid_modes = self.grid_modes.filter(|grid| grid.is_valid());
        if self.grid_modes.is_some() {
            self.static_flexibility = false;
            self.residual_modes = 0;
        }
        self
    }

    /// The seed's string, bridge and thread at 44.1 kHz, modes up to 20 kHz, contact points
    /// every millimetre on the bridge and every half millimetre on the thread.
    pub const REFERENCE: ModalStringConfig = ModalStringConfig {
        string: StringParameters::SEED,
        time_step_s: 1.0 / 44_100.0,
        bridge: BridgeSettings::SEED,
        thread: Some(ThreadSettings::SEED),
        finger: FingerSettings::SEED,
        highest_mode_hz: AUDIBLE_LIMIT_HZ,
        bridge_point_spacing_m: 1e-3,
        thread_point_spacing_m: 0.5e-3,
        newton: NewtonSettings {
            tolerance_m: 1e-12,
            max_iterations: 30,
        },
        track_energy: false,
        static_flexibility: false,
        residual_modes: 0,
        sleep_far_points: true,
        grid_modes: None,
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

    /// Where the bridge's points start: just before the first place the string can reach the
    /// bridge. With a thread that is the thread; without one, the string comes from the lowered
    /// support with the slope `|y_TB|/x_crest` and first meets the parabola where the bridge's
    /// slope equals it, `R_b |y_TB|/x_crest` before the crest. Two millimetres more for margin.
    /// On the bead's side of that the string runs above the bridge (0.5–1 mm at rest), so the
    /// FD grids' points there never carry a force.
    fn bridge_start_m(&self) -> f64 {
        let crest = self.bridge.crest_position_m;
        let first_touch =
            crest - self.bridge.curvature_radius_m * self.string.left_support_m.abs() / crest;
        let speaking = self.thread.map_or(first_touch, |thread| {
            thread.position_m - thread.half_width_m()
        });
        (speaking.min(first_touch) - 2e-3).max(self.bridge.start_m)
    }

    /// The bridge's first point: [`Self::bridge_start_m`], or on grid modes the first point of
    /// the reference's lattice (`bridge.start_m` and every spacing after it, as the FD string's
    /// barrier grid places them) at or past it. On the seed's grid a string whose bridge points
    /// lie half a spacing (0.09 mm) from the reference's plays the crest's grazing contact
    /// otherwise (`docs/modal-tanpura.md` §10, stop 50).
    fn bridge_first_point_m(&self) -> f64 {
        let start = self.bridge_start_m();
        if self.grid_modes.is_none() {
            return start;
        }
        let (origin, spacing) = (self.bridge.start_m, self.bridge_point_spacing_m);
        // The tolerance keeps a start that lies on the lattice where it is despite round-off.
        origin + ((start - origin) / spacing - 1e-9).ceil().max(0.0) * spacing
    }

    /// Where the bridge's points end: the bridge's end, or the thread without the bridge beyond it.
    fn bridge_end_m(&self) -> f64 {
        match (self.bridge.beyond_thread, self.thread) {
            (false, Some(thread)) => self.bridge.end_m.min(thread.position_m),
            _ => self.bridge.end_m,
        }
    }

    fn point_capacity(&self) -> usize {
        // The earliest start over the thread's range of positions.
        let earliest = ModalStringConfig {
            thread: Some(ThreadSettings {
                position_m: ThreadSettings::POSITION_RANGE_M.0,
                ..ThreadSettings::SEED
            }),
            ..*self
        }
        .bridge_start_m()
        .min(self.bridge_start_m());
        let bridge = grid_points(earliest, self.bridge.end_m, self.bridge_point_spacing_m);
        let half_width = ThreadSettings::SEED
            .half_width_m()
            .max(self.thread.map_or(0.0, |thread| thread.half_width_m()));
        // Room for the finest lattice tried.
        let finest = THREAD_LATTICES
            .iter()
            .map(|lattice| lattice.spacing)
            .fold(f64::INFINITY, f64::min);
        let finest_spacing_m = finest * self.thread_point_spacing_m;
        // The symmetric lattice's 2⌊w/s⌋ + 1 points, or the grid's ⌊2w/s⌋ + 1 (one more at most).
        let thread = 2 * (half_width / finest_spacing_m).floor() as usize + 2;
        bridge + thread
    }
}

impl Default for ModalStringConfig {
    fn default() -> Self {
        Self::REFERENCE
    }
}

/// One tanpura string in modal form; allocation-free after [`ModalString::new`].
#[derive(Debug, Clone)]
pub struct ModalString<T: Real> {
    config: ModalStringConfig,
    modes: ModeSet,
    kernels: Kernels,
    /// The kept modes rounded up to whole registers: the length the kernels run over.
    lanes: usize,
    // The mode arrays the kernels run on (T), MODE_CAPACITY long, zero beyond the modes the step
    // advances (the kept ones and any residual ones), each starting on a cache line.
    a: CacheAligned<T>,
    b: CacheAligned<T>,
    nut_weights: CacheAligned<T>,
    /// r̃ = r − r_rest.
    modal: CacheAligned<T>,
    /// p, the scaled velocity of eq. M1.
    velocity: CacheAligned<T>,
    /// s_free, the free step from the current state (kept by every step and every change of
    /// the state from outside, [`ModalString::prepare_free_step`]).
    step: CacheAligned<T>,
    /// The whole step of the last step (written by every step; the loss ledger reads it right
    /// after). Between steps it is free: `set_config` keeps the physical velocity in it.
    whole_step: CacheAligned<T>,
    /// Ψ rows in T, `points.capacity() × MODE_CAPACITY` (the force projection).
    shapes: CacheAligned<T>,
    points: ContactPoints,
    /// ‖Ψ_i‖ per point (every mode the step advances), m/√J: what bounds a point's reach.
    shape_norms: Vec<f64>,
    /// The thread's points' spacing and offset from its top, m
    /// ([`ModalString::place_thread_lattice`]).
    thread_spacing_m: f64,
    thread_offset_m: f64,
    /// Steps since far points were last put to sleep.
    steps_since_sleep_check: usize,
    contact: ContactStep,
    /// The contact condensed on the grid's nodes (section 11), in use when `nodal_in_use`.
    nodal: NodalContact,
    nodal_in_use: bool,
    /// V rows in T, `NODE_CAPACITY × MODE_CAPACITY` (the nodes' projections), and the nodal
    /// force changes in T.
    node_shapes: CacheAligned<T>,
    node_forces: Vec<T>,
    solver: StaticSolver,
    /// The static problems on the nodes, with the condensed contact (`nodal_statics.rs`).
    statics: NodalStatics,
    loaded_forces: Vec<T>,
    /// r_rest (f64) and a scratch row.
    rest_modal: Vec<f64>,
    row: Vec<f64>,
    stats: NewtonStats,
    nut_force_change_n: f64,
    bridge_force_change_n: f64,
    rest_nut_force_n: f64,
    rest_bridge_force_n: f64,
    max_penetration_m: f64,
    cumulative_losses_j: f64,
    external_work_j: f64,
    static_solve_failures: u64,
    /// The last pluck's pressed modal state (`pressed_modal`, f64) and what it was pressed
    /// with: the finger's centre, width and amplitude, and whether its static solve converged.
    /// A pluck is a static solve from the rest state, not from the motion, so a string plucked
    /// again the same way before its configuration or rest state changes (the drone's strings,
    /// every cycle) takes it back instead of solving again, to the bit. On the nodes, a pluck
    /// at the same place and width pressed by another amplitude (a humanised drone's) takes
    /// the solved state shifted along its contact set's line while that set holds
    /// ([`NodalStatics::shifted_modal`]), the same state as its own solve's to round-off.
    last_press: Option<LastPress>,
    pressed_modal: Vec<f64>,
    /// Presses solved (plucks that did not take the last one's pressed state back).
    press_solves: u64,
    /// Static solves of the rest state since the string was built (the cost of a retune).
    rest_state_solves: u64,
    non_finite_resets: u64,
}

/// What a pluck pressed the string with, and whether the press's static solve converged
/// ([`ModalString::pluck`] keeps the last one's pressed state).
#[derive(Debug, Clone, Copy, PartialEq)]
struct LastPress {
    centre_m: f64,
    width_m: f64,
    amplitude_m: f64,
    converged: bool,
}

impl LastPress {
    /// The same finger, pressed as far: the same pressed state.
    fn same_finger(&self, other: &Self) -> bool {
        self.same_place(other) && self.amplitude_m == other.amplitude_m
    }

    /// The same finger at the same place: the same points, their free gaps shifted by the
    /// difference of the amplitudes.
    fn same_place(&self, other: &Self) -> bool {
        self.centre_m == other.centre_m && self.width_m == other.width_m
    }
}

impl<T: Real> ModalString<T> {
    /// Builds the string and settles it at rest on bridge and thread. Allocates.
    pub fn new(config: ModalStringConfig) -> Self {
        let config = config.sanitised();
        let points = config.point_capacity();
        let finger = grid_points(0.0, MAX_FINGER_WIDTH_M, config.finger.spacing_m);
        let mut string = Self {
            config,
            modes: ModeSet::new(),
            kernels: Kernels::detect(),
            lanes: 0,
            a: CacheAligned::new(MODE_CAPACITY, T::default()),
            b: CacheAligned::new(MODE_CAPACITY, T::default()),
            nut_weights: CacheAligned::new(MODE_CAPACITY, T::default()),
            modal: CacheAligned::new(MODE_CAPACITY, T::default()),
            velocity: CacheAligned::new(MODE_CAPACITY, T::default()),
            step: CacheAligned::new(MODE_CAPACITY, T::default()),
            whole_step: CacheAligned::new(MODE_CAPACITY, T::default()),
            shapes: CacheAligned::new(points * MODE_CAPACITY, T::default()),
            points: ContactPoints::with_capacity(points),
            shape_norms: vec![0.0; points],
            thread_spacing_m: config.thread_point_spacing_m,
            thread_offset_m: 0.0,
            steps_since_sleep_check: 0,
            contact: ContactStep::new(points),
            nodal: NodalContact::new(points),
            nodal_in_use: false,
            node_shapes: CacheAligned::new(NODE_CAPACITY * MODE_CAPACITY, T::default()),
            node_forces: vec![T::default(); NODE_CAPACITY],
            solver: StaticSolver::new(points + finger),
            statics: NodalStatics::new(points + finger),
            loaded_forces: vec![T::default(); points],
            rest_modal: vec![0.0; MODE_CAPACITY],
            row: vec![0.0; MODE_CAPACITY],
            stats: NewtonStats::default(),
            nut_force_change_n: 0.0,
            bridge_force_change_n: 0.0,
            rest_nut_force_n: 0.0,
            rest_bridge_force_n: 0.0,
            max_penetration_m: 0.0,
            cumulative_losses_j: 0.0,
            external_work_j: 0.0,
            static_solve_failures: 0,
            last_press: None,
            pressed_modal: vec![0.0; MODE_CAPACITY],
            press_solves: 0,
            rest_state_solves: 0,
            non_finite_resets: 0,
        };
        string.apply_config(false);
        string.reset();
        string
    }

    /// Changes the configuration without reallocating; the string keeps its motion (its modal
    /// displacement and velocity) about the new rest state. Returns false, changing nothing,
    /// when the new configuration needs more contact points than the string was built for.
    pub fn set_config(&mut self, config: ModalStringConfig) -> bool {
        let config = config.sanitised();
        if config.point_capacity() > self.points.capacity()
            || config.time_step_s.is_nan()
            || config.time_step_s <= 0.0
            || config.string.length_m != self.config.string.length_m
        {
            return false;
        }
        if config == self.config {
            return true;
        }
        // The motion in physical modal coordinates: q = r/√κ, q̇ ∝ p/√κ.
        let old_count = self.modes.count();
        for k in 0..MODE_CAPACITY {
            let scale = if k < old_count {
                self.modes.inverse_root_stiffness[k]
            } else {
                0.0
            };
            self.row[k] = (self.modal[k].to_f64() + self.rest_modal[k]) * scale;
            self.whole_step[k] = T::from_f64(self.velocity[k].to_f64() * scale);
        }
        // The string's losses (γ, η) do not enter the rest state, so neither the margins nor the
        // lattice the rule takes: a change of them alone keeps the lattice.
        let losses_alone = ModalStringConfig {
            string: StringParameters {
                gamma_per_s: config.string.gamma_per_s,
                eta_s: config.string.eta_s,
                ..self.config.string
            },
            ..self.config
        } == config;
        self.config = config;
        // Leaves the rest state solved for the new configuration.
        self.apply_config(losses_alone);
        let count = self.modes.count();
        for k in 0..MODE_CAPACITY {
            let root = if k < count {
                self.modes.stiffness[k].sqrt()
            } else {
                0.0
            };
            self.modal[k] = T::from_f64(self.row[k] * root - self.rest_modal[k]);
            self.velocity[k] = T::from_f64(self.whole_step[k].to_f64() * root);
        }
        self.refresh_gaps();
        true
    }

    /// Sets the modes for the configuration and places the points: on the lattice the string
    /// has with `keep_lattice` (a change that leaves the rest state alone), else on the one
    /// [`ModalString::place_thread_lattice`] takes. Leaves the rest state solved.
    fn apply_config(&mut self, keep_lattice: bool) {
        self.last_press = None;
        let config = self.config;
        self.modes.configure(
            &config.string,
            config.time_step_s,
            config.highest_mode_hz,
            config.grid_modes,
        );
        self.modes.set_residual_modes(
            config.residual_modes,
            2.0 * PI * RESIDUAL_MODE_RATE_FRACTION / config.time_step_s,
            &config.string,
            config.time_step_s,
        );
        self.lanes = padded_lanes(self.modes.count());
        for k in 0..MODE_CAPACITY {
            self.a[k] = T::from_f64(self.modes.a[k]);
            self.b[k] = T::from_f64(self.modes.b[k]);
            self.nut_weights[k] = T::from_f64(self.modes.nut_weight[k]);
        }
        if keep_lattice {
            self.place_points(self.thread_spacing_m, self.thread_offset_m);
            self.update_rest_state();
        } else {
            self.place_thread_lattice();
        }
    }

    /// With condensed grid modes, the nodes the points reach, their shapes and compliance
    /// (section 11): returns whether the contact is condensed on them. Not with other modes, nor
    /// when the points reach more than [`NODE_CAPACITY`] nodes (the point-level solve then).
    fn configure_nodes(&mut self) -> bool {
        self.nodal_in_use = match self.config.grid_modes {
            Some(grid) if grid.condensed => self.nodal.configure(
                &self.points,
                &self.modes,
                grid.intervals,
                self.config.string.length_m,
            ),
            _ => false,
        };
        if self.nodal_in_use {
            for (target, source) in self.node_shapes.iter_mut().zip(&self.nodal.node_shapes) {
                *target = T::from_f64(*source);
            }
        }
        self.nodal_in_use
    }

    /// Places the points, the thread's on the first of [`THREAD_LATTICES`] whose points all
    /// keep [`THREAD_EDGE_MARGIN`] from the rest state's contact edges (the first at once
    /// without a thread: its margin is infinite), or on the one with the largest margin; leaves
    /// the rest state solved on the lattice it keeps, one static solve per lattice tried.
    ///
    /// A thread point that lies at the edge of the string's contact at rest (barely touching,
    /// or barely clear) enters and leaves contact with the smallest vibration, so the contact
    /// solve takes a second Newton update in many steps; which points lie there depends on where
    /// the lattice falls against the contact region, which moves with the string's tension. At
    /// the live tier's 0.5 mm points, over 1 s of the one-string scene, key 59 takes 1.654
    /// updates per step on the top and 1.062 at 0.55 mm; over keys 36–64 the rule's most is
    /// 1.065 (key 60; `docs/performance.md`, "Stop 39"). No lattice tried is finer than the
    /// configured one: more points cost more per update. The lattice is a function of the
    /// configuration alone (the order of the lattices tried is fixed). Allocation-free; a retune
    /// solves the rest state once per lattice tried (once where the first is kept), and a
    /// lattice after the first re-places and re-couples the thread's points alone.
    fn place_thread_lattice(&mut self) {
        let configured_m = self.config.thread_point_spacing_m;
        let mut best = (f64::NEG_INFINITY, configured_m, 0.0);
        // On grid modes, the configured lattice alone (section 11: with the contact condensed
        // on the nodes a point at the contact's edge costs a lane, not a row of the solve; the
        // point-level solve takes the same points, so that the two solve the same string).
        let tried_lattices = if self.config.grid_modes.is_some() {
            1
        } else {
            THREAD_LATTICES.len()
        };
        for (tried, lattice) in THREAD_LATTICES[..tried_lattices].iter().enumerate() {
            let spacing_m = lattice.spacing * configured_m;
            let offset_m = lattice.offset * spacing_m;
            if tried == 0 {
                self.place_points(spacing_m, offset_m);
            } else {
                self.place_thread_points(spacing_m, offset_m);
            }
            self.update_rest_state();
            let margin = self.thread_edge_margin();
            if margin >= THREAD_EDGE_MARGIN {
                return;
            }
            if margin > best.0 {
                best = (margin, spacing_m, offset_m);
            }
        }
        if (best.1, best.2) != (self.thread_spacing_m, self.thread_offset_m) {
            self.place_thread_points(best.1, best.2);
            self.update_rest_state();
        }
    }

    /// How far the thread's points lie from the rest state's contact edges, the least over its
    /// points: a point in contact by its rest force over the largest of the thread's, a point
    /// clear of it by its gap over the cap's drop over one spacing (`Δx² / 2R_c`, the gap of
    /// the point next to one that touches the cap's top). 0 for a point at an edge; 1 or more
    /// for none near one. Infinite without a thread.
    fn thread_edge_margin(&self) -> f64 {
        let Some(thread) = self.config.thread else {
            return f64::INFINITY;
        };
        let points = &self.points;
        let thread_points = points.bridge_count()..points.len();
        let largest_force_n = points.rest_forces_n[thread_points.clone()]
            .iter()
            .fold(0.0f64, |largest, &force| largest.max(force));
        let spacing_m = self.thread_spacing_m;
        let gap_scale_m = spacing_m * spacing_m / (2.0 * thread.curvature_radius_m);
        thread_points
            .map(|i| {
                let force_n = points.rest_forces_n[i];
                if force_n > 0.0 {
                    force_n / largest_force_n
                } else {
                    // A rest gap is negative clear of contact.
                    (-points.rest_gaps_m[i]).max(0.0) / gap_scale_m
                }
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The thread's points' spacing, m ([`ModalString::place_thread_lattice`]).
    pub fn thread_lattice_spacing_m(&self) -> f64 {
        self.thread_spacing_m
    }

    /// The thread's points' offset from its top, m (0: a point on the top).
    pub fn thread_lattice_offset_m(&self) -> f64 {
        self.thread_offset_m
    }

    /// Places the points (the thread's `thread_spacing_m` apart, `thread_offset_m` from its
    /// top) and couples them to the modes.
    fn place_points(&mut self, thread_spacing_m: f64, thread_offset_m: f64) {
        let config = self.config;
        self.points.place_bridge(
            &config.bridge,
            config.bridge_first_point_m(),
            config.bridge_end_m(),
            config.bridge_point_spacing_m,
            config.time_step_s,
            config.string.left_support_m,
            config.string.length_m,
        );
        self.place_thread_coupling_from(thread_spacing_m, thread_offset_m, 0);
    }

    /// Places the thread's points anew (`thread_spacing_m` apart, `thread_offset_m` from its
    /// top) after [`Self::place_points`] for the same configuration: the bridge's points and
    /// their coupling stay.
    fn place_thread_points(&mut self, thread_spacing_m: f64, thread_offset_m: f64) {
        let first = self.points.bridge_count();
        self.place_thread_coupling_from(thread_spacing_m, thread_offset_m, first);
    }

    /// Places the thread's points after the bridge's and couples the points `first..`.
    fn place_thread_coupling_from(
        &mut self,
        thread_spacing_m: f64,
        thread_offset_m: f64,
        first: usize,
    ) {
        let config = self.config;
        self.thread_spacing_m = thread_spacing_m;
        self.thread_offset_m = thread_offset_m;
        if config.grid_modes.is_some() {
            self.points.place_thread_as_the_grid(
                &config.bridge,
                config.thread.as_ref(),
                thread_spacing_m,
                config.time_step_s,
                config.string.left_support_m,
                config.string.length_m,
            );
        } else {
            self.points.place_thread(
                &config.bridge,
                config.thread.as_ref(),
                thread_spacing_m,
                thread_offset_m,
                config.time_step_s,
                config.string.left_support_m,
                config.string.length_m,
            );
        }
        self.couple_points_from(first);
    }

    /// Couples the points `first..` to the modes (those before unchanged since they were); with
    /// the contact condensed on the grid's nodes, the nodes alone: every solve then works
    /// through them (section 11), and the points' shape rows are never formed.
    fn couple_points_from(&mut self, first: usize) {
        if self.configure_nodes() {
            self.points.flexible = false;
            return;
        }
        // From 0 after a condensed placement (whose rows were never formed) or with residual
        // modes (`ContactPoints::couple_from`).
        let first = if matches!(self.config.grid_modes, Some(grid) if grid.condensed) {
            0
        } else {
            first
        };
        let first = self.points.couple_from(
            first,
            &self.modes,
            self.config.static_flexibility,
            &self.kernels,
        );
        let rows = first * MODE_CAPACITY..;
        for (target, source) in self.shapes[rows.clone()]
            .iter_mut()
            .zip(&self.points.shapes[rows])
        {
            *target = T::from_f64(*source);
        }
        for (i, norm) in self.shape_norms[..self.points.len()]
            .iter_mut()
            .enumerate()
            .skip(first)
        {
            *norm = self
                .points
                .shape(i)
                .iter()
                .map(|psi| psi * psi)
                .sum::<f64>()
                .sqrt();
        }
    }

    /// Puts the string at rest on bridge and thread and clears every statistic and ledger.
    pub fn reset(&mut self) {
        self.update_rest_state();
        self.settle_to_rest();
        self.stats = NewtonStats::default();
        self.cumulative_losses_j = 0.0;
        self.external_work_j = 0.0;
        self.static_solve_failures = 0;
        self.non_finite_resets = 0;
    }

    /// The static equilibrium on bridge and thread (section 5), warm-started from the last one:
    /// on the nodes with the condensed contact (`nodal_statics.rs`), else on the points.
    fn update_rest_state(&mut self) {
        self.last_press = None;
        let count = self.points.len();
        let modes = self.modes.count();
        self.rest_state_solves += 1;
        let (forces, displacements, modal) = if self.nodal_in_use {
            if !self.solve_statics_on_nodes(|_| Ok(())) {
                self.static_solve_failures += 1;
            }
            let statics = &self.statics;
            (&statics.forces_n, &statics.displacements_m, &statics.modal)
        } else {
            let count = self.solver.load_points(&self.points);
            self.solver.forces_n[..count].copy_from_slice(&self.points.rest_forces_n[..count]);
            if !self.solver.solve(count, modes) {
                self.static_solve_failures += 1;
            }
            let solver = &self.solver;
            (&solver.forces_n, &solver.displacements_m, &solver.modal)
        };
        self.rest_modal.fill(0.0);
        self.rest_modal[..modes].copy_from_slice(&modal[..modes]);
        for i in 0..count {
            self.points.rest_forces_n[i] = forces[i];
            self.points.rest_gaps_m[i] = self.points.free_gaps_m[i] - displacements[i];
        }
        if self.nodal_in_use {
            self.nodal
                .set_rest_forces(&self.points.rest_forces_n[..count]);
        }
        let string = &self.config.string;
        self.rest_nut_force_n = string.tension_n * string.left_support_m / string.length_m
            + (0..modes)
                .map(|k| self.modes.nut_weight[k] * self.rest_modal[k])
                .sum::<f64>();
        self.rest_bridge_force_n = self.points.rest_forces_n[..count].iter().sum();
    }

    /// Solves the static problem [`Self::pose_statics_on_nodes`] poses (the bridge's and
    /// thread's points, and whatever `more` adds: the finger's points): whether it converged. A problem that does not fit the solver, or is not positive definite (neither
    /// happens for a finite configuration), has the string free of every point as its solution.
    fn solve_statics_on_nodes(
        &mut self,
        more: impl FnOnce(&mut NodalStatics) -> Result<(), NodalStaticsError>,
    ) -> bool {
        let posed = self
            .pose_statics_on_nodes(more)
            .and_then(|()| self.statics.solve(&self.modes));
        match posed {
            Ok(converged) => converged,
            Err(_) => {
                self.statics.clear_solution();
                false
            }
        }
    }

    /// Loads the bridge's and thread's points (from their rest forces) into the nodal static
    /// solver, then whatever `more` adds, and prepares the nodes' rows and stiffness.
    fn pose_statics_on_nodes(
        &mut self,
        more: impl FnOnce(&mut NodalStatics) -> Result<(), NodalStaticsError>,
    ) -> Result<(), NodalStaticsError> {
        let grid = self.config.grid_modes.ok_or(NodalStaticsError::NoGrid)?;
        let statics = &mut self.statics;
        statics.begin(grid.intervals, self.config.string.length_m);
        statics.add_contact_points(&self.points)?;
        more(statics)?;
        statics.prepare(&self.modes)
    }

    /// The free step `s_free = a p − b r` for the current state: what a step starts
    /// from. Every change of the state from outside a step ends here.
    fn prepare_free_step(&mut self) {
        let lanes = self.lanes;
        self.kernels.free_step(
            &self.a[..lanes],
            &self.b[..lanes],
            &self.modal[..lanes],
            &self.velocity[..lanes],
            &mut self.step[..lanes],
        );
    }

    /// The gaps of every point for the current state, `a_i = a_rest,i − Ψ_i r̃`, and the free
    /// step.
    fn refresh_gaps(&mut self) {
        self.prepare_free_step();
        if self.nodal_in_use {
            // Through the nodes: y = V r̃, a_i = a_rest,i − l_i · y.
            let modes = self.modes.count();
            let nodes = self.nodal.node_count();
            for j in 0..nodes {
                self.row[j] = self.nodal.node_shapes[j * MODE_CAPACITY..j * MODE_CAPACITY + modes]
                    .iter()
                    .zip(&self.modal[..modes])
                    .map(|(v, r)| v * r.to_f64())
                    .sum();
            }
            self.nodal
                .gaps_from_nodes(&self.points.rest_gaps_m, &self.row[..nodes]);
            let count = self.points.len();
            self.contact.gaps_m[..count].copy_from_slice(&self.nodal.gaps_m[..count]);
        } else {
            for i in 0..self.points.len() {
                self.contact.gaps_m[i] = self.modal_gap_m(i);
            }
        }
        self.classify_points();
    }

    /// The tracking of the points from scratch, from the gaps in `contact.gaps_m` (exact on
    /// entry), for the solve in use: with the contact condensed on the nodes, the nodal
    /// contact's (its gaps copied from those), else the point-level one's. The point-level
    /// solve is not read while the contact is condensed, and a change of configuration that
    /// takes it up again classifies it here first (`set_config` ends in `refresh_gaps`).
    /// Classifying it on the nodes as well cleared and refilled its block of couplings, a
    /// column of which strides the whole block: after half a second of steps those lines are
    /// out of cache, and that was a third of a ringing fine drone string's pluck, which took
    /// 73–806 µs where the same pluck repeated at once took 37–52 µs (`docs/performance.md`,
    /// "Stop 52").
    fn classify_points(&mut self) {
        if self.nodal_in_use {
            let count = self.points.len();
            self.nodal.gaps_m[..count].copy_from_slice(&self.contact.gaps_m[..count]);
            self.nodal.classify(TRACKING_BAND_M);
        } else {
            self.contact.classify(&self.points, TRACKING_BAND_M);
        }
    }

    /// The gaps of the points after the last step, from the solve in use.
    fn current_gaps_m(&self) -> &[f64] {
        if self.nodal_in_use {
            &self.nodal.gaps_m
        } else {
            &self.contact.gaps_m
        }
    }

    /// Point i's gap from the modal state, `a_rest,i − Ψ_i r̃`, in f64 (a step carries the
    /// gaps forward instead).
    fn modal_gap_m(&self, i: usize) -> f64 {
        let modes = self.modes.count();
        let displacement: f64 = self.points.shape(i)[..modes]
            .iter()
            .zip(&self.modal[..modes])
            .map(|(psi, r)| psi * r.to_f64())
            .sum();
        self.points.rest_gaps_m[i] - displacement
    }

    /// Puts a decayed string exactly at rest (the sleeping state), keeping the ledgers.
    pub fn settle_to_rest(&mut self) {
        let energy_before = self.vibration_energy_j();
        self.modal.fill(T::default());
        self.velocity.fill(T::default());
        self.step.fill(T::default());
        let count = self.points.len();
        self.contact.gaps_m[..count].copy_from_slice(&self.points.rest_gaps_m[..count]);
        self.classify_points();
        self.prepare_free_step();
        self.external_work_j -= energy_before;
        self.nut_force_change_n = 0.0;
        self.bridge_force_change_n = 0.0;
        self.max_penetration_m = 0.0;
    }

    /// Advances one sample (eq. M1 with Newton on the tracked points, section 4). Allocation-free;
    /// never panics. The whole step (dot products, contact solve, mode update) runs as one
    /// function compiled for the machine's vector unit.
    pub fn step(&mut self) {
        T::step_string(self);
    }

    /// [`ModalString::step`]'s body, instantiated in this crate only ([`Real::step_string`]).
    fn dispatch_step(&mut self) {
        let kernels = self.kernels;
        kernels.arch.dispatch(WholeStep { string: self });
    }

    /// [`ModalString::step`] once per element of `output`, writing each step's pickup signal
    /// ([`weighted_pickup_n`] with `nut_weight`, N) as f32: one dispatch to the vector unit for
    /// the whole run.
    pub fn step_into(&mut self, output: &mut [f32], nut_weight: f64) {
        T::step_string_into(self, output, nut_weight);
    }

    /// [`ModalString::step_into`]'s body, instantiated in this crate only
    /// ([`Real::step_string_into`]).
    fn dispatch_step_into(&mut self, output: &mut [f32], nut_weight: f64) {
        let kernels = self.kernels;
        kernels.arch.dispatch(StepRun {
            string: self,
            output,
            nut_weight,
        });
    }

    /// [`ModalString::step`] on the vector unit `simd`.
    #[inline(always)]
    fn step_on<S: Simd>(&mut self, simd: S) {
        if self.nodal_in_use {
            self.step_on_nodes(simd);
            return;
        }
        // The kernels run over the kept modes, padded to whole registers; `step` holds s_free.
        let lanes = self.lanes;
        // Every awake point's free step Ψ_i s_free, one dot product per point; far points are
        // put to sleep every SLEEP_CHECK_STEPS steps.
        self.steps_since_sleep_check += 1;
        if self.steps_since_sleep_check >= SLEEP_CHECK_STEPS {
            self.steps_since_sleep_check = 0;
            self.sleep_far_points();
        }
        if let Some(free_steps) = self.contact.point_free_steps_mut(self.points.len()) {
            LeadingDots {
                matrix: &self.shapes,
                stride: MODE_CAPACITY,
                x: &self.step[..lanes],
                out: free_steps,
            }
            .with_simd(simd);
        } else {
            let (rows, free_steps) = self.contact.awake_rows();
            Dots::<T, true> {
                matrix: &self.shapes,
                stride: MODE_CAPACITY,
                rows,
                x: &self.step[..lanes],
                out: free_steps,
            }
            .with_simd(simd);
        }
        // The contact solve, and the tracking for the next step (which reads only the gaps and
        // forces, not the modes).
        let outcome = self.contact.step(
            simd,
            &self.points,
            &self.config.newton,
            self.config.track_energy,
            TRACKING_BAND_M,
            2.0 * TRACKING_BAND_M,
        );
        self.stats.record(outcome.iterations, outcome.converged);
        if self.config.track_energy {
            // Contact damping at this step's forces; the modes' loss needs the whole step below.
            self.cumulative_losses_j += outcome.damping_loss_j;
        }
        let (_, changes) = self.contact.loaded();
        let mut bridge_change = 0.0;
        for (value, change) in self.loaded_forces.iter_mut().zip(changes) {
            *value = T::from_f64(*change);
            bridge_change += change;
        }
        self.advance_and_finish(simd, false, bridge_change, outcome.penetration_m);
    }

    /// The end of a step: the modes advanced by eq. M1 with the force changes of the solve in
    /// use on their shape rows (the nodes' with `on_nodes`, section 11; else the loaded points'),
    /// the modes' loss booked, and the outputs set; a non-finite state cannot recover, so it
    /// silences the string at rest (fail soft).
    #[inline(always)]
    fn advance_and_finish<S: Simd>(
        &mut self,
        simd: S,
        on_nodes: bool,
        bridge_change: f64,
        penetration_m: f64,
    ) {
        let lanes = self.lanes;
        let (rows, forces, matrix) = if on_nodes {
            let rows = self.nodal.loaded().0;
            (rows, &self.node_forces[..rows.len()], &self.node_shapes[..])
        } else {
            let rows = self.contact.loaded().0;
            (rows, &self.loaded_forces[..rows.len()], &self.shapes[..])
        };
        let nut_change = AdvanceAndPrepare {
            a: &self.a[..lanes],
            b: &self.b[..lanes],
            c: &self.nut_weights[..lanes],
            matrix,
            stride: MODE_CAPACITY,
            rows,
            forces,
            work: &mut self.whole_step[..lanes],
            s: &mut self.step[..lanes],
            r: &mut self.modal[..lanes],
            p: &mut self.velocity[..lanes],
        }
        .with_simd(simd);
        if self.config.track_energy {
            self.cumulative_losses_j += (0..self.modes.count())
                .map(|k| {
                    let s = self.whole_step[k].to_f64();
                    self.modes.loss_factor[k] * s * s
                })
                .sum::<f64>();
        }
        self.nut_force_change_n = nut_change;
        self.bridge_force_change_n = bridge_change;
        self.max_penetration_m = penetration_m;
        if !nut_change.is_finite() || !bridge_change.is_finite() {
            self.non_finite_resets += 1;
            let external = self.external_work_j;
            self.settle_to_rest();
            self.external_work_j = external;
        }
    }

    /// [`ModalString::step`] with the contact condensed on the grid's nodes (section 11): the
    /// nodes' free steps, Newton on the nodes, the modes forced through the node rows.
    #[inline(always)]
    fn step_on_nodes<S: Simd>(&mut self, simd: S) {
        let lanes = self.lanes;
        // Whole groups of four rows (the dots past the nodes are never read), so that every
        // row takes the four-row kernel: NODE_CAPACITY is a multiple of four.
        let rows = self.nodal.node_count().next_multiple_of(4);
        let time = step_timers::start();
        LeadingDots {
            matrix: &self.node_shapes,
            stride: MODE_CAPACITY,
            x: &self.step[..lanes],
            out: &mut self.nodal.node_free_steps_m[..rows],
        }
        .with_simd(simd);
        step_timers::add(StepPart::NodeDots, time);
        let outcome = self.nodal.step(
            simd,
            &self.config.newton,
            self.config.track_energy,
            TRACKING_BAND_M,
            2.0 * TRACKING_BAND_M,
        );
        self.stats.record(outcome.iterations, outcome.converged);
        if self.config.track_energy {
            self.cumulative_losses_j += outcome.damping_loss_j;
        }
        let (_, changes) = self.nodal.loaded();
        for (value, change) in self.node_forces.iter_mut().zip(changes) {
            *value = T::from_f64(*change);
        }
        let time = step_timers::start();
        self.advance_and_finish(simd, true, outcome.force_change_n, outcome.penetration_m);
        step_timers::add(StepPart::Advance, time);
    }

    /// Puts to sleep the far points that the string's vibration energy cannot carry into
    /// contact before its next excitation ([`ContactStep::sleep_far_points`]): `‖r̃‖ ≤ √(2 H_v)`,
    /// with 1 % more energy for the f32 state's rounding.
    fn sleep_far_points(&mut self) {
        if !self.config.sleep_far_points {
            return;
        }
        let energy = self.vibration_energy_j();
        if !energy.is_finite() {
            return;
        }
        let reach = (2.02 * energy.max(0.0)).sqrt();
        self.contact
            .sleep_far_points(&self.points, &self.shape_norms, reach);
    }

    /// How many grid nodes the contact is condensed on (section 11); 0 when it is solved on the
    /// points.
    pub fn contact_node_count(&self) -> usize {
        if self.nodal_in_use {
            self.nodal.node_count()
        } else {
            0
        }
    }

    /// How many contact points are awake (the others provably cannot touch before the next
    /// excitation, so their free steps are not computed).
    pub fn awake_point_count(&self) -> usize {
        if self.nodal_in_use {
            // The condensed contact steps every point.
            self.points.len()
        } else {
            self.contact.awake_count()
        }
    }

    /// Forgets Newton's initial guess, so that a new excitation evolves exactly as it would on
    /// a freshly built string.
    fn forget_motion_history(&mut self) {
        self.contact.forget_corrections();
        self.nodal.forget_corrections();
    }

    /// `Σ_k Ψ_k(x) c_k` for modal coefficients `c_k`, with the sines by recurrence (no scratch,
    /// so `&self`).
    fn modal_sum(&self, x_m: f64, coefficient: impl Fn(usize) -> f64) -> f64 {
        self.modes.shape_sum(x_m, coefficient)
    }

    /// y_s(x), the line between the supports, m.
    fn line_at_m(&self, x_m: f64) -> f64 {
        self.config.string.left_support_m * (1.0 - x_m / self.config.string.length_m)
    }

    /// The rest shape's displacement at `x_m`, m: `y_s(x) + Σ_k Ψ_k(x) r_rest,k`, or with the
    /// static flexibility the continuous string's `y_s(x) + Σ_i C(x, x_i) F_rest,i`.
    pub fn rest_displacement_at_m(&self, x_m: f64) -> f64 {
        if !self.points.flexible {
            return self.line_at_m(x_m) + self.modal_sum(x_m, |k| self.rest_modal[k]);
        }
        let points = &self.points;
        let pressed: f64 = (0..points.len())
            .filter(|&i| points.rest_forces_n[i] != 0.0)
            .map(|i| {
                self.modes.static_compliance_m_n(x_m, points.positions_m[i])
                    * points.rest_forces_n[i]
            })
            .sum();
        self.line_at_m(x_m) + pressed
    }

    /// The string's displacement at `x_m` now, m: the rest shape and the kept modes' motion
    /// `Σ_k Ψ_k(x) r̃_k` (the step moves the string in its kept modes only).
    pub fn displacement_at_m(&self, x_m: f64) -> f64 {
        self.rest_displacement_at_m(x_m) + self.modal_sum(x_m, |k| self.modal[k].to_f64())
    }

    /// The seed's finger pluck (section 5): press the finger until the string is in static
    /// equilibrium against finger, bridge and thread, then release it. The previous motion is
    /// stopped by the finger; the work done is booked as external work. Allocation-free.
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
        let modes = self.modes.count();
        let press = LastPress {
            centre_m: centre,
            width_m: width,
            amplitude_m: amplitude,
            converged: true,
        };
        let last_press = self.last_press;
        match last_press {
            Some(last) if last.same_finger(&press) => {
                self.row[..modes].copy_from_slice(&self.pressed_modal[..modes]);
                if !last.converged {
                    self.static_solve_failures += 1;
                }
            }
            Some(last) if self.shift_last_press(&last, &press) => {}
            _ => {
                let failures = self.static_solve_failures;
                self.press_solves += 1;
                let top = self.rest_displacement_at_m(centre) + amplitude;
                if self.nodal_in_use {
                    // Where the shift does not hold, the same finger at the same place still
                    // loads the same points: only the finger's gaps change.
                    let same_place = last_press.is_some_and(|last| last.same_place(&press));
                    if same_place && self.statics.holds_prepared_shift() {
                        self.repress_finger_on_nodes(centre, width, top);
                    } else {
                        self.press_finger_on_nodes(centre, width, top);
                    }
                    if self.static_solve_failures == failures {
                        self.statics.prepare_shift(self.points.len(), &self.modes);
                    }
                } else {
                    self.press_finger_on_points(centre, width, top);
                }
                self.pressed_modal[..modes].copy_from_slice(&self.row[..modes]);
                self.last_press = Some(LastPress {
                    converged: self.static_solve_failures == failures,
                    ..press
                });
            }
        }
        for k in 0..MODE_CAPACITY {
            let pressed = if k < modes { self.row[k] } else { 0.0 };
            self.modal[k] = T::from_f64(pressed - self.rest_modal[k]);
        }
        self.velocity.fill(T::default());
        self.refresh_gaps();
        self.external_work_j += self.energy_j() - energy_before;
        self.refresh_outputs_at_rest_of_motion();
    }

    /// The pressed string of a pluck on the nodes (`nodal_statics.rs`): the finger's points
    /// (`width` m wide, centred at `centre` m, its top at `top` m) join the bridge's and the
    /// thread's; the pressed modal state is left in `row`.
    fn press_finger_on_nodes(&mut self, centre: f64, width: f64, top: f64) {
        let spacing = self.config.finger.spacing_m;
        let finger_points = grid_points(0.0, width, spacing);
        let spring = self.config.finger.stiffness_n_m2 * spacing;
        let finger = FingerPress::new(&self.config, centre, width, top);
        let converged = self.solve_statics_on_nodes(|statics| {
            (0..finger_points).try_for_each(|index| {
                let (x, gap) = finger.point(index);
                statics.add_point(x, gap, spring, 0.0)
            })
        });
        if !converged {
            self.static_solve_failures += 1;
        }
        let modes = self.modes.count();
        self.row[..modes].copy_from_slice(&self.statics.modal[..modes]);
    }

    /// The pressed state of `press` into `row` from the `last` one's, shifted along its contact
    /// set ([`NodalStatics::shifted_modal`]), if `press` is at the same place and the set
    /// holds. The static solver holds a prepared shift only after a converged press on the
    /// nodes (`pluck`), until it poses another problem.
    fn shift_last_press(&mut self, last: &LastPress, press: &LastPress) -> bool {
        let modes = self.modes.count();
        self.nodal_in_use
            && last.same_place(press)
            && self.statics.shifted_modal(
                press.amplitude_m - last.amplitude_m,
                &self.pressed_modal[..modes],
                &mut self.row[..modes],
            )
    }

    /// [`Self::press_finger_on_nodes`] on the problem the last press loaded and prepared (the
    /// same points, the same nodes' rows and stiffness), with the finger's gaps for `top` and
    /// the solve started from the last press's forces.
    fn repress_finger_on_nodes(&mut self, centre: f64, width: f64, top: f64) {
        let finger = FingerPress::new(&self.config, centre, width, top);
        let first = self.points.len();
        for index in 0..grid_points(0.0, width, self.config.finger.spacing_m) {
            self.statics
                .set_free_gap(first + index, finger.point(index).1);
        }
        let converged = self.statics.solve(&self.modes).unwrap_or_else(|_| {
            self.statics.clear_solution();
            false
        });
        if !converged {
            self.static_solve_failures += 1;
        }
        let modes = self.modes.count();
        self.row[..modes].copy_from_slice(&self.statics.modal[..modes]);
    }

    /// The pressed string of a pluck on the points (section 5, `solve.rs`); the pressed modal
    /// state is left in `row`.
    fn press_finger_on_points(&mut self, centre: f64, width: f64, top: f64) {
        let count = self.solver.load_points(&self.points);
        let spacing = self.config.finger.spacing_m;
        let finger_points = grid_points(0.0, width, spacing).min(self.solver.capacity() - count);
        let finger = FingerPress::new(&self.config, centre, width, top);
        for index in 0..finger_points {
            let (x, gap) = finger.point(index);
            let row = count + index;
            self.modes.shape_row(
                x,
                &mut self.solver.shapes[row * MODE_CAPACITY..(row + 1) * MODE_CAPACITY],
            );
            self.solver.free_gaps_m[row] = gap;
            self.solver.springs_n_m[row] = self.config.finger.stiffness_n_m2 * spacing;
            self.solver.forces_n[row] = 0.0;
            // The truncated modes' compliance between this finger point and every row so far.
            for other in 0..=row {
                let value = if self.config.static_flexibility {
                    let x_other = if other < count {
                        self.points.positions_m[other]
                    } else {
                        finger.point(other - count).0
                    };
                    let shapes = &self.solver.shapes;
                    self.modes.residual_compliance_m_n(
                        x,
                        x_other,
                        &shapes[row * MODE_CAPACITY..(row + 1) * MODE_CAPACITY],
                        &shapes[other * MODE_CAPACITY..(other + 1) * MODE_CAPACITY],
                    )
                } else {
                    0.0
                };
                self.solver.set_residual(row, other, value);
            }
        }
        self.solver.forces_n[..count].copy_from_slice(&self.points.rest_forces_n[..count]);
        let modes = self.modes.count();
        if !self.solver.solve(count + finger_points, modes) {
            self.static_solve_failures += 1;
        }
        self.row[..modes].copy_from_slice(&self.solver.modal[..modes]);
    }

    /// The seed's "first mode" initial condition: the rest shape plus `amplitude_m` times the
    /// first mode of the speaking length, released from rest. Allocation-free.
    pub fn excite_first_mode(&mut self, amplitude_m: f64) {
        self.forget_motion_history();
        let energy_before = self.energy_j();
        let start = self.config.speaking_start_m();
        let length = self.config.string.length_m;
        for k in 0..MODE_CAPACITY {
            let value = if k < self.modes.count() {
                // q_k = (2/L) ∫ A sin(π(x − x₀)/(L − x₀)) sin(β_k x) dx over the speaking length.
                let projection = first_mode_projection(start, length, k + 1);
                amplitude_m * projection * self.modes.stiffness[k].sqrt()
            } else {
                0.0
            };
            self.modal[k] = T::from_f64(value);
        }
        self.velocity.fill(T::default());
        self.refresh_gaps();
        self.external_work_j += self.energy_j() - energy_before;
        self.refresh_outputs_at_rest_of_motion();
    }

    fn refresh_outputs_at_rest_of_motion(&mut self) {
        let modes = self.modes.count();
        self.nut_force_change_n = (0..modes)
            .map(|k| self.modes.nut_weight[k] * self.modal[k].to_f64())
            .sum();
        self.bridge_force_change_n = (0..self.points.len())
            .map(|i| {
                self.points.springs_n_m[i] * self.current_gaps_m()[i].max(0.0)
                    - self.points.rest_forces_n[i]
            })
            .sum();
    }

    /// The vibration energy above the rest state (section 4), J: non-negative, computed
    /// without cancellation; what decides when a string may sleep.
    pub fn vibration_energy_j(&self) -> f64 {
        let modes: f64 = (0..self.modes.count())
            .map(|k| {
                let (r, p) = (self.modal[k].to_f64(), self.velocity[k].to_f64());
                0.5 * r * r + self.modes.kinetic_factor[k] * p * p
            })
            .sum();
        modes + self.points.excess_energy_j(self.current_gaps_m())
    }

    /// H at the rest state, J: the tension over the lowered support, the modes' rest
    /// deflection and the contact potential at rest.
    pub fn rest_energy_j(&self) -> f64 {
        let string = &self.config.string;
        let line = 0.5 * string.tension_n * string.left_support_m * string.left_support_m
            / string.length_m;
        let modes: f64 = self.rest_modal.iter().map(|r| 0.5 * r * r).sum();
        line + modes + self.points.potential_energy_j(&self.points.rest_gaps_m)
    }

    /// The discrete energy H of eq. M3, J.
    pub fn energy_j(&self) -> f64 {
        self.rest_energy_j() + self.vibration_energy_j()
    }

    /// The nut force minus its rest value after the last step (eq. 13), N.
    pub fn nut_force_change_n(&self) -> f64 {
        self.nut_force_change_n
    }

    /// The bridge and thread force minus its rest value over the last step (eq. 12), N.
    pub fn bridge_force_change_n(&self) -> f64 {
        self.bridge_force_change_n
    }

    /// The force on the nut after the last step (eq. 13), N.
    pub fn nut_force_n(&self) -> f64 {
        self.rest_nut_force_n + self.nut_force_change_n
    }

    /// The total force of bridge and thread on the string over the last step (eq. 12), N.
    pub fn bridge_force_n(&self) -> f64 {
        self.rest_bridge_force_n + self.bridge_force_change_n
    }

    pub fn rest_nut_force_n(&self) -> f64 {
        self.rest_nut_force_n
    }

    pub fn rest_bridge_force_n(&self) -> f64 {
        self.rest_bridge_force_n
    }

    /// Energy dissipated since the last reset, J (booked only when `track_energy` is on).
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

    /// Deepest penetration into bridge or thread after the last step, m.
    pub fn max_penetration_m(&self) -> f64 {
        self.max_penetration_m
    }

    pub fn static_solve_failures(&self) -> u64 {
        self.static_solve_failures
    }

    /// Static solves of the rest state since the string was built: one per thread lattice tried
    /// on each configuration change, one for a change of the losses alone and one per reset.
    pub fn rest_state_solves(&self) -> u64 {
        self.rest_state_solves
    }

    pub fn non_finite_resets(&self) -> u64 {
        self.non_finite_resets
    }

    pub fn config(&self) -> &ModalStringConfig {
        &self.config
    }

    pub fn modes(&self) -> &ModeSet {
        &self.modes
    }

    pub fn points(&self) -> &ContactPoints {
        &self.points
    }

    /// The modal state about the rest state: `r̃_k` and `p_k` of the kept modes (section 4).
    pub fn modal_state(&self) -> (&[T], &[T]) {
        let count = self.modes.count();
        (&self.modal[..count], &self.velocity[..count])
    }

    /// The gaps a_i of the points after the last step, m (positive: the string penetrates):
    /// an awake point's carried by its step (`a_rest,i − Ψ_i r̃` to within a few nanometres of
    /// round-off, tested), a sleeping point's as it fell asleep (its true gap stays at least
    /// 10 µm short of contact); [`ModalString::displacement_at_m`] gives the shape anywhere.
    pub fn gaps_m(&self) -> &[f64] {
        &self.current_gaps_m()[..self.points.len()]
    }

    /// The points' positions, m: the bridge's first ([`ModalString::bridge_point_count`]), then
    /// the thread's.
    pub fn point_positions_m(&self) -> &[f64] {
        &self.points.positions_m[..self.points.len()]
    }

    /// How many of the points lie on the bridge (the rest lie on the thread).
    pub fn bridge_point_count(&self) -> usize {
        self.points.bridge_count()
    }

    /// The fundamental of small vibrations about the rest state with every point in contact at
    /// rest acting as a spring of its stiffness, Hz (section 5). Allocation-free.
    pub fn linearised_fundamental_hz(&mut self) -> f64 {
        self.linearised_fundamental_settled_hz(RAYLEIGH_SETTLED)
    }

    /// [`ModalString::linearised_fundamental_hz`] with the inverse iteration stopped once its
    /// Rayleigh quotient moves by at most `settled_below` of itself ([`rayleigh_settled`]).
    fn linearised_fundamental_settled_hz(&mut self, settled_below: f64) -> f64 {
        let modes = self.modes.count();
        let angular = if self.nodal_in_use {
            // On the nodes (`nodal_statics.rs`), with the contact points alone loaded.
            if self.pose_statics_on_nodes(|_| Ok(())).is_err() {
                return f64::NAN;
            }
            self.statics.linearised_fundamental(
                &self.points.rest_forces_n,
                &self.modes.angular_frequency,
                modes,
                TUNING_ITERATIONS,
                settled_below,
            )
        } else {
            linearised_fundamental(
                &self.points,
                &self.modes.angular_frequency,
                modes,
                &mut self.solver,
                TUNING_ITERATIONS,
                settled_below,
            )
        };
        angular / (2.0 * PI)
    }

    /// The point nearest the nut in contact at rest, m: the start of the speaking length.
    pub fn rest_contact_end_m(&self) -> Option<f64> {
        (0..self.points.len())
            .filter(|&i| self.points.rest_forces_n[i] > 0.0)
            .map(|i| self.points.positions_m[i])
            .reduce(f64::max)
    }
}

/// The finger of a pluck pressed with its top at `top` m: its points every `spacing` across
/// `width` m centred at `centre` m, each with its free gap from the line between the supports.
struct FingerPress {
    centre: f64,
    width: f64,
    top: f64,
    spacing: f64,
    length: f64,
    left: f64,
}

impl FingerPress {
    fn new(config: &ModalStringConfig, centre: f64, width: f64, top: f64) -> Self {
        Self {
            centre,
            width,
            top,
            spacing: config.finger.spacing_m,
            length: config.string.length_m,
            left: config.string.left_support_m,
        }
    }

    /// The finger's point `index`: its position and free gap, m.
    fn point(&self, index: usize) -> (f64, f64) {
        let x = self.centre - 0.5 * self.width + index as f64 * self.spacing;
        let gap = finger_height_m(x, self.centre, self.width, self.top)
            - self.left * (1.0 - x / self.length);
        (x, gap)
    }
}

/// `(2/L) ∫ sin(π(x − x₀)/ℓ) sin(kπx/L) dx` over `[x₀, L]`, ℓ = L − x₀: the first mode of the
/// speaking length projected on mode k of the whole string, in closed form.
fn first_mode_projection(start_m: f64, length_m: f64, k: usize) -> f64 {
    let speaking = length_m - start_m;
    let alpha = PI / speaking;
    let beta = k as f64 * PI / length_m;
    // sin(α(x − x₀)) sin(βx) = ½[cos((α − β)x − αx₀) − cos((α + β)x − αx₀)].
    let cosine_integral = |u: f64| {
        // ∫ cos(u x − α x₀) dx over [x₀, L], stable as u → 0.
        let middle = 0.5 * (start_m + length_m);
        let half = 0.5 * speaking;
        let phase = u * middle - alpha * start_m;
        if (u * half).abs() < 1e-9 {
            speaking * phase.cos()
        } else {
            2.0 * phase.cos() * (u * half).sin() / u
        }
    };
    (2.0 / length_m) * 0.5 * (cosine_integral(alpha - beta) - cosine_integral(alpha + beta))
}

/// [`ModalString::step_into`] as one function for the vector unit pulp picks.
struct StepRun<'a, T: Real> {
    string: &'a mut ModalString<T>,
    output: &'a mut [f32],
    nut_weight: f64,
}

impl<T: Real> WithSimd for StepRun<'_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let (string, weight) = (self.string, self.nut_weight);
        for sample in self.output {
            string.step_on(simd);
            let pickup = weighted_pickup_n(
                weight,
                string.nut_force_change_n,
                string.bridge_force_change_n,
            );
            *sample = pickup as f32;
        }
    }
}

/// [`ModalString::step`] as one function for the vector unit pulp picks.
struct WholeStep<'a, T: Real> {
    string: &'a mut ModalString<T>,
}

impl<T: Real> WithSimd for WholeStep<'_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        self.string.step_on(simd);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_mode_projection_matches_quadrature() {
        let (start, length) = (0.04, 0.668);
        for k in [1, 2, 7, 30] {
            let n = 200_000;
            let dx = (length - start) / n as f64;
            let numeric: f64 = (0..n)
                .map(|i| {
                    let x = start + (i as f64 + 0.5) * dx;
                    (PI * (x - start) / (length - start)).sin() * (k as f64 * PI * x / length).sin()
                })
                .sum::<f64>()
                * dx
                * 2.0
                / length;
            let closed = first_mode_projection(start, length, k);
            assert!(
                (numeric - closed).abs() < 1e-8,
                "k = {k}: {numeric} vs {closed}"
            );
        }
    }

    /// The gaps a step carries forward by the points' steps (`ContactStep::finish_step`) stay
    /// those of the modal state, `a_rest,i − Ψ_i r̃`, at every awake point over a long ring in
    /// single precision, although no gap is recomputed between plucks. Measured: at most 2.1 nm
    /// (the tracked points' Newton steps and the f32 state's rounding), reached within the first
    /// 3 s and not growing after. Every sleeping point's true gap stays below its margin, and
    /// points do fall asleep as the string decays.
    #[test]
    fn carried_gaps_stay_the_modal_states_over_twenty_seconds() {
        let mut string = ModalString::<f32>::new(ModalStringConfig::REFERENCE);
        string.pluck(&Pluck::default());
        let steps = (20.0 / string.config().time_step_s) as usize;
        let (mut worst, mut closest_sleeper, mut fewest_awake) = (0.0f64, f64::MIN, usize::MAX);
        for step in 1..=steps {
            string.step();
            if step % 4_410 == 0 {
                for i in 0..string.points.len() {
                    if string.contact.is_awake(i) {
                        let error = string.contact.gaps_m[i] - string.modal_gap_m(i);
                        worst = worst.max(error.abs());
                    } else {
                        closest_sleeper = closest_sleeper.max(string.modal_gap_m(i));
                    }
                }
                fewest_awake = fewest_awake.min(string.awake_point_count());
            }
        }
        assert!(worst < 1e-8, "carried gaps off by {worst:e} m");
        assert!(
            closest_sleeper < -10e-6,
            "a sleeping point came within {closest_sleeper:e} m"
        );
        assert!(
            fewest_awake < string.points.len() / 2,
            "{fewest_awake} of {} points awake after 20 s",
            string.points.len()
        );
    }

    /// Far points asleep or not, the string's output is the same bit for bit: a sleeping point is
    /// one that cannot touch, so skipping its free step changes nothing (here through a pluck,
    /// 1.5 s of ringing, a second pluck that wakes every point and 1.5 s more).
    #[test]
    fn sleeping_far_points_change_nothing() {
        let run = |sleep_far_points: bool| {
            let mut string = ModalString::<f32>::new(ModalStringConfig {
                sleep_far_points,
                ..ModalStringConfig::REFERENCE
            });
            let mut output = Vec::new();
            let mut fewest_awake = usize::MAX;
            for pluck in [
                Pluck::default(),
                Pluck {
                    amplitude_m: 4e-3,
                    ..Pluck::default()
                },
            ] {
                string.pluck(&pluck);
                for _ in 0..66_150 {
                    string.step();
                    output.push(string.nut_force_n().to_bits());
                    output.push(string.bridge_force_n().to_bits());
                    fewest_awake = fewest_awake.min(string.awake_point_count());
                }
            }
            (output, fewest_awake)
        };
        let (asleep, fewest_awake) = run(true);
        let (awake, all_awake) = run(false);
        assert_eq!(
            all_awake,
            ModalString::<f32>::new(ModalStringConfig::REFERENCE)
                .points
                .len()
        );
        assert!(fewest_awake < all_awake, "no point fell asleep");
        assert!(asleep == awake, "sleeping points changed the output");
    }

    /// The contact solve in fixed lanes (`block.rs`: up to eight tracked points, and up to
    /// sixteen) gives the general path's iterates: the same outputs bit for bit (to the sign of a
    /// zero) and the same Newton updates, through a pluck and a harder second pluck on the
    /// bench's grid, and on a finer grid where more than eight and more than sixteen points are
    /// tracked at times (more than sixteen: both take the general path).
    #[test]
    fn fixed_lanes_solve_as_the_general_path() {
        let run = |spacing_m: f64, general_path_only: bool| {
            let mut string = ModalString::<f32>::new(ModalStringConfig {
                bridge_point_spacing_m: spacing_m,
                thread_point_spacing_m: 0.5 * spacing_m,
                ..ModalStringConfig::REFERENCE
            });
            if general_path_only {
                string.contact.take_general_path_only();
            }
            // Steps with at most 8, 9 to 16, and more than 16 points tracked.
            let (mut output, mut widths) = (Vec::new(), [0usize; 3]);
            for amplitude_m in [2e-3, 4e-3] {
                string.pluck(&Pluck {
                    amplitude_m,
                    ..Pluck::default()
                });
                for _ in 0..44_100 {
                    string.step();
                    output.push((string.nut_force_n(), string.bridge_force_n()));
                    let tracked = string.contact.tracked_count();
                    widths[usize::from(tracked > 8) + usize::from(tracked > 16)] += 1;
                }
            }
            (output, widths, *string.newton_stats())
        };
        let mut all_widths = [0usize; 3];
        for spacing_m in [1e-3, 0.25e-3] {
            let (lanes, widths, lane_stats) = run(spacing_m, false);
            let (general, _, general_stats) = run(spacing_m, true);
            assert!(lanes == general, "the paths part at spacing {spacing_m}");
            assert_eq!(lane_stats, general_stats);
            assert!(lane_stats.iterations > lane_stats.steps, "{lane_stats:?}");
            eprintln!("spacing {spacing_m}: steps by tracked width {widths:?}");
            for (all, width) in all_widths.iter_mut().zip(widths) {
                *all += width;
            }
        }
        assert!(all_widths.iter().all(|&steps| steps > 0), "{all_widths:?}");
    }

    /// Asserts that both pickups (nut, bridge) of `other` lie sample by sample within
    /// `relative` times their range in `ranged` of `ranged`'s.
    fn assert_pickups_within(ranged: &[[f64; 2]], other: &[[f64; 2]], relative: f64) {
        for pickup in 0..2 {
            let range = ranged.iter().map(|f| f[pickup].abs()).fold(0.0, f64::max);
            let worst = ranged
                .iter()
                .zip(other)
                .map(|(a, b)| (a[pickup] - b[pickup]).abs())
                .fold(0.0, f64::max);
            assert!(
                worst <= relative * range,
                "pickup {pickup}: {worst:e} of {range:e}"
            );
        }
    }

    /// The reference's string on its own grid's modes (N = 200, the trapezoidal rule at
    /// 4 × 44.1 kHz), contact points every `bridge_m` on the bridge and `thread_m` on the
    /// thread, the contact condensed on the grid's nodes or not (f64 modes in the tests that
    /// compare its solves).
    pub(super) fn grid_mode_config(
        bridge_m: f64,
        thread_m: f64,
        condensed: bool,
    ) -> ModalStringConfig {
        ModalStringConfig {
            bridge_point_spacing_m: bridge_m,
            thread_point_spacing_m: thread_m,
            grid_modes: Some(GridModes {
                intervals: 200,
                time_step_s: 1.0 / (4.0 * 44_100.0),
                condensed,
            }),
            ..ModalStringConfig::REFERENCE
        }
    }

    /// The condensed contact's update in fixed lanes (up to 8 and 16 nodes, every step here)
    /// and on the general path play the same string, to round-off (the two factorisations round
    /// differently): pickups within 1e-10 of their range over 0.2 s of a hard pluck on the
    /// reference's points, the same Newton updates.
    #[test]
    fn condensed_lanes_solve_as_the_general_path() {
        let run = |general_path_only: bool| {
            let mut string = ModalString::<f64>::new(grid_mode_config(0.18e-3, 0.15e-3, true));
            assert!(string.nodal_in_use);
            if general_path_only {
                string.nodal.take_general_path_only();
            }
            string.pluck(&Pluck::default());
            let output: Vec<[f64; 2]> = (0..8820)
                .map(|_| {
                    string.step();
                    [string.nut_force_n(), string.bridge_force_n()]
                })
                .collect();
            (output, *string.newton_stats())
        };
        let (lanes, lane_stats) = run(false);
        let (general, general_stats) = run(true);
        assert_pickups_within(&lanes, &general, 1e-10);
        assert_eq!(lane_stats.iterations, general_stats.iterations);
        assert!(lane_stats.iterations > lane_stats.steps, "{lane_stats:?}");
    }

    /// A step whose evaluation finds several points crossing the contact's edge is finished by
    /// Newton on their steps alone (`NodalContact::solve_crossings`), and the finish is the
    /// solution Newton's iteration on S converges to: over a pluck and a harder one on the
    /// fine tier's points, the pickups lie within 1e-10 of their range of those of the iteration
    /// run to 1e-17 m, and the finish takes less than two thirds of the updates the iteration
    /// takes at the tier's tolerance (1e-12 m).
    #[test]
    fn several_crossings_finish_where_newtons_iteration_converges() {
        let run = |iterate: bool, tolerance_m: f64| {
            let mut string = ModalString::<f64>::new(ModalStringConfig {
                newton: NewtonSettings {
                    tolerance_m,
                    max_iterations: 30,
                },
                ..grid_mode_config(0.36e-3, 0.2e-3, true)
            });
            assert!(string.nodal_in_use);
            if iterate {
                string.nodal.iterate_over_crossings();
            }
            let mut output = Vec::new();
            for amplitude_m in [2e-3, 4e-3] {
                string.pluck(&Pluck {
                    amplitude_m,
                    ..Pluck::default()
                });
                for _ in 0..8820 {
                    string.step();
                    output.push([string.nut_force_n(), string.bridge_force_n()]);
                }
            }
            (output, *string.newton_stats())
        };
        let (finished, finished_stats) = run(false, 1e-12);
        let (converged, converged_stats) = run(true, 1e-17);
        let (_, iterated_stats) = run(true, 1e-12);
        assert_eq!(converged_stats.cap_hits, 0, "{converged_stats:?}");
        assert_eq!(finished_stats.cap_hits, 0, "{finished_stats:?}");
        assert_pickups_within(&converged, &finished, 1e-10);
        eprintln!(
            "updates per step: finished {:.3}, iterated {:.3}, converged {:.3}",
            finished_stats.mean_iterations(),
            iterated_stats.mean_iterations(),
            converged_stats.mean_iterations()
        );
        assert!(
            3 * finished_stats.iterations < 2 * iterated_stats.iterations,
            "{finished_stats:?} against {iterated_stats:?}"
        );
    }

    /// A string plucked again as before takes the last pluck's pressed state back without
    /// solving the press, and plays on exactly as if it had solved it (the same pickups to the
    /// bit over the next 2000 steps, on the nodes and on the points); a pluck pressed further,
    /// and any pluck after a retune, solves the press again.
    #[test]
    fn a_pluck_repeated_takes_the_last_pressed_state_and_plays_on_to_the_bit() {
        for condensed in [true, false] {
            let config = grid_mode_config(0.36e-3, 0.2e-3, condensed);
            let harder = Pluck {
                amplitude_m: 3e-3,
                ..Pluck::default()
            };
            let play = |remember: bool| {
                let mut string = ModalString::<f32>::new(config);
                assert_eq!(string.nodal_in_use, condensed);
                let mut output = Vec::new();
                let mut pluck_and_play = |string: &mut ModalString<f32>, pluck: &Pluck| {
                    if !remember {
                        string.last_press = None;
                    }
                    string.pluck(pluck);
                    for _ in 0..2000 {
                        string.step();
                        output.push((string.nut_force_n(), string.bridge_force_n()));
                    }
                };
                pluck_and_play(&mut string, &Pluck::default());
                pluck_and_play(&mut string, &Pluck::default());
                pluck_and_play(&mut string, &harder);
                pluck_and_play(&mut string, &harder);
                let retuned = ModalStringConfig {
                    string: StringParameters {
                        tension_n: 1.01 * config.string.tension_n,
                        ..config.string
                    },
                    ..config
                };
                assert!(string.set_config(retuned));
                pluck_and_play(&mut string, &harder);
                (output, string.press_solves)
            };
            let (remembered, remembered_solves) = play(true);
            let (solved, solved_solves) = play(false);
            assert_eq!(solved_solves, 5);
            assert_eq!(
                remembered_solves, 3,
                "the repeated plucks take the press back"
            );
            assert_eq!(remembered.len(), solved.len());
            for (step, (a, b)) in remembered.iter().zip(&solved).enumerate() {
                assert!(
                    a.0.to_bits() == b.0.to_bits() && a.1.to_bits() == b.1.to_bits(),
                    "condensed {condensed}, step {step}: {a:?} against {b:?}"
                );
            }
        }
    }

    /// On the nodes, plucks at the same place and width pressed by other amplitudes (a
    /// humanised drone's, within 10 %) take the solved press shifted along its contact set
    /// instead of solving it: the pressed state is the solve's to 1e-9 of its size, and the
    /// string plays as one that solves every press. A pluck pressed hard enough to change the
    /// contact set solves it again, on the problem the last press prepared, to the same
    /// tolerance.
    #[test]
    fn a_pluck_pressed_softer_at_the_same_place_shifts_the_solved_press() {
        let config = grid_mode_config(0.36e-3, 0.2e-3, true);
        let base = Pluck::default();
        let plucks: Vec<Pluck> = [1.0, 0.93, 0.97, 0.9, 0.95]
            .iter()
            .map(|&factor| Pluck {
                amplitude_m: factor * base.amplitude_m,
                ..base
            })
            .chain([Pluck {
                amplitude_m: 3e-3,
                ..base
            }])
            .collect();
        let play = |remember: bool| {
            let mut string = ModalString::<f32>::new(config);
            assert!(string.nodal_in_use);
            let modes = string.modes.count();
            let (mut output, mut pressed) = (Vec::new(), Vec::new());
            for pluck in &plucks {
                if !remember {
                    string.last_press = None;
                }
                string.pluck(pluck);
                pressed.push(string.row[..modes].to_vec());
                for _ in 0..2000 {
                    string.step();
                    output.push((string.nut_force_n(), string.bridge_force_n()));
                }
            }
            (output, pressed, string.press_solves)
        };
        let (shifted, shifted_presses, shifted_solves) = play(true);
        let (solved, solved_presses, solved_solves) = play(false);
        assert_eq!(solved_solves, 6);
        assert_eq!(shifted_solves, 2, "the first press and the hard one");
        for (index, (a, b)) in shifted_presses.iter().zip(&solved_presses).enumerate() {
            let size = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let largest = a
                .iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(
                size > 0.0 && largest <= 1e-9 * size,
                "pluck {index}: {largest:e} of {size:e}"
            );
        }
        let loudest = solved.iter().fold(0.0f64, |m, (nut, bridge)| {
            m.max(nut.abs()).max(bridge.abs())
        });
        for (step, (a, b)) in shifted.iter().zip(&solved).enumerate() {
            let apart = (a.0 - b.0).abs().max((a.1 - b.1).abs());
            assert!(apart <= 1e-5 * loudest, "step {step}: {a:?} against {b:?}");
        }
    }

    /// The static problems solved on the nodes (`nodal_statics.rs`) are the point-level ones
    /// (`solve.rs`) up to round-off, on the tier's spacings and the reference's, at a crest key
    /// and above it: the rest state (every point's rest force, the modal rest state), the
    /// linearised fundamental the voice tunes by, and a pluck's pressed string. f64 modes, so
    /// that the comparison is not f32's.
    #[test]
    fn the_static_problems_on_the_nodes_are_the_point_level_ones() {
        for (tension_n, bridge_m, thread_m) in [(52.0, 0.36e-3, 0.2e-3), (80.0, 0.18e-3, 0.15e-3)] {
            let build = |condensed: bool| {
                let mut config = grid_mode_config(bridge_m, thread_m, condensed);
                config.string.tension_n = tension_n;
                let string = ModalString::<f64>::new(config);
                assert_eq!(string.nodal_in_use, condensed);
                string
            };
            let (mut nodes, mut points) = (build(true), build(false));
            let count = points.points.len();
            let largest = points.points.rest_forces_n[..count]
                .iter()
                .fold(0.0f64, |m, f| m.max(*f));
            assert!(largest > 0.0);
            for i in 0..count {
                let (a, b) = (
                    nodes.points.rest_forces_n[i],
                    points.points.rest_forces_n[i],
                );
                assert!(
                    (a - b).abs() <= 1e-9 * largest,
                    "point {i}: {a} N against {b} N"
                );
            }
            let close = |a: &[f64], b: &[f64], what: &str| {
                let range = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let worst = a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0, f64::max);
                assert!(worst <= 1e-9 * range, "{what}: {worst:e} of {range:e}");
            };
            let modes = points.modes.count();
            close(
                &nodes.rest_modal[..modes],
                &points.rest_modal[..modes],
                "rest state",
            );
            let (f_nodes, f_points) = (
                nodes.linearised_fundamental_hz(),
                points.linearised_fundamental_hz(),
            );
            assert!(
                (f_nodes / f_points - 1.0).abs() <= 1e-11,
                "{f_nodes} Hz against {f_points} Hz"
            );
            nodes.pluck(&Pluck::default());
            points.pluck(&Pluck::default());
            close(
                &nodes.modal[..modes],
                &points.modal[..modes],
                "pressed string",
            );
            assert_eq!(nodes.static_solve_failures(), 0);
            assert_eq!(points.static_solve_failures(), 0);
        }
    }

    /// The linearised fundamental's inverse iteration stops once its Rayleigh quotient has
    /// settled, well before the cap, at the frequency every iteration reaches: on the nodes (the
    /// fine tier's string) and on the points, at two tensions, within 1e-13 of the frequency
    /// the full 30 iterations give.
    #[test]
    fn the_linearised_fundamental_stops_once_settled_at_the_converged_frequency() {
        for tension_n in [52.0, 80.0] {
            for condensed in [true, false] {
                let mut config = grid_mode_config(0.36e-3, 0.2e-3, condensed);
                config.string.tension_n = tension_n;
                let mut string = ModalString::<f64>::new(config);
                let settled = string.linearised_fundamental_hz();
                let settled_iterations = string.statics.fundamental_iterations;
                let every = string.linearised_fundamental_settled_hz(0.0);
                assert!(
                    (settled / every - 1.0).abs() <= 1e-13,
                    "{tension_n} N, condensed {condensed}: {settled} Hz against {every} Hz"
                );
                if condensed {
                    assert!(
                        settled_iterations <= TUNING_ITERATIONS / 2,
                        "{tension_n} N: {settled_iterations} iterations"
                    );
                    assert!(string.statics.fundamental_iterations > settled_iterations);
                }
            }
        }
    }

    /// The scalar fallback, the step a machine without AVX2 and FMA runs (the shipped binary
    /// dispatches at run time), plays the string the machine's vector unit plays, to round-off:
    /// f64 modes, so that f32's rounding does not hide a difference in the contact solve (the
    /// mode kernels' multiply-adds are fused on the vector units only). 2e-13 N apart over 0.1 s
    /// at a peak of 2.1 N on the AVX-512 machine of `docs/performance.md`.
    #[test]
    fn the_scalar_fallback_plays_the_string_the_vector_unit_plays() {
        let run = |scalar: bool| {
            let mut string = ModalString::<f64>::new(ModalStringConfig::REFERENCE);
            string.pluck(&Pluck {
                amplitude_m: 3e-3,
                ..Pluck::default()
            });
            let mut output = Vec::new();
            for _ in 0..4_410 {
                if scalar {
                    pulp::Scalar.vectorize(WholeStep {
                        string: &mut string,
                    });
                } else {
                    string.step();
                }
                output.push(string.bridge_force_n());
            }
            (output, *string.newton_stats())
        };
        let (vector, vector_stats) = run(false);
        let (scalar, scalar_stats) = run(true);
        let peak = vector
            .iter()
            .fold(0.0f64, |peak, force| peak.max(force.abs()));
        let largest = vector
            .iter()
            .zip(&scalar)
            .fold(0.0f64, |largest, (a, b)| largest.max((a - b).abs()));
        assert!(peak > 0.0 && scalar.iter().all(|force| force.is_finite()));
        assert!(largest <= 1e-10 * peak, "{largest} N apart, peak {peak} N");
        assert!(
            scalar_stats.iterations > scalar_stats.steps,
            "{scalar_stats:?}"
        );
        eprintln!("vector {vector_stats:?}, scalar {scalar_stats:?}: {largest:e} N apart");
    }
}
