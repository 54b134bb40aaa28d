//! [`BowedString`]: the rounded-corner bowed string of McIntyre, Schumacher and Woodhouse
//! (`shared/notes/bowed-model.md`; Woodhouse 1993, section 3.1).
//!
//! Per sample (the note's equations, in this order):
//!
//! ```text
//!     i_b = Σ r_b(k) o_b(n − k)          incoming from the bridge side   (reflection.rs)
//!     i_n = Σ r_n(k) o_n(n − k)          incoming from the nut/finger side
//!     v_h = i_b + i_n                    what the string would do without the bow
//!     (v, f) = line ∩ friction curve     f = 2Z₀ (v − v_h), with hysteresis (bow_point.rs)
//!     o_b = i_n + f/(2Z₀),  o_n = i_b + f/(2Z₀)
//! ```
//!
//! Outputs: v (the bow-point velocity) and the bridge force. The force of the string on a rigid
//! bridge is Z₀ (v_incident − v_reflected) (a velocity wave v travelling towards the bridge
//! carries slope v/c, so force T v/c = Z₀ v; the reflected wave carries the opposite sign). The
//! wave that arrives at the bridge halfway through the bridge-side round trip is o_b(n − D_b)
//! (read half a round trip late) and the wave it sends back reaches the bow as i_b(n), so
//!
//! ```text
//!     F_bridge = Z₀ (o_b(n − D_b) − i_b(n))
//! ```
//!
//! which is the bridge force delayed by D_b/2: a constant latency of βP/2 (P the period), which
//! does not matter for listening and keeps the model causal.
//!
//! Physical constants: Z₀ = √(T m) from tension T and linear density m; the wave speed
//! c = √(T/m); the finger sets the vibrating length L = c/(2 f₀) for the pitch f₀, so the bow
//! sits βL from the bridge and the round-trip delays are D_b = 2βL/c = β/f₀ and
//! D_n = 2(1 − β)L/c = (1 − β)/f₀.
//!
//! Schelleng's bounds for the current controls (the note; Schelleng 1973):
//!
//! ```text
//!     F_max = 2 Z₀ v_b / (β (μ_s − μ_d))
//!     F_min = Z₀² v_b / (2 R β² (μ_s − μ_d)),   R = Z₀ (1 + A_b)/(1 − A_b)
//! ```
//!
//! where R is the resistance of a dashpot bridge whose reflection coefficient −(R − Z₀)/(R + Z₀)
//! equals the bridge pulse's −A_b.

use super::body::{BodyFilter, BodyResonance, BodyRun, VIOLIN_BODY};
use super::bow_point::{BowPoint, BowPointSolution, ContactState};
use super::friction::{FrictionLaw, HyperbolicFriction};
use super::reflection::{ReflectionCursor, ReflectionFunction, ReflectionPulse};
use super::{BowedCapacity, BowedConfigError, BowedOutput, BowedVoice, MIN_SAMPLE_RATE_HZ};

/// Widest reflection pulse a voice can be given, s.
pub const MAX_PULSE_WIDTH_S: f64 = 1e-3;

/// Smallest and largest bow position accepted by [`BowedString::set_bow_position`].
pub const BOW_POSITION_RANGE: (f64, f64) = (0.001, 0.999);

/// Whether every value is finite, in one test: x · 0 is ±0 for finite x and NaN for ±∞ or NaN,
/// so the sum of the products is zero exactly when all are finite.
#[inline(always)]
pub(crate) fn all_finite<const N: usize>(values: [f64; N]) -> bool {
    let mut probe = 0.0;
    for value in values {
        probe += value * 0.0;
    }
    probe == 0.0
}

/// The bow-point solution of a voice at rest: stuck, no force.
const RESTING_SOLUTION: BowPointSolution = BowPointSolution {
    velocity_m_s: 0.0,
    friction_force_n: 0.0,
    state: ContactState::Sticking,
    intersections: 1,
};

/// The string's physical constants and its two reflection functions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StringConstants {
    /// Tension T, N (> 0).
    pub tension_n: f64,
    /// Linear density m, kg/m (> 0).
    pub linear_density_kg_m: f64,
    /// Bridge-side reflection pulse (the bridge is stiff: narrow, nearly lossless).
    pub bridge_pulse: ReflectionPulse,
    /// Nut/finger-side reflection pulse (a finger is soft: wider and lossier).
    pub nut_pulse: ReflectionPulse,
}

impl StringConstants {
    /// A violin A string (440 Hz open, 328 mm): T = 50 N, m = 0.6 g/m, so c = 289 m/s and
    /// Z₀ = √(T m) = 0.173 N s/m. Pulses: bridge 40 µs wide, area 0.98; finger 80 µs,
    /// area 0.96.
    pub fn violin_a() -> Self {
        Self {
            tension_n: 50.0,
            linear_density_kg_m: 0.6e-3,
            bridge_pulse: ReflectionPulse {
                width_s: 40e-6,
                area: 0.98,
            },
            nut_pulse: ReflectionPulse {
                width_s: 80e-6,
                area: 0.96,
            },
        }
    }

    /// A cello D string (146.8 Hz open, 690 mm): T = 150 N, m = 3.65 g/m, c = 203 m/s,
    /// Z₀ = 0.740 N s/m. Pulses: bridge 80 µs, area 0.98; finger 160 µs, area 0.96.
    pub fn cello_d() -> Self {
        Self {
            tension_n: 150.0,
            linear_density_kg_m: 3.65e-3,
            bridge_pulse: ReflectionPulse {
                width_s: 80e-6,
                area: 0.98,
            },
            nut_pulse: ReflectionPulse {
                width_s: 160e-6,
                area: 0.96,
            },
        }
    }

    /// Wave impedance Z₀ = √(T m), N s/m.
    pub fn wave_impedance_n_s_m(&self) -> f64 {
        (self.tension_n * self.linear_density_kg_m).sqrt()
    }

    /// Transverse wave speed c = √(T/m), m/s.
    pub fn wave_speed_m_s(&self) -> f64 {
        (self.tension_n / self.linear_density_kg_m).sqrt()
    }
}

impl Default for StringConstants {
    fn default() -> Self {
        Self::violin_a()
    }
}

/// The rounded-corner bowed string, generic over its friction law.
#[derive(Clone, Debug)]
pub struct BowedString<F: FrictionLaw = HyperbolicFriction> {
    capacity: BowedCapacity,
    constants: StringConstants,
    friction: F,
    sample_rate_hz: f64,
    wave_impedance_n_s_m: f64,
    bridge: ReflectionFunction,
    nut: ReflectionFunction,
    bow: BowPoint,
    body: BodyFilter,
    body_enabled: bool,
    pitch_hz: f64,
    bow_force_n: f64,
    bow_velocity_m_s: f64,
    bow_position: f64,
    last_solution: BowPointSolution,
    /// The per-sample values of a run of `process` ([`RoundedRun::render_run`]).
    run_scratch: RunScratch,
}

impl BowedString<HyperbolicFriction> {
    /// Allocate for `capacity`, with the hyperbolic friction law of the note. Starts prepared at
    /// 48 kHz (or the capacity's rate if lower), 440 Hz, β = 0.1, bow lifted, body filter on
    /// with [`VIOLIN_BODY`].
    pub fn new(capacity: BowedCapacity, constants: StringConstants) -> Self {
        Self::with_friction(capacity, constants, HyperbolicFriction::default())
    }
}

impl<F: FrictionLaw> BowedString<F> {
    /// Allocate for `capacity` with any friction law.
    pub fn with_friction(capacity: BowedCapacity, constants: StringConstants, friction: F) -> Self {
        let max_rate = capacity.max_sample_rate_hz.max(MIN_SAMPLE_RATE_HZ);
        let lowest_pitch = capacity.lowest_pitch_hz.max(1.0);
        let capacity = BowedCapacity {
            max_sample_rate_hz: max_rate,
            lowest_pitch_hz: lowest_pitch,
        };
        let max_delay = max_rate / lowest_pitch;
        let max_width = MAX_PULSE_WIDTH_S * max_rate;
        let sample_rate_hz = 48_000.0_f64.min(max_rate);
        let mut voice = Self {
            capacity,
            constants,
            friction,
            sample_rate_hz,
            wave_impedance_n_s_m: constants.wave_impedance_n_s_m(),
            bridge: ReflectionFunction::new(max_delay, max_width),
            nut: ReflectionFunction::new(max_delay, max_width),
            bow: BowPoint::new(),
            body: BodyFilter::new(&VIOLIN_BODY, sample_rate_hz),
            body_enabled: true,
            pitch_hz: 440.0,
            bow_force_n: 0.0,
            bow_velocity_m_s: 0.0,
            bow_position: 0.1,
            last_solution: RESTING_SOLUTION,
            run_scratch: RunScratch::default(),
        };
        voice.update_reflections();
        voice
    }

    /// Replace the string constants (tension, density, pulses). Allocation-free.
    pub fn set_constants(&mut self, constants: StringConstants) {
        let valid = constants.tension_n > 0.0
            && constants.linear_density_kg_m > 0.0
            && constants.wave_impedance_n_s_m().is_finite();
        if valid {
            self.constants = constants;
            self.wave_impedance_n_s_m = constants.wave_impedance_n_s_m();
            self.update_reflections();
        }
    }

    /// Replace the body resonances (at most 8). Allocation-free.
    pub fn set_body_resonances(&mut self, resonances: &[BodyResonance]) {
        self.body.set_resonances(resonances);
    }

    /// The friction law.
    pub fn friction(&self) -> &F {
        &self.friction
    }

    /// The string constants in use.
    pub fn constants(&self) -> &StringConstants {
        &self.constants
    }

    /// Z₀ = √(T m), N s/m.
    pub fn wave_impedance_n_s_m(&self) -> f64 {
        self.wave_impedance_n_s_m
    }

    /// Sample rate set by `prepare`, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// Pitch in use after clamping, Hz.
    pub fn pitch_hz(&self) -> f64 {
        self.pitch_hz
    }

    /// Bow position in use after clamping.
    pub fn bow_position(&self) -> f64 {
        self.bow_position
    }

    /// The bridge-side reflection function (for inspection and for setting explicit taps).
    pub fn bridge_reflection(&self) -> &ReflectionFunction {
        &self.bridge
    }

    /// Mutable access to the bridge-side reflection function, e.g. for Woodhouse's [σ, λ, σ].
    /// The next change of pitch, position, constants or sample rate recomputes the pulse.
    pub fn bridge_reflection_mut(&mut self) -> &mut ReflectionFunction {
        &mut self.bridge
    }

    /// The nut/finger-side reflection function.
    pub fn nut_reflection(&self) -> &ReflectionFunction {
        &self.nut
    }

    /// Mutable access to the nut/finger-side reflection function.
    pub fn nut_reflection_mut(&mut self) -> &mut ReflectionFunction {
        &mut self.nut
    }

    /// The bow-point solution of the last sample (contact state, friction force).
    pub fn last_bow_point(&self) -> BowPointSolution {
        self.last_solution
    }

    /// Schelleng's maximum bow force for the current controls, N.
    pub fn schelleng_max_force_n(&self) -> f64 {
        let fall = self.friction.static_coefficient() - self.friction.dynamic_coefficient();
        2.0 * self.wave_impedance_n_s_m * self.bow_velocity_m_s.abs() / (self.bow_position * fall)
    }

    /// Schelleng's minimum bow force for the current controls, N, with the bridge taken as a
    /// dashpot of resistance R = Z₀ (1 + A_b)/(1 − A_b).
    pub fn schelleng_min_force_n(&self) -> f64 {
        let fall = self.friction.static_coefficient() - self.friction.dynamic_coefficient();
        let area = self.constants.bridge_pulse.area;
        let z0 = self.wave_impedance_n_s_m;
        let resistance = z0 * (1.0 + area) / (1.0 - area);
        z0 * z0 * self.bow_velocity_m_s.abs()
            / (2.0 * resistance * self.bow_position * self.bow_position * fall)
    }

    /// `pitch_hz` clamped to [lowest pitch of the capacity, sample rate / 4].
    fn clamped_pitch_hz(&self, pitch_hz: f64) -> f64 {
        // min/max, not clamp: a capacity whose lowest pitch exceeds f_s/4 must not panic.
        pitch_hz
            .min(0.25 * self.sample_rate_hz)
            .max(self.capacity.lowest_pitch_hz)
    }

    fn update_reflections(&mut self) {
        let period_samples = self.sample_rate_hz / self.pitch_hz;
        let bridge_delay = self.bow_position * period_samples;
        let nut_delay = (1.0 - self.bow_position) * period_samples;
        let bridge = self.constants.bridge_pulse;
        let nut = self.constants.nut_pulse;
        self.bridge.set_pulse(
            bridge_delay,
            bridge.width_s * self.sample_rate_hz,
            bridge.area,
        );
        self.nut
            .set_pulse(nut_delay, nut.width_s * self.sample_rate_hz, nut.area);
    }
}

impl<F: FrictionLaw> BowedVoice for BowedString<F> {
    fn prepare(&mut self, sample_rate_hz: f64) -> Result<(), BowedConfigError> {
        self.capacity.check_sample_rate(sample_rate_hz)?;
        self.sample_rate_hz = sample_rate_hz;
        self.body.prepare(sample_rate_hz);
        // The delays in samples change with the rate even where the pitch does not.
        self.pitch_hz = self.clamped_pitch_hz(self.pitch_hz);
        self.update_reflections();
        self.reset();
        Ok(())
    }

    fn reset(&mut self) {
        self.bridge.reset();
        self.nut.reset();
        self.bow.reset();
        self.body.reset();
        self.last_solution = RESTING_SOLUTION;
    }

    /// Clamped to [lowest pitch of the capacity, sample rate / 4]; non-finite is ignored. The
    /// reflection functions are recomputed only when the pitch changes (the instrument sets the
    /// controls every sample).
    fn set_pitch_hz(&mut self, pitch_hz: f64) {
        if pitch_hz.is_finite() {
            let pitch_hz = self.clamped_pitch_hz(pitch_hz);
            if pitch_hz != self.pitch_hz {
                self.pitch_hz = pitch_hz;
                self.update_reflections();
            }
        }
    }

    /// Negative values are taken as 0 (bow lifted); non-finite is ignored.
    fn set_bow_force_n(&mut self, bow_force_n: f64) {
        if bow_force_n.is_finite() {
            self.bow_force_n = bow_force_n.max(0.0);
        }
    }

    /// Non-finite is ignored.
    fn set_bow_velocity_m_s(&mut self, bow_velocity_m_s: f64) {
        if bow_velocity_m_s.is_finite() {
            self.bow_velocity_m_s = bow_velocity_m_s;
        }
    }

    /// Clamped to [`BOW_POSITION_RANGE`]; non-finite is ignored. Where β/f₀ is shorter than
    /// one sample the bridge-side delay is held at one sample (the pitch then runs sharp). The
    /// reflection functions are recomputed only when the position changes.
    fn set_bow_position(&mut self, beta: f64) {
        if beta.is_finite() {
            let beta = beta.clamp(BOW_POSITION_RANGE.0, BOW_POSITION_RANGE.1);
            if beta != self.bow_position {
                self.bow_position = beta;
                self.update_reflections();
            }
        }
    }

    fn set_body_enabled(&mut self, enabled: bool) {
        self.body_enabled = enabled;
    }

    /// The per-sample path works on the voice's fields directly: building a block's run state
    /// for one sample would cost more than the sample. [`Self::process`] runs the same
    /// arithmetic (`RoundedRun::step`) bit for bit (tests/bowed_reference.rs).
    #[inline]
    fn next_sample(&mut self) -> BowedOutput {
        let z0 = self.wave_impedance_n_s_m;
        let line_slope = 2.0 * z0;

        let incoming_bridge = self.bridge.incoming();
        let incoming_nut = self.nut.incoming();
        let free_velocity = incoming_bridge + incoming_nut;

        let solution = self.bow.solve(
            &self.friction,
            line_slope,
            free_velocity,
            self.bow_velocity_m_s,
            self.bow_force_n,
        );
        let bow_wave = solution.friction_force_n / line_slope;
        let outgoing_bridge = incoming_nut + bow_wave;
        let outgoing_nut = incoming_bridge + bow_wave;

        // Read before pushing: the wave sent towards the bridge one round trip ago.
        let arriving_at_bridge = self.bridge.outgoing_round_trip_ago();
        self.bridge.push(outgoing_bridge);
        self.nut.push(outgoing_nut);

        let bridge_force_n = z0 * (arriving_at_bridge - incoming_bridge);
        let radiated = if self.body_enabled {
            self.body.tick(bridge_force_n)
        } else {
            bridge_force_n
        };

        let output = BowedOutput {
            bridge_force_n,
            bow_point_velocity_m_s: solution.velocity_m_s,
            radiated,
        };
        if !all_finite([
            output.bridge_force_n,
            output.bow_point_velocity_m_s,
            output.radiated,
            outgoing_bridge,
            outgoing_nut,
        ]) {
            self.reset();
            return BowedOutput::default();
        }
        self.last_solution = solution;
        output
    }

    fn process(&mut self, radiated: &mut [f32]) {
        match (self.body_enabled, self.body.active_groups()) {
            (true, 1) => self.run::<1, _>(|run| run.render(radiated)),
            (true, 2) => self.run::<2, _>(|run| run.render(radiated)),
            _ => self.run::<0, _>(|run| run.render(radiated)),
        }
    }
}

impl<F: FrictionLaw> BowedString<F> {
    /// Run `work` on the voice's state taken out for a run of samples (`G` body groups; 0 when
    /// the body is bypassed), then store the state back.
    #[inline(always)]
    fn run<const G: usize, R>(&mut self, work: impl FnOnce(&mut RoundedRun<'_, F, G>) -> R) -> R {
        let mut groups = self.body.copy_groups::<G>();
        let z0 = self.wave_impedance_n_s_m;
        let mut run = RoundedRun {
            friction: &self.friction,
            bridge: self.bridge.cursor(),
            nut: self.nut.cursor(),
            bow: self.bow,
            body: BodyRun::new(&mut groups),
            body_enabled: self.body_enabled,
            wave_impedance_n_s_m: z0,
            line_slope_n_s_m: 2.0 * z0,
            bow_force_n: self.bow_force_n,
            bow_velocity_m_s: self.bow_velocity_m_s,
            last_solution: self.last_solution,
            scratch: &mut self.run_scratch,
        };
        let result = work(&mut run);
        let (bow, last_solution) = (run.bow, run.last_solution);
        // Ends the borrows: the cursors store their write positions back.
        drop(run);
        self.bow = bow;
        self.body.store_groups(&groups);
        self.last_solution = last_solution;
        result
    }
}

/// The rounded-corner voice during a run of samples: controls fixed, delay-line positions, the
/// branch memory and the filter states in locals.
struct RoundedRun<'a, F, const G: usize> {
    friction: &'a F,
    bridge: ReflectionCursor<'a>,
    nut: ReflectionCursor<'a>,
    bow: BowPoint,
    body: BodyRun<'a, G>,
    body_enabled: bool,
    wave_impedance_n_s_m: f64,
    /// 2Z₀, N s/m.
    line_slope_n_s_m: f64,
    bow_force_n: f64,
    bow_velocity_m_s: f64,
    last_solution: BowPointSolution,
    scratch: &'a mut RunScratch,
}

/// Samples a run renders stage by stage ([`RoundedRun::render_run`]).
const RUN: usize = 16;

/// The per-sample values of a run, kept in the voice so that no run clears or moves them: only
/// the first samples of a run are written, and only those are read.
#[derive(Clone, Debug)]
struct RunScratch {
    incoming_bridge: [f64; RUN],
    incoming_nut: [f64; RUN],
    arriving_at_bridge: [f64; RUN],
    outgoing_bridge: [f64; RUN],
    outgoing_nut: [f64; RUN],
    velocity: [f64; RUN],
}

impl Default for RunScratch {
    fn default() -> Self {
        Self {
            incoming_bridge: [0.0; RUN],
            incoming_nut: [0.0; RUN],
            arriving_at_bridge: [0.0; RUN],
            outgoing_bridge: [0.0; RUN],
            outgoing_nut: [0.0; RUN],
            velocity: [0.0; RUN],
        }
    }
}

impl<F: FrictionLaw, const G: usize> RoundedRun<'_, F, G> {
    #[inline]
    fn render(&mut self, radiated: &mut [f32]) {
        // A wave pushed into either line comes back no sooner than its first tap's delay (or
        // the round trip), so in a run no longer than that every read sees only waves pushed
        // before the run: the reads of the run's samples are independent.
        let reach = self.bridge.run_reach().min(self.nut.run_reach()).min(RUN);
        if reach < 4 {
            self.render_by_sample(radiated);
            return;
        }
        for run in radiated.chunks_mut(reach) {
            self.render_run(run);
        }
    }

    fn render_by_sample(&mut self, radiated: &mut [f32]) {
        for sample in radiated.iter_mut() {
            *sample = self.step().radiated as f32;
        }
    }

    /// [`Self::step`] for each sample of `radiated` (at most [`RUN`] and the lines' reach), the
    /// same arithmetic in the same order, by stages: every read and convolution, then the bow
    /// point sample after sample (its branch memory carries over), then the pushes, then the
    /// body and the output.
    #[inline(always)]
    fn render_run(&mut self, radiated: &mut [f32]) {
        let count = radiated.len().min(RUN);
        let controls = self.controls();
        let scratch = &mut *self.scratch;
        let read = self
            .bridge
            .incoming_run(&mut scratch.incoming_bridge[..count])
            && self
                .bridge
                .round_trip_run(&mut scratch.arriving_at_bridge[..count])
            && self.nut.incoming_run(&mut scratch.incoming_nut[..count]);
        if !read {
            return self.render_by_sample(radiated);
        }
        let mut solution = self.last_solution;
        for k in 0..count {
            (
                solution,
                scratch.outgoing_bridge[k],
                scratch.outgoing_nut[k],
            ) = Self::bow_junction(
                &mut self.bow,
                self.friction,
                controls,
                scratch.incoming_bridge[k],
                scratch.incoming_nut[k],
            );
            scratch.velocity[k] = solution.velocity_m_s;
        }
        self.bridge.push_run(&scratch.outgoing_bridge[..count]);
        self.nut.push_run(&scratch.outgoing_nut[..count]);

        let z0 = self.wave_impedance_n_s_m;
        let bridge_force =
            |k: usize| z0 * (scratch.arriving_at_bridge[k] - scratch.incoming_bridge[k]);
        let mut probe = 0.0;
        for (k, sample) in radiated[..count].iter_mut().enumerate() {
            let bridge_force_n = bridge_force(k);
            let out = if self.body_enabled {
                self.body.tick(bridge_force_n)
            } else {
                bridge_force_n
            };
            probe += bridge_force_n * 0.0
                + scratch.velocity[k] * 0.0
                + out * 0.0
                + scratch.outgoing_bridge[k] * 0.0
                + scratch.outgoing_nut[k] * 0.0;
            *sample = out as f32;
        }
        if probe == 0.0 {
            self.last_solution = solution;
            return;
        }
        // Some sample was not finite: silence from there on and reset, as `step` does at that
        // sample (the rest of this run is silent; the next starts from rest).
        let first = (0..count)
            .find(|&k| {
                !all_finite([
                    bridge_force(k),
                    scratch.velocity[k],
                    f64::from(radiated[k]),
                    scratch.outgoing_bridge[k],
                    scratch.outgoing_nut[k],
                ])
            })
            .unwrap_or(0);
        radiated[first..].fill(0.0);
        self.bridge.reset();
        self.nut.reset();
        self.bow.reset();
        self.body.reset();
        self.last_solution = RESTING_SOLUTION;
    }

    /// The bow point of one sample from the waves arriving at it: its solution and the waves it
    /// sends towards bridge and nut. The bow point and the controls are passed apart from the
    /// rest of the run so that a run can hold its arrays while it calls this.
    #[inline(always)]
    fn bow_junction(
        bow: &mut BowPoint,
        friction: &F,
        controls: [f64; 3],
        incoming_bridge: f64,
        incoming_nut: f64,
    ) -> (BowPointSolution, f64, f64) {
        let [line_slope, bow_velocity_m_s, bow_force_n] = controls;
        let free_velocity = incoming_bridge + incoming_nut;
        let solution = bow.solve(
            friction,
            line_slope,
            free_velocity,
            bow_velocity_m_s,
            bow_force_n,
        );
        let bow_wave = solution.friction_force_n / line_slope;
        (
            solution,
            incoming_nut + bow_wave,
            incoming_bridge + bow_wave,
        )
    }

    /// The line slope 2Z₀, the bow's velocity and its force, for [`Self::bow_junction`].
    #[inline(always)]
    fn controls(&self) -> [f64; 3] {
        [
            self.line_slope_n_s_m,
            self.bow_velocity_m_s,
            self.bow_force_n,
        ]
    }

    /// One sample of the module doc's equations.
    #[inline(always)]
    fn step(&mut self) -> BowedOutput {
        let z0 = self.wave_impedance_n_s_m;

        let incoming_bridge = self.bridge.incoming();
        let incoming_nut = self.nut.incoming();
        let controls = self.controls();
        let (solution, outgoing_bridge, outgoing_nut) = Self::bow_junction(
            &mut self.bow,
            self.friction,
            controls,
            incoming_bridge,
            incoming_nut,
        );

        // Read before pushing: the wave sent towards the bridge one round trip ago.
        let arriving_at_bridge = self.bridge.outgoing_round_trip_ago();
        self.bridge.push(outgoing_bridge);
        self.nut.push(outgoing_nut);

        let bridge_force_n = z0 * (arriving_at_bridge - incoming_bridge);
        let radiated = if self.body_enabled {
            self.body.tick(bridge_force_n)
        } else {
            bridge_force_n
        };

        let output = BowedOutput {
            bridge_force_n,
            bow_point_velocity_m_s: solution.velocity_m_s,
            radiated,
        };
        if !all_finite([
            output.bridge_force_n,
            output.bow_point_velocity_m_s,
            output.radiated,
            outgoing_bridge,
            outgoing_nut,
        ]) {
            // The voice's reset, on the run's state.
            self.bridge.reset();
            self.nut.reset();
            self.bow.reset();
            self.body.reset();
            self.last_solution = RESTING_SOLUTION;
            return BowedOutput::default();
        }
        self.last_solution = solution;
        output
    }
}
