//! The modes of the stiff, lossy string with the lowered support, and the coefficients of their
//! exact two-pole recursion (`docs/modal-tanpura.md`, sections 1–2).
//!
//! `y(x, t) = y_s(x) + Σ_k φ_k(x) q_k(t)`, `y_s(x) = y_TB (1 − x/L)`, `φ_k(x) = sin(β_k x)`,
//! `β_k = kπ/L`; modal stiffness `κ_k = (L/2)(T β_k² + EI β_k⁴)`, mass `m = ρA L/2`,
//! `ω_k² = κ_k/m`, decay `σ_k = γ/2 + η ω_k²/2` (seed 000, eq. 5 projected on φ_k). The code
//! works in `r_k = √κ_k q_k`, so that mode k's potential energy is `r_k²/2` and its shape at a
//! point is `Ψ_k(x) = φ_k(x)/√κ_k`.
//!
//! With the poles `z_k = e^{(−σ_k ± i ω_d,k)Δt}` of the exact recursion, the mid-point form
//! `s = a p − b r + b (Ψᵀ F)` (eq. M1) has `a = |1 + z|²/2` and `b = |1 − z|²/2`, evaluated as
//! `((1 ± e)² ∓ 4e sin²(θ/2))/2` with `e = e^{−σΔt}`, `θ = ω_d Δt`, so that the small `b` of the
//! low modes carries no cancellation. An overdamped mode (σ ≥ ω) takes its two real poles:
//! `a = (1 + z₁)(1 + z₂)/2`, `b = (1 − z₁)(1 − z₂)/2`. The discrete energy of mode k is
//! `r²/2 + (a/2b) p²` and it loses `((1 − e²)/2b) s²` per step (eq. M2).
//!
//! With [`GridModes`] (section 10) the modes are instead those of the seed's FD grid of N
//! intervals: the sampled sines `sin(kπi/N)`, k = 1 … N − 1, all kept, with `β_k²` replaced by
//! `μ_k = (4/Δx²) sin²(kπ/2N)` in κ_k and ω_k, each mode's poles moved as the FD's trapezoidal
//! rule moves them (the bilinear transform at Δt_FD: [`trapezoidal_equivalent`]; without losses
//! `(2/Δt_FD) atan(ω_k Δt_FD/2)`) in the recursion, shapes at a point by the FD's cubic
//! Lagrange interpolation of the nodes, and the nut weight the FD operator's nut force of the
//! sampled sine (zero above the output band, which the reference's decimator removes).

use crate::tanpura::fd::barrier_grid::lagrange_stencil;
use crate::tanpura::string::StringParameters;
use std::f64::consts::PI;

/// Most modes a string keeps. The stiffness bounds the count below 20 kHz at about 121 (a 20 Hz
/// string at the seed's EI and ρA); the reference's grid has 199 ([`GridModes`]); the capacity
/// is a multiple of the lane padding.
pub const MODE_CAPACITY: usize = 256;
/// Modes are kept up to this frequency (nothing above is audible) ...
pub const AUDIBLE_LIMIT_HZ: f64 = 20_000.0;
/// ... and below this fraction of the sample rate, so that no pole sits at Nyquist.
pub const NYQUIST_GUARD: f64 = 0.45;

/// The FD grid whose modes a string takes instead of the continuous string's
/// (`docs/modal-tanpura.md` §10): the seed's grid of `intervals` intervals, whose eigenvectors are
/// the sampled sines `sin(kπi/N)` (k = 1 … N − 1), and the time step of its trapezoidal rule,
/// whose frequency warp the modes take so that their partials are the FD scheme's own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridModes {
    pub intervals: usize,
    pub time_step_s: f64,
    /// Solve the contact on the grid's nodes (`nodal.rs`, section 11) instead of on the points
    /// (`step.rs`): the same scheme, the same iterates up to round-off, at the cost of the
    /// nodes the stencils reach instead of the points.
    pub condensed: bool,
}

impl GridModes {
    /// Whether the grid can be taken: at least four intervals (the cubic interpolation's
    /// stencil) and at most one more than [`MODE_CAPACITY`], a positive finite time step.
    pub fn is_valid(self) -> bool {
        (4..=MODE_CAPACITY + 1).contains(&self.intervals)
            && self.time_step_s.is_finite()
            && self.time_step_s > 0.0
    }
}

/// Everything about the modes that depends on the string and the time step, in f64.
#[derive(Debug, Clone)]
pub struct ModeSet {
    /// Every mode the step advances: the kept string modes, then the residual modes.
    count: usize,
    /// The kept string modes (sines); `kept..count` are residual modes (see
    /// [`ModeSet::set_residual_modes`]).
    kept: usize,
    length_m: f64,
    /// T, N, and EI, N m²: the static compliance of all the modes is closed-form in them.
    tension_n: f64,
    bending_stiffness_n_m2: f64,
    /// The grid whose modes these are, or `None` for the continuous string's sines.
    grid: Option<GridModes>,
    /// κ_k, N/m.
    pub stiffness: Vec<f64>,
    /// 1/√κ_k.
    pub inverse_root_stiffness: Vec<f64>,
    /// ω_k, rad/s (undamped; with grid modes the grid's own, before the time step's warp,
    /// which only the recursion coefficients take).
    pub angular_frequency: Vec<f64>,
    /// σ_k, 1/s.
    pub decay: Vec<f64>,
    /// Recursion coefficients of eq. M1.
    pub a: Vec<f64>,
    pub b: Vec<f64>,
    /// a/(2b): the kinetic energy factor of p².
    pub kinetic_factor: Vec<f64>,
    /// (1 − det)/(2b): the loss over a step per s².
    pub loss_factor: Vec<f64>,
    /// c_k: the nut force of eq. 13 per unit r_k, N per √J.
    pub nut_weight: Vec<f64>,
    /// With grid modes of N intervals, `sin(π m/N)` for m in `0..2N` ([`ModeSet::grid_sines`]),
    /// and the N they were formed for (0: none yet).
    grid_sines: Vec<f64>,
    grid_sines_intervals: usize,
}

/// Room in [`ModeSet`]'s table of the grid's sines: 2N entries for the largest grid
/// ([`GridModes::is_valid`]: N ≤ MODE_CAPACITY + 1).
const GRID_SINE_CAPACITY: usize = 2 * (MODE_CAPACITY + 1);

impl ModeSet {
    /// Room for [`MODE_CAPACITY`] modes. Allocates.
    pub fn new() -> Self {
        let zeros = || vec![0.0; MODE_CAPACITY];
        Self {
            count: 0,
            kept: 0,
            length_m: 1.0,
            tension_n: 1.0,
            bending_stiffness_n_m2: 0.0,
            grid: None,
            stiffness: zeros(),
            inverse_root_stiffness: zeros(),
            angular_frequency: zeros(),
            decay: zeros(),
            a: zeros(),
            b: zeros(),
            kinetic_factor: zeros(),
            loss_factor: zeros(),
            nut_weight: zeros(),
            grid_sines: vec![0.0; GRID_SINE_CAPACITY],
            grid_sines_intervals: 0,
        }
    }

    /// `sin(π m/N)` for m in `0..2N` on the grid of N intervals these modes were configured on,
    /// the table [`ModeSet::configure`] forms once per grid; `None` without grid modes or for
    /// another N. The sampled sine of mode k at node n is entry `k n mod 2N`: the `sin` of its
    /// reduced argument instead of the end of a recurrence over k.
    #[inline]
    pub fn grid_sines(&self, intervals: usize) -> Option<&[f64]> {
        (intervals > 0 && intervals == self.grid_sines_intervals)
            .then(|| &self.grid_sines[..2 * intervals])
    }

    /// Forms the table of [`ModeSet::grid_sines`] for N intervals (a valid grid's: 2N fits) if
    /// it is not that grid's.
    fn form_grid_sines(&mut self, intervals: usize) {
        if intervals == self.grid_sines_intervals {
            return;
        }
        for (m, sine) in self.grid_sines[..2 * intervals].iter_mut().enumerate() {
            *sine = (PI * m as f64 / intervals as f64).sin();
        }
        self.grid_sines_intervals = intervals;
    }

    /// Every mode the step advances (the kept modes and the residual modes).
    pub fn count(&self) -> usize {
        self.count
    }

    /// K, the string's modes kept (sines).
    pub fn kept(&self) -> usize {
        self.kept
    }

    /// Appends `count` residual modes after the kept ones (dropping any earlier ones), each a
    /// resonator of angular frequency `angular_frequency` with the string's loss law at that
    /// frequency (`σ = γ/2 + ηω²/2`), advanced by the same exact recursion. They have no shape
    /// along the string: their shapes at the contact points are set by
    /// [`super::points::ContactPoints::couple`], and their stiffness, shape factor and nut weight
    /// are zero, so that every sum along the string skips them. Allocation-free.
    pub fn set_residual_modes(
        &mut self,
        count: usize,
        angular_frequency: f64,
        string: &StringParameters,
        time_step_s: f64,
    ) {
        let count = count.min(MODE_CAPACITY - self.kept);
        let decay =
            0.5 * string.gamma_per_s + 0.5 * string.eta_s * angular_frequency * angular_frequency;
        let (a, b, det) = recursion_coefficients(angular_frequency, decay, time_step_s);
        for index in self.kept..MODE_CAPACITY {
            let residual = index < self.kept + count;
            let value = |v: f64| if residual { v } else { 0.0 };
            self.stiffness[index] = 0.0;
            self.inverse_root_stiffness[index] = 0.0;
            self.angular_frequency[index] = value(angular_frequency);
            self.decay[index] = value(decay);
            self.a[index] = value(a);
            self.b[index] = value(b);
            self.kinetic_factor[index] = value(a / (2.0 * b));
            self.loss_factor[index] = value((1.0 - det) / (2.0 * b));
            self.nut_weight[index] = 0.0;
        }
        self.count = self.kept + count;
    }

    /// The highest frequency a kept mode may have at this sample rate, Hz.
    pub fn frequency_limit_hz(sample_rate_hz: f64, highest_mode_hz: f64) -> f64 {
        highest_mode_hz.min(NYQUIST_GUARD * sample_rate_hz)
    }

    /// Computes the modes of `string` below `highest_mode_hz` (and below 0.45 of the sample rate)
    /// and their recursion coefficients for the step `time_step_s`; with `grid` (valid), every
    /// mode of that FD grid instead, whatever its frequency (§10). Allocation-free.
    pub fn configure(
        &mut self,
        string: &StringParameters,
        time_step_s: f64,
        highest_mode_hz: f64,
        grid: Option<GridModes>,
    ) {
        let length = string.length_m;
        let limit_hz = Self::frequency_limit_hz(1.0 / time_step_s, highest_mode_hz);
        let half_length = 0.5 * length;
        let mass = string.linear_density_kg_m * half_length;
        let grid = grid.filter(|grid| grid.is_valid());
        if let Some(GridModes { intervals, .. }) = grid {
            self.form_grid_sines(intervals);
        }
        self.length_m = length;
        self.tension_n = string.tension_n;
        self.bending_stiffness_n_m2 = string.bending_stiffness_n_m2;
        self.grid = grid;
        self.count = 0;
        for index in 0..MODE_CAPACITY {
            let number = (index + 1) as f64;
            // The operator's eigenvalue per unit tension, μ_k (the continuous string's β_k², the
            // grid's (4/Δx²) sin²(kπ/2N)), and the nut force per unit q_k.
            let (k2, nut_force) = match grid {
                Some(GridModes { intervals, .. }) => {
                    if index + 1 >= intervals {
                        break;
                    }
                    let spacing = length / intervals as f64;
                    let half_angle = number * PI / (2.0 * intervals as f64);
                    let k2 = (2.0 * half_angle.sin() / spacing).powi(2);
                    // The FD operator's nut force (`fd::operator::StringOperator::nut_force_n`)
                    // of the sampled sine, whose nodes N − 1 and N − 2 are these.
                    // The table is this grid's (formed above).
                    let node = |i: usize| self.grid_sines[(index + 1) * i % (2 * intervals)];
                    let last = node(intervals - 1);
                    let curvature = (node(intervals - 2) - 2.0 * last) / (spacing * spacing);
                    let nut_force = -string.bending_stiffness_n_m2 * curvature / spacing
                        + string.tension_n * last / spacing;
                    (k2, nut_force)
                }
                None => {
                    let wavenumber = number * PI / length;
                    let k2 = wavenumber * wavenumber;
                    let sign = if index % 2 == 0 { 1.0 } else { -1.0 }; // −(−1)^k, k = index + 1
                    let nut_force = sign
                        * (string.tension_n * wavenumber
                            + string.bending_stiffness_n_m2 * wavenumber * k2);
                    (k2, nut_force)
                }
            };
            let stiffness =
                half_length * (string.tension_n * k2 + string.bending_stiffness_n_m2 * k2 * k2);
            let omega = (stiffness / mass).sqrt();
            // NaN (a degenerate string) stops the count like a mode above the limit.
            let below_limit = omega / (2.0 * PI) < limit_hz;
            if !below_limit && index > 0 && grid.is_none() {
                break;
            }
            let decay = 0.5 * string.gamma_per_s + 0.5 * string.eta_s * omega * omega;
            // The grid's trapezoidal rule moves each mode's poles (`trapezoidal_equivalent`).
            let (heard_omega, heard_decay) = match grid {
                Some(GridModes { time_step_s, .. }) => {
                    trapezoidal_equivalent(omega, decay, time_step_s)
                }
                None => (omega, decay),
            };
            let (a, b, det) = recursion_coefficients(heard_omega, heard_decay, time_step_s);
            let root = stiffness.sqrt();
            self.stiffness[index] = stiffness;
            self.inverse_root_stiffness[index] = 1.0 / root;
            self.angular_frequency[index] = omega;
            self.decay[index] = decay;
            self.a[index] = a;
            self.b[index] = b;
            self.kinetic_factor[index] = a / (2.0 * b);
            self.loss_factor[index] = (1.0 - det) / (2.0 * b);
            // Grid modes above the output band still move the string (the contact, the static
            // problems) but are not heard at the nut, as the reference's decimator removes them;
            // sounded, they would alias into the top octave.
            self.nut_weight[index] = if grid.is_none() || heard_omega / (2.0 * PI) < limit_hz {
                nut_force / root
            } else {
                0.0
            };
            self.count = index + 1;
        }
        self.kept = self.count;
        for index in self.count..MODE_CAPACITY {
            self.stiffness[index] = 0.0;
            self.inverse_root_stiffness[index] = 0.0;
            self.angular_frequency[index] = 0.0;
            self.decay[index] = 0.0;
            self.a[index] = 0.0;
            self.b[index] = 0.0;
            self.kinetic_factor[index] = 0.0;
            self.loss_factor[index] = 0.0;
            self.nut_weight[index] = 0.0;
        }
    }

    /// Writes `Ψ_k(x) = sin(kπx/L)/√κ_k` for every kept mode into `row` (zeros beyond K, the
    /// residual modes included), by the recurrence `sin((k+1)θ) = 2 cos θ sin(kθ) −
    /// sin((k−1)θ)`; with grid modes, the FD's cubic Lagrange interpolation of the sampled sines
    /// at x (`fd::barrier_grid::lagrange_stencil`, eq. 17 of the seed), over √κ_k.
    /// Allocation-free.
    pub fn shape_row(&self, x_m: f64, row: &mut [f64]) {
        row.fill(0.0);
        self.for_each_shape(x_m, |index, shape| {
            if let Some(value) = row.get_mut(index) {
                *value = shape;
            }
        });
    }

    /// `Σ_k Ψ_k(x) c_k` over the kept modes for the coefficients `coefficient(k)`, m: the
    /// displacement at x of the modal state `c` (the shapes of [`ModeSet::shape_row`]).
    /// Allocation-free.
    pub fn shape_sum(&self, x_m: f64, coefficient: impl Fn(usize) -> f64) -> f64 {
        let mut sum = 0.0;
        self.for_each_shape(x_m, |index, shape| sum += shape * coefficient(index));
        sum
    }

    /// Calls `visit(k, Ψ_k(x))` for every kept mode, in order.
    fn for_each_shape(&self, x_m: f64, mut visit: impl FnMut(usize, f64)) {
        if let Some(GridModes { intervals, .. }) = self.grid {
            let (first, weights) =
                lagrange_stencil(x_m * intervals as f64 / self.length_m, intervals);
            // The sampled sines of the stencil's four nodes, sin(kθ_j), θ_j = π n_j/N, by the
            // same recurrence over k (four sines and cosines per point, not four per mode: a
            // retune shapes about a hundred points over 199 modes).
            let thetas: [f64; 4] =
                std::array::from_fn(|j| PI * (first + j) as f64 / intervals as f64);
            let twice_cos = thetas.map(|theta| 2.0 * theta.cos());
            let mut previous = [0.0; 4];
            let mut current = thetas.map(f64::sin);
            for index in 0..self.kept {
                let interpolated: f64 = weights.iter().zip(&current).map(|(w, s)| w * s).sum();
                visit(index, interpolated * self.inverse_root_stiffness[index]);
                for j in 0..4 {
                    let next = twice_cos[j] * current[j] - previous[j];
                    previous[j] = current[j];
                    current[j] = next;
                }
            }
            return;
        }
        let theta = PI * x_m / self.length_m;
        let twice_cos = 2.0 * theta.cos();
        let (mut previous, mut current) = (0.0, theta.sin());
        for index in 0..self.kept {
            visit(index, current * self.inverse_root_stiffness[index]);
            let next = twice_cos * current - previous;
            previous = current;
            current = next;
        }
    }
}

impl ModeSet {
    /// The static compliance of the whole string (every mode, not only the kept ones) between
    /// two points, m/N: `C(x, ξ) = Σ_k φ_k(x) φ_k(ξ)/κ_k`, the deflection at x under a unit
    /// force at ξ, in closed form. For x ≤ ξ, with λ² = T/EI (partial fractions of
    /// `1/(Tβ² + EIβ⁴)`):
    ///
    /// `C = [x (L − ξ)/L − sinh(λx) sinh(λ(L − ξ))/(λ sinh λL)] / T`,
    ///
    /// the second term written with decaying exponentials only,
    /// `e^{−λ(ξ − x)} (1 − e^{−2λx})(1 − e^{−2λ(L − ξ)}) / (2λ (1 − e^{−2λL}))`, so that it
    /// neither overflows nor cancels for the stiff strings' large λL. Without stiffness it is the
    /// taut string's `x (L − ξ)/(L T)`.
    pub fn static_compliance_m_n(&self, x_m: f64, xi_m: f64) -> f64 {
        let (low, high) = if x_m <= xi_m {
            (x_m, xi_m)
        } else {
            (xi_m, x_m)
        };
        let length = self.length_m;
        let taut = low * (length - high) / length;
        let bending = if self.bending_stiffness_n_m2 > 0.0 {
            let lambda = (self.tension_n / self.bending_stiffness_n_m2).sqrt();
            let left = -(-2.0 * lambda * low).exp_m1();
            let right = -(-2.0 * lambda * (length - high)).exp_m1();
            let whole = -(-2.0 * lambda * length).exp_m1();
            (-lambda * (high - low)).exp() * left * right / (2.0 * lambda * whole)
        } else {
            0.0
        };
        (taut - bending) / self.tension_n
    }

    /// The truncated modes' part of the static compliance between two points, m/N: `C(x, ξ)`
    /// minus the kept modes' `Σ_{k ≤ K} Ψ_k(x) Ψ_k(ξ)`, given the points' shape rows.
    pub fn residual_compliance_m_n(
        &self,
        x_m: f64,
        xi_m: f64,
        row_x: &[f64],
        row_xi: &[f64],
    ) -> f64 {
        let kept: f64 = row_x[..self.count]
            .iter()
            .zip(&row_xi[..self.count])
            .map(|(a, b)| a * b)
            .sum();
        self.static_compliance_m_n(x_m, xi_m) - kept
    }
}

impl Default for ModeSet {
    fn default() -> Self {
        Self::new()
    }
}

/// The `(ω, σ)` whose exactly sampled oscillator has the poles the FD scheme's trapezoidal rule
/// at step `h` gives `q̈ + 2σq̇ + ω²q = 0`: its step is the bilinear transform of the continuous
/// poles, `z = (1 + s h/2)/(1 − s h/2)` (the FD's step matrix `(1 + γh/2) I + (1 + 2η/h) D` per
/// mode, `fd/operator.rs`), and `s' = ln z / h`. Without losses `ω' = (2/h) atan(ωh/2)`, the
/// dispersion `tanpura_invariants.rs` holds the FD string to. An overdamped pair whose transform
/// leaves the positive axis (σ beyond 2/h) keeps its continuous poles.
pub fn trapezoidal_equivalent(omega: f64, decay: f64, h: f64) -> (f64, f64) {
    let half = 0.5 * h;
    if decay < omega {
        let damped = (omega * omega - decay * decay).sqrt();
        let magnitude_squared = ((1.0 - decay * half).powi(2) + (damped * half).powi(2))
            / ((1.0 + decay * half).powi(2) + (damped * half).powi(2));
        let angle =
            (damped * half).atan2(1.0 - decay * half) + (damped * half).atan2(1.0 + decay * half);
        let heard_decay = -0.5 * magnitude_squared.ln() / h;
        let heard_damped = angle / h;
        (heard_damped.hypot(heard_decay), heard_decay)
    } else {
        let spread = (decay * decay - omega * omega).sqrt();
        let transformed = |s: f64| (1.0 + s * half) / (1.0 - s * half);
        let (slow, fast) = (transformed(-decay + spread), transformed(-decay - spread));
        if slow <= 0.0 || fast <= 0.0 {
            return (omega, decay);
        }
        let (slow, fast) = (slow.ln() / h, fast.ln() / h);
        ((slow * fast).sqrt(), -0.5 * (slow + fast))
    }
}

/// `(a, b, det)` of the recursion whose poles are those of `q̈ + 2σq̇ + ω²q = 0` sampled at Δt.
pub fn recursion_coefficients(omega: f64, decay: f64, time_step_s: f64) -> (f64, f64, f64) {
    if decay < omega {
        let damped = (omega * omega - decay * decay).sqrt();
        let e = (-decay * time_step_s).exp();
        let one_minus_e = -(-decay * time_step_s).exp_m1();
        let half_angle_sine = (0.5 * damped * time_step_s).sin();
        let cross = 4.0 * e * half_angle_sine * half_angle_sine;
        let a = 0.5 * ((1.0 + e) * (1.0 + e) - cross);
        let b = 0.5 * (one_minus_e * one_minus_e + cross);
        (a, b, e * e)
    } else {
        let spread = (decay * decay - omega * omega).sqrt();
        let slow = ((-decay + spread) * time_step_s).exp();
        let fast = ((-decay - spread) * time_step_s).exp();
        let a = 0.5 * (1.0 + slow) * (1.0 + fast);
        let b = 0.5 * (1.0 - slow) * (1.0 - fast);
        (a, b, slow * fast)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One mode stepped by eq. M1: returns (r, p) after `steps` steps.
    fn free_run(a: f64, b: f64, mut r: f64, mut p: f64, steps: usize) -> (f64, f64) {
        for _ in 0..steps {
            let s = a * p - b * r;
            r += s;
            p = s - p;
        }
        (r, p)
    }

    #[test]
    fn recursion_has_the_exact_poles() {
        let dt = 1.0 / 44_100.0;
        for &(omega, decay) in &[(2.0 * PI * 189.0, 0.3), (2.0 * PI * 15_000.0, 400.0)] {
            let (a, b, det) = recursion_coefficients(omega, decay, dt);
            // trace a − b and determinant a + b − 1 of the update matrix.
            let damped = (omega * omega - decay * decay).sqrt();
            let trace = 2.0 * (-decay * dt).exp() * (damped * dt).cos();
            assert!((a - b - trace).abs() < 1e-14);
            assert!((a + b - 1.0 - det).abs() < 1e-14);
            assert!((det - (-2.0 * decay * dt).exp()).abs() < 1e-15);
        }
    }

    #[test]
    fn a_mode_released_from_rest_follows_the_exact_damped_cosine() {
        let dt = 1.0 / 44_100.0;
        let (omega, decay) = (2.0 * PI * 440.0, 2.5);
        let (a, b, _) = recursion_coefficients(omega, decay, dt);
        let steps = 1000;
        let (r, _) = free_run(a, b, 1.0, 0.0, steps);
        // The lossless case is exact for q(0) = 1, p = 0; with losses the mid-point velocity
        // differs from the sampled one by O(σΔt), so compare the envelope and phase closely.
        let t = steps as f64 * dt;
        let damped = (omega * omega - decay * decay).sqrt();
        let exact = (-decay * t).exp() * ((damped * t).cos() + decay / damped * (damped * t).sin());
        assert!((r - exact).abs() < 1e-4, "{r} vs {exact}");
        let (a0, b0, _) = recursion_coefficients(omega, 0.0, dt);
        let (lossless, _) = free_run(a0, b0, 1.0, 0.0, steps);
        assert!((lossless - (omega * t).cos()).abs() < 1e-10);
    }

    #[test]
    fn mode_energy_balance_is_exact() {
        // eq. M2 for random states and forces: E' − E = s F − loss s².
        let (a, b, det) = recursion_coefficients(2.0 * PI * 3000.0, 40.0, 1.0 / 48_000.0);
        for &(r, p, force) in &[(0.3, -0.2, 0.0), (-1.0, 0.7, 0.4), (2e-3, 1e-3, -5e-4)] {
            let s = a * p - b * r + b * force;
            let energy = |r: f64, p: f64| 0.5 * r * r + a / (2.0 * b) * p * p;
            let change = energy(r + s, s - p) - energy(r, p);
            let expected = s * force - (1.0 - det) / (2.0 * b) * s * s;
            assert!((change - expected).abs() < 1e-13, "{change} vs {expected}");
        }
    }

    #[test]
    fn the_static_response_is_exact() {
        // A constant force F settles the mode at r = F (q = Ψ F / √κ, the static deflection).
        let (a, b, _) = recursion_coefficients(2.0 * PI * 500.0, 30.0, 1.0 / 44_100.0);
        let force = 0.25;
        let (mut r, mut p) = (0.0, 0.0);
        for _ in 0..200_000 {
            let s = a * p - b * r + b * force;
            r += s;
            p = s - p;
        }
        assert!((r - force).abs() < 1e-12);
    }

    /// The equivalent oscillator sampled at h has the trapezoidal rule's poles, the bilinear
    /// transform of the continuous ones (checked on the characteristic polynomial of the FD's
    /// per-mode step: `(1 + σh + ω²h²/4) z² − (2 − ω²h²/2) z + (1 − σh + ω²h²/4)`).
    #[test]
    fn the_trapezoidal_equivalent_has_the_fd_steps_poles() {
        let h = 1.0 / 176_400.0;
        for (omega, decay) in [
            (2.0 * PI * 191.0, 0.3),
            (2.0 * PI * 9_000.0, 2_000.0),
            (2.0 * PI * 31_000.0, 30_000.0),
            (1_000.0, 5_000.0),
        ] {
            let (heard_omega, heard_decay) = trapezoidal_equivalent(omega, decay, h);
            // The sampled equivalent's poles: z = e^{s'h}, s' = −σ' ± √(σ'² − ω'²).
            let (sum, product) = if heard_decay < heard_omega {
                let damped = (heard_omega.powi(2) - heard_decay.powi(2)).sqrt();
                let e = (-heard_decay * h).exp();
                (2.0 * e * (damped * h).cos(), e * e)
            } else {
                let spread = (heard_decay.powi(2) - heard_omega.powi(2)).sqrt();
                let (slow, fast) = (
                    ((-heard_decay + spread) * h).exp(),
                    ((-heard_decay - spread) * h).exp(),
                );
                (slow + fast, slow * fast)
            };
            let w = omega * omega * h * h / 4.0;
            let lead = 1.0 + decay * h + w;
            let expected_sum = (2.0 - 2.0 * w) / lead;
            let expected_product = (1.0 - decay * h + w) / lead;
            assert!(
                (sum - expected_sum).abs() < 1e-12 && (product - expected_product).abs() < 1e-12,
                "ω {omega}, σ {decay}: {sum} {product} against {expected_sum} {expected_product}"
            );
        }
        // Without losses, the FD's dispersion (2/h) atan(ωh/2).
        let (heard, decay) = trapezoidal_equivalent(1e5, 0.0, h);
        assert!((heard - 2.0 / h * (0.5e5 * h).atan()).abs() < 1e-9 * heard && decay == 0.0);
    }

    #[test]
    fn overdamped_modes_decay_without_oscillating() {
        let (a, b, det) = recursion_coefficients(100.0, 1e5, 1e-5);
        assert!(a > 0.0 && b > 0.0 && det < 1.0);
        let (mut r, mut p) = (1.0, 0.0);
        let mut previous = r;
        for _ in 0..1000 {
            let s = a * p - b * r;
            r += s;
            p = s - p;
            assert!(r <= previous + 1e-15 && r >= 0.0);
            previous = r;
        }
    }

    #[test]
    fn the_seed_string_keeps_the_modes_below_20_khz_and_below_nyquist() {
        let mut modes = ModeSet::new();
        modes.configure(
            &StringParameters::SEED,
            1.0 / 44_100.0,
            AUDIBLE_LIMIT_HZ,
            None,
        );
        let count = modes.count();
        let top = modes.angular_frequency[count - 1] / (2.0 * PI);
        assert!(top < NYQUIST_GUARD * 44_100.0, "{top}");
        // The next mode would lie above the limit.
        let next = (count + 1) as f64 * PI / 0.668;
        let p = StringParameters::SEED;
        let next_hz = ((p.tension_n * next * next + p.bending_stiffness_n_m2 * next.powi(4))
            / p.linear_density_kg_m)
            .sqrt()
            / (2.0 * PI);
        assert!(next_hz >= NYQUIST_GUARD * 44_100.0, "{next_hz}");
        // Mode 1: the full string's fundamental with its stiffness correction.
        let f1 = modes.angular_frequency[0] / (2.0 * PI);
        let ideal = p.wave_speed_m_s() / (2.0 * 0.668);
        let b_coeff = PI * PI * p.bending_stiffness_n_m2 / (p.tension_n * 0.668 * 0.668);
        assert!((f1 - ideal * (1.0 + b_coeff).sqrt()).abs() < 1e-9);
        assert!(count > 90 && count < 120, "{count}");
    }

    /// `Σ_k φ_k(x) φ_k(ξ)/κ_k` summed over `terms` modes.
    fn compliance_series(string: &StringParameters, x: f64, xi: f64, terms: usize) -> f64 {
        let length = string.length_m;
        (1..=terms)
            .map(|k| {
                let beta = k as f64 * PI / length;
                let kappa = 0.5
                    * length
                    * (string.tension_n * beta * beta
                        + string.bending_stiffness_n_m2 * beta.powi(4));
                (beta * x).sin() * (beta * xi).sin() / kappa
            })
            .sum()
    }

    #[test]
    fn the_closed_form_static_compliance_is_the_sum_over_all_modes() {
        // The series converges like 1/k² (taut) or faster; two million terms leave < 1e-6.
        let mut taut = StringParameters::SEED;
        taut.bending_stiffness_n_m2 = 0.0;
        for string in [StringParameters::SEED, taut] {
            let mut modes = ModeSet::new();
            modes.configure(&string, 1.0 / 44_100.0, AUDIBLE_LIMIT_HZ, None);
            for &(x, xi) in &[(0.040, 0.0465), (0.0465, 0.040), (0.3, 0.3), (0.01, 0.6)] {
                let closed = modes.static_compliance_m_n(x, xi);
                let series = compliance_series(&string, x, xi, 2_000_000);
                assert!(
                    (closed - series).abs() < 1e-6 * closed.abs(),
                    "x {x}, ξ {xi}: {closed:e} vs {series:e}"
                );
            }
        }
    }

    #[test]
    fn the_residual_compliance_is_the_truncated_modes_part() {
        let mut modes = ModeSet::new();
        modes.configure(
            &StringParameters::SEED,
            1.0 / 44_100.0,
            AUDIBLE_LIMIT_HZ,
            None,
        );
        let (x, xi) = (0.040, 0.0465);
        let (mut row_x, mut row_xi) = (vec![0.0; MODE_CAPACITY], vec![0.0; MODE_CAPACITY]);
        modes.shape_row(x, &mut row_x);
        modes.shape_row(xi, &mut row_xi);
        let residual = modes.residual_compliance_m_n(x, xi, &row_x, &row_xi);
        let count = modes.count();
        let tail = compliance_series(&StringParameters::SEED, x, xi, 2_000_000)
            - compliance_series(&StringParameters::SEED, x, xi, count);
        assert!(
            (residual - tail).abs() < 1e-3 * tail.abs(),
            "{residual:e} vs {tail:e}"
        );
        // At one point it is a variance: positive.
        let own = modes.residual_compliance_m_n(x, x, &row_x, &row_x);
        assert!(own > 0.0);
    }

    #[test]
    fn shape_rows_are_the_scaled_sines() {
        let mut modes = ModeSet::new();
        modes.configure(
            &StringParameters::SEED,
            1.0 / 44_100.0,
            AUDIBLE_LIMIT_HZ,
            None,
        );
        let mut row = vec![0.0; MODE_CAPACITY];
        modes.shape_row(0.0465, &mut row);
        for k in 0..modes.count() {
            let direct =
                ((k + 1) as f64 * PI * 0.0465 / 0.668).sin() * modes.inverse_root_stiffness[k];
            assert!((row[k] - direct).abs() < 1e-12 * modes.inverse_root_stiffness[k]);
        }
        assert!(row[modes.count()..].iter().all(|&v| v == 0.0));
    }
}
