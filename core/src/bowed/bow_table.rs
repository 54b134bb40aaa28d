//! The cheap tier: the STK bow-table waveguide (seed `004_7bfa60067b967fec.txt`; Smith 1986,
//! after McIntyre–Schumacher–Woodhouse 1983; Cook & Scavone's STK `Bowed`).
//!
//! The bow is a memoryless reflection coefficient of the differential velocity
//! Δv⁺ = v_b − (i_b + i_n) (bow velocity minus the sum of the incoming waves), seed 004:
//!
//! ```text
//!     BowTable(Δv⁺) = min{ (|Δv⁺| · S + 0.75)^−4, 1 },      S = 5 − 4 · pressure
//! ```
//!
//! and the bow adds Δv⁺ · BowTable(Δv⁺) to both outgoing waves. The plateau |Δv⁺| ≤ 0.25/S,
//! where the table is 1, is sticking (the string is pulled to the bow velocity); outside it the
//! string slips. There is no hysteresis, no friction force and no impedance: the velocities are
//! those of the rounded-corner voice (m/s) so both tiers take the same controls, and the bridge
//! force is reported as Z₀ (incident − reflected) like the rounded-corner voice's.
//!
//! Loop: two fractional delay lines (linear interpolation), bow→nut→bow of D_n and
//! bow→bridge→bow of D_b, and a loss filter in the bridge reflection with STK's gain 0.95.
//! STK uses a one-pole low-pass there; this tier uses the symmetric three-tap low-pass
//! g·[¼, ½, ¼] instead (Woodhouse's [σ, λ, σ] shape of eq. 22), because a one-pole's group
//! delay falls with frequency, so the sharp Helmholtz corner travels round a shorter loop than
//! the fundamental: measured with the one-pole, +4.5 cents at 440 Hz / 48 kHz even with its
//! phase delay at f₀ taken out. The three-tap filter delays every frequency by exactly one
//! sample; that sample is taken out of the loop and the rest split β : (1 − β).
//!
//! Mapping of the physical bow force to STK's normalised pressure:
//! pressure = clamp(F_b / `full_pressure_force_n`, 0, 1). F_b = 0 lifts the bow: the table is
//! bypassed and the string rings down.
//!
//! **Blocks in runs** (`BowedVoice::process`). A wave pushed into a delay line comes back no
//! sooner than the line's whole samples later, so the samples of a run no longer than the
//! shorter line's whole delay (and at most `RUN` = 16 samples) read only waves pushed before the run: they
//! are independent of each other except through the body filter. A run is rendered stage by
//! stage: both lines' reads, the loss filter and the junctions (a branch-free loop over the
//! run's samples that the compiler vectorises: the table's plateau test became a comparison
//! that gives the same value bit for bit), the pushes, then the body filter and the output. The
//! arithmetic of every sample is that of [`BowedVoice::next_sample`], so `process` reproduces it
//! bit for bit (tests/bowed_reference.rs, down to delays shorter than a run); delays under four
//! samples take the sample-by-sample path. Hand-written rather than on a SIMD crate's vector
//! types: the compiler vectorises these loops, and fused multiply-adds would change the
//! round-off against `next_sample`. The block path is compiled once per vector unit and picked
//! at run time through pulp (`RenderOnUnit`): the same operations, so the same bits, on
//! three-operand AVX2 instructions where the machine has them (body off 24.8 → 20 µs per 0.1 s,
//! divan). The body filter's stage stays on the baseline unit (`BodyRun::filter_run`, never
//! inlined), where its four sections ran faster than in 256-bit code; with the body's shorter
//! recursion (`body.rs`), body on 35.9 → 29.2 µs (docs/performance.md).

use super::body::{BodyFilter, BodyResonance, BodyRun, VIOLIN_BODY};
use super::bowed_string::{all_finite, StringConstants, BOW_POSITION_RANGE};
use super::delay_line::{DelayCursor, DelayHistory, FractionalDelay};
use super::{BowedCapacity, BowedConfigError, BowedOutput, BowedVoice, MIN_SAMPLE_RATE_HZ};

/// STK's slope for a normalised bow pressure in [0, 1]: S = 5 − 4 · pressure (seed 004).
/// Pressure outside [0, 1] is clamped.
#[inline]
pub fn bow_table_slope(pressure: f64) -> f64 {
    5.0 - 4.0 * pressure.clamp(0.0, 1.0)
}

/// The bow table of seed 004: min{(|Δv⁺| · S + 0.75)^−4, 1}, its fourth power as two
/// squarings (no `powf`).
///
/// On the plateau, base = |Δv⁺| S + 0.75 ≤ 1, the fourth power is ≤ 1 and the minimum is 1:
/// it is returned without the division, which keeps the division off the sticking samples
/// (most of the period). Off it, base > 1 gives base⁴ ≥ 1 and the quotient is already ≤ 1.
#[inline]
pub fn bow_table_reflection(differential_velocity: f64, slope: f64) -> f64 {
    let base = differential_velocity.abs() * slope + 0.75;
    if base <= 1.0 {
        return 1.0;
    }
    let squared = base * base;
    (1.0 / (squared * squared)).min(1.0)
}

/// [`bow_table_reflection`] without the plateau's branch, bit for bit the same value: on the
/// plateau base⁴ ≤ 1, so the quotient is ≥ 1 and the minimum is exactly 1 (base ≥ 0.75 keeps
/// it finite). For runs of samples, where a branch per sample stops the loop from vectorising.
#[inline(always)]
fn bow_table_reflection_branch_free(differential_velocity: f64, slope: f64) -> f64 {
    let base = differential_velocity.abs() * slope + 0.75;
    let squared = base * base;
    let quotient = 1.0 / (squared * squared);
    // `quotient.min(1.0)` as a comparison (a NaN quotient gives 1 both ways), which vectorises.
    if quotient < 1.0 {
        quotient
    } else {
        1.0
    }
}

/// Default force for full STK pressure, N: a firm violin bow stroke.
pub const DEFAULT_FULL_PRESSURE_FORCE_N: f64 = 2.0;

/// STK's bridge-reflection loss, gain 0.95 at low frequency.
const STRING_FILTER_GAIN: f64 = 0.95;

/// Outer taps σ of the linear-phase loss filter g·[σ, 1 − 2σ, σ] (zero response at Nyquist).
const STRING_FILTER_SIDE_TAP: f64 = 0.25;

/// Group delay of that filter, samples (constant: it is symmetric).
const STRING_FILTER_DELAY_SAMPLES: f64 = 1.0;

/// The STK bow-table bowed string.
#[derive(Clone, Debug)]
pub struct BowTableString {
    capacity: BowedCapacity,
    sample_rate_hz: f64,
    wave_impedance_n_s_m: f64,
    full_pressure_force_n: f64,
    neck: DelayHistory,
    bridge: DelayHistory,
    /// Bow → nut → bow, samples, split when the controls change.
    neck_delay: FractionalDelay,
    /// Bow → bridge → bow without the loss filter's sample, split when the controls change.
    bridge_delay: FractionalDelay,
    filter_history: [f64; 2],
    body: BodyFilter,
    body_enabled: bool,
    pitch_hz: f64,
    bow_force_n: f64,
    bow_velocity_m_s: f64,
    bow_position: f64,
    slope: f64,
    run_scratch: RunScratch,
    /// The vector unit the block path is compiled for, detected once under
    /// `JAVARI_VECTOR_UNIT`'s cap ([`crate::simd::vector_unit`], [`RenderOnUnit`]).
    arch: pulp::Arch,
}

impl BowTableString {
    /// Allocate for `capacity`; Z₀ from `constants` (only used to express the bridge force in N).
    /// Starts at 48 kHz (or the capacity's rate if lower), 440 Hz, β = 0.1, bow lifted.
    pub fn new(capacity: BowedCapacity, constants: StringConstants) -> Self {
        let max_rate = capacity.max_sample_rate_hz.max(MIN_SAMPLE_RATE_HZ);
        let lowest_pitch = capacity.lowest_pitch_hz.max(1.0);
        let capacity = BowedCapacity {
            max_sample_rate_hz: max_rate,
            lowest_pitch_hz: lowest_pitch,
        };
        let max_delay = max_rate / lowest_pitch;
        let sample_rate_hz = 48_000.0_f64.min(max_rate);
        let mut voice = Self {
            capacity,
            sample_rate_hz,
            wave_impedance_n_s_m: constants.wave_impedance_n_s_m(),
            full_pressure_force_n: DEFAULT_FULL_PRESSURE_FORCE_N,
            neck: DelayHistory::new(max_delay.max(1.0).ceil() as usize + 3),
            bridge: DelayHistory::new(max_delay.max(1.0).ceil() as usize + 3),
            neck_delay: FractionalDelay::new(1.0, 1.0),
            bridge_delay: FractionalDelay::new(1.0, 1.0),
            filter_history: [0.0; 2],
            body: BodyFilter::new(&VIOLIN_BODY, sample_rate_hz),
            body_enabled: true,
            pitch_hz: 440.0,
            bow_force_n: 0.0,
            bow_velocity_m_s: 0.0,
            bow_position: 0.1,
            slope: bow_table_slope(0.0),
            run_scratch: RunScratch::default(),
            arch: crate::simd::vector_unit(),
        };
        voice.update_delays();
        voice
    }

    /// Bow force that maps to STK pressure 1, N (> 0; other values are ignored).
    pub fn set_full_pressure_force_n(&mut self, force_n: f64) {
        if force_n.is_finite() && force_n > 0.0 {
            self.full_pressure_force_n = force_n;
            self.set_bow_force_n(self.bow_force_n);
        }
    }

    /// Replace the body resonances (at most 8). Allocation-free.
    pub fn set_body_resonances(&mut self, resonances: &[BodyResonance]) {
        self.body.set_resonances(resonances);
    }

    /// The table slope S in use.
    pub fn slope(&self) -> f64 {
        self.slope
    }

    /// Pitch in use after clamping, Hz.
    pub fn pitch_hz(&self) -> f64 {
        self.pitch_hz
    }

    /// Total loop delay through both lines and the loss filter, samples.
    pub fn loop_delay_samples(&self) -> f64 {
        self.neck_delay.samples() + self.bridge_delay.samples() + STRING_FILTER_DELAY_SAMPLES
    }

    /// `pitch_hz` clamped to [lowest pitch of the capacity, sample rate / 4].
    fn clamped_pitch_hz(&self, pitch_hz: f64) -> f64 {
        // min/max, not clamp: a capacity whose lowest pitch exceeds f_s/4 must not panic.
        pitch_hz
            .min(0.25 * self.sample_rate_hz)
            .max(self.capacity.lowest_pitch_hz)
    }

    fn update_delays(&mut self) {
        let period = self.sample_rate_hz / self.pitch_hz;
        let line_total = period - STRING_FILTER_DELAY_SAMPLES;
        // Both neighbours of the interpolated read must lie inside the history.
        let max_delay = (self.neck.size() - 2) as f64;
        self.bridge_delay = FractionalDelay::new(self.bow_position * line_total, max_delay);
        self.neck_delay = FractionalDelay::new((1.0 - self.bow_position) * line_total, max_delay);
    }
}

impl BowedVoice for BowTableString {
    fn prepare(&mut self, sample_rate_hz: f64) -> Result<(), BowedConfigError> {
        self.capacity.check_sample_rate(sample_rate_hz)?;
        self.sample_rate_hz = sample_rate_hz;
        self.body.prepare(sample_rate_hz);
        // The delays in samples change with the rate even where the pitch does not.
        self.pitch_hz = self.clamped_pitch_hz(self.pitch_hz);
        self.update_delays();
        self.reset();
        Ok(())
    }

    fn reset(&mut self) {
        self.neck.reset();
        self.bridge.reset();
        self.filter_history = [0.0; 2];
        self.body.reset();
    }

    /// Clamped to [lowest pitch of the capacity, sample rate / 4]; non-finite is ignored. The
    /// delays are split again only when the pitch changes (the instrument sets the controls
    /// every sample).
    fn set_pitch_hz(&mut self, pitch_hz: f64) {
        if pitch_hz.is_finite() {
            let pitch_hz = self.clamped_pitch_hz(pitch_hz);
            if pitch_hz != self.pitch_hz {
                self.pitch_hz = pitch_hz;
                self.update_delays();
            }
        }
    }

    fn set_bow_force_n(&mut self, bow_force_n: f64) {
        if bow_force_n.is_finite() {
            self.bow_force_n = bow_force_n.max(0.0);
            self.slope = bow_table_slope(self.bow_force_n / self.full_pressure_force_n);
        }
    }

    fn set_bow_velocity_m_s(&mut self, bow_velocity_m_s: f64) {
        if bow_velocity_m_s.is_finite() {
            self.bow_velocity_m_s = bow_velocity_m_s;
        }
    }

    fn set_bow_position(&mut self, beta: f64) {
        if beta.is_finite() {
            let beta = beta.clamp(BOW_POSITION_RANGE.0, BOW_POSITION_RANGE.1);
            if beta != self.bow_position {
                self.bow_position = beta;
                self.update_delays();
            }
        }
    }

    fn set_body_enabled(&mut self, enabled: bool) {
        self.body_enabled = enabled;
    }

    /// The per-sample path works on the voice's fields directly: building a block's run state
    /// for one sample would cost more than the sample. [`Self::process`] runs the same
    /// arithmetic (`TableRun::step`, and by stages `TableRun::render_run`) bit for bit
    /// (tests/bowed_reference.rs).
    #[inline]
    fn next_sample(&mut self) -> BowedOutput {
        let arriving_at_bridge = self.bridge.read(&self.bridge_delay);
        let [previous, before_previous] = self.filter_history;
        let filtered = STRING_FILTER_GAIN
            * (STRING_FILTER_SIDE_TAP * (arriving_at_bridge + before_previous)
                + (1.0 - 2.0 * STRING_FILTER_SIDE_TAP) * previous);
        self.filter_history = [arriving_at_bridge, previous];
        let bridge_reflection = -filtered;
        let nut_reflection = -self.neck.read(&self.neck_delay);

        let string_velocity = bridge_reflection + nut_reflection;
        let differential_velocity = self.bow_velocity_m_s - string_velocity;
        let bow_wave = if self.bow_force_n > 0.0 {
            differential_velocity * bow_table_reflection(differential_velocity, self.slope)
        } else {
            0.0
        };

        self.neck.push(bridge_reflection + bow_wave);
        self.bridge.push(nut_reflection + bow_wave);

        let bridge_force_n = self.wave_impedance_n_s_m * (arriving_at_bridge - bridge_reflection);
        let radiated = if self.body_enabled {
            self.body.tick(bridge_force_n)
        } else {
            bridge_force_n
        };
        let output = BowedOutput {
            bridge_force_n,
            bow_point_velocity_m_s: string_velocity + bow_wave,
            radiated,
        };
        if !all_finite([
            output.bridge_force_n,
            output.bow_point_velocity_m_s,
            output.radiated,
        ]) {
            self.reset();
            return BowedOutput::default();
        }
        output
    }

    fn process(&mut self, radiated: &mut [f32]) {
        let arch = self.arch;
        match (self.body_enabled, self.body.active_groups()) {
            (true, 1) => arch.dispatch(RenderOnUnit::<1> {
                voice: self,
                radiated,
            }),
            (true, 2) => arch.dispatch(RenderOnUnit::<2> {
                voice: self,
                radiated,
            }),
            _ => arch.dispatch(RenderOnUnit::<0> {
                voice: self,
                radiated,
            }),
        }
    }
}

impl BowTableString {
    /// Run `work` on the voice's state taken out for a run of samples (`G` body groups; 0 when
    /// the body is bypassed), then store the state back.
    #[inline(always)]
    fn run<const G: usize, R>(&mut self, work: impl FnOnce(&mut TableRun<'_, G>) -> R) -> R {
        let mut groups = self.body.copy_groups::<G>();
        let mut run = TableRun {
            neck: self.neck.cursor(),
            bridge: self.bridge.cursor(),
            neck_delay: self.neck_delay,
            bridge_delay: self.bridge_delay,
            filter_history: self.filter_history,
            body: BodyRun::new(&mut groups),
            body_enabled: self.body_enabled,
            bow_on: self.bow_force_n > 0.0,
            bow_velocity_m_s: self.bow_velocity_m_s,
            slope: self.slope,
            wave_impedance_n_s_m: self.wave_impedance_n_s_m,
            scratch: &mut self.run_scratch,
        };
        let result = work(&mut run);
        let filter_history = run.filter_history;
        // Ends the borrows: the cursors store their write positions back.
        drop(run);
        self.filter_history = filter_history;
        self.body.store_groups(&groups);
        result
    }
}

/// [`BowTableString::process`] with `G` body groups, compiled for each vector unit and picked at
/// run time: on AVX2 the reads, junctions and pushes run on three-operand instructions (the body
/// filter's stage stays on the baseline unit, `BodyRun::filter_run`). The same operations in the
/// same order (no fused multiply-add), so every unit computes the same bits as `next_sample`.
struct RenderOnUnit<'a, const G: usize> {
    voice: &'a mut BowTableString,
    radiated: &'a mut [f32],
}

impl<const G: usize> pulp::WithSimd for RenderOnUnit<'_, G> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let radiated = self.radiated;
        self.voice.run::<G, _>(|run| run.render(radiated));
    }
}

/// The bow-table voice during a run of samples: controls fixed, delay-line positions and filter
/// states in locals.
struct TableRun<'a, const G: usize> {
    neck: DelayCursor<'a>,
    bridge: DelayCursor<'a>,
    neck_delay: FractionalDelay,
    bridge_delay: FractionalDelay,
    filter_history: [f64; 2],
    body: BodyRun<'a, G>,
    body_enabled: bool,
    bow_on: bool,
    bow_velocity_m_s: f64,
    slope: f64,
    wave_impedance_n_s_m: f64,
    scratch: &'a mut RunScratch,
}

/// Samples a run renders stage by stage ([`TableRun::render_run`]).
const RUN: usize = 16;

/// The per-sample values of a run ([`TableRun::render_run`]), kept in the voice so that no run
/// clears or moves them: only the first samples of a run are written, and only those are read.
#[derive(Clone, Debug)]
struct RunScratch {
    /// `arriving[k + 2]` is sample k's wave at the bridge; [0] and [1] the loss filter's history.
    arriving: [f64; RUN + 2],
    from_nut: [f64; RUN],
    /// What the junctions send on: the waves pushed towards nut and bridge, the bridge force and
    /// the string's velocity under the bow.
    to_nut: [f64; RUN],
    to_bridge: [f64; RUN],
    bridge_force: [f64; RUN],
    bow_point_velocity: [f64; RUN],
}

impl Default for RunScratch {
    fn default() -> Self {
        Self {
            arriving: [0.0; RUN + 2],
            from_nut: [0.0; RUN],
            to_nut: [0.0; RUN],
            to_bridge: [0.0; RUN],
            bridge_force: [0.0; RUN],
            bow_point_velocity: [0.0; RUN],
        }
    }
}

impl<const G: usize> TableRun<'_, G> {
    #[inline(always)]
    fn render(&mut self, radiated: &mut [f32]) {
        // A value pushed into a delay line is read back `whole` samples later at the earliest,
        // so in a run of at most that many samples every read sees only values pushed before
        // the run: the run's samples are independent but for the body filter.
        let reach = self
            .neck_delay
            .whole()
            .min(self.bridge_delay.whole())
            .min(RUN);
        if reach < 4 {
            // Written out rather than a call of `render_by_sample`: measured, the call here
            // made the compiler lay out the whole block path worse (37 → 49 µs per 0.1 s).
            for sample in radiated.iter_mut() {
                *sample = self.step().radiated as f32;
            }
            return;
        }
        for run in radiated.chunks_mut(reach) {
            self.render_run(run);
        }
    }

    /// [`Self::step`] for each sample of `radiated` (at most [`RUN`], and at most the shorter
    /// delay's whole samples), the same arithmetic in the same order, but stage by stage over
    /// the run: every read, then every junction, then every push, then the body. The stages
    /// are loops over independent samples that the processor overlaps (and the compiler
    /// vectorises), where the sample-by-sample loop is one long dependency chain per sample.
    #[inline(always)]
    fn render_run(&mut self, radiated: &mut [f32]) {
        let count = radiated.len().min(RUN);
        let scratch = &mut *self.scratch;
        let read = self
            .bridge
            .read_run(&self.bridge_delay, &mut scratch.arriving[2..2 + count])
            && self
                .neck
                .read_run(&self.neck_delay, &mut scratch.from_nut[..count]);
        if !read {
            return self.render_by_sample(radiated);
        }
        let [previous, before_previous] = self.filter_history;
        scratch.arriving[0] = before_previous;
        scratch.arriving[1] = previous;
        self.filter_history = [scratch.arriving[count + 1], scratch.arriving[count]];
        if self.bow_on {
            self.junctions::<true>(count);
        } else {
            self.junctions::<false>(count);
        }
        let scratch = &*self.scratch;
        self.neck.push_run(&scratch.to_nut[..count]);
        self.bridge.push_run(&scratch.to_bridge[..count]);

        let mut filtered = [0.0; RUN];
        if self.body_enabled {
            self.body
                .filter_run(&scratch.bridge_force[..count], &mut filtered[..count]);
        } else {
            filtered[..count].copy_from_slice(&scratch.bridge_force[..count]);
        }
        let mut probe = 0.0;
        for ((sample, &force), (&velocity, &out)) in radiated[..count]
            .iter_mut()
            .zip(&scratch.bridge_force[..count])
            .zip(scratch.bow_point_velocity[..count].iter().zip(&filtered))
        {
            probe += force * 0.0 + velocity * 0.0 + out * 0.0;
            *sample = out as f32;
        }
        if probe != 0.0 {
            // Some sample was not finite: silence from there on and reset, as `step` does at
            // that sample (the rest of this run is silent; the next starts from rest).
            let first = (0..count)
                .find(|&k| {
                    !all_finite([
                        scratch.bridge_force[k],
                        scratch.bow_point_velocity[k],
                        f64::from(radiated[k]),
                    ])
                })
                .unwrap_or(0);
            radiated[first..].fill(0.0);
            self.neck.reset();
            self.bridge.reset();
            self.filter_history = [0.0; 2];
            self.body.reset();
        }
    }

    /// The bow junction of each sample of a run (the middle of [`Self::step`]), branch-free so
    /// that the loop vectorises.
    #[inline(always)]
    fn junctions<const BOW_ON: bool>(&mut self, count: usize) {
        let scratch = &mut *self.scratch;
        let arriving = &scratch.arriving;
        for k in 0..count.min(RUN) {
            let filtered = STRING_FILTER_GAIN
                * (STRING_FILTER_SIDE_TAP * (arriving[k + 2] + arriving[k])
                    + (1.0 - 2.0 * STRING_FILTER_SIDE_TAP) * arriving[k + 1]);
            let bridge_reflection = -filtered;
            let nut_reflection = -scratch.from_nut[k];
            let string_velocity = bridge_reflection + nut_reflection;
            let differential_velocity = self.bow_velocity_m_s - string_velocity;
            let bow_wave = if BOW_ON {
                differential_velocity
                    * bow_table_reflection_branch_free(differential_velocity, self.slope)
            } else {
                0.0
            };
            scratch.to_nut[k] = bridge_reflection + bow_wave;
            scratch.to_bridge[k] = nut_reflection + bow_wave;
            scratch.bridge_force[k] =
                self.wave_impedance_n_s_m * (arriving[k + 2] - bridge_reflection);
            scratch.bow_point_velocity[k] = string_velocity + bow_wave;
        }
    }

    fn render_by_sample(&mut self, radiated: &mut [f32]) {
        for sample in radiated.iter_mut() {
            *sample = self.step().radiated as f32;
        }
    }

    /// One sample of seed 004's loop.
    #[inline(always)]
    fn step(&mut self) -> BowedOutput {
        let arriving_at_bridge = self.bridge.read(&self.bridge_delay);
        let [previous, before_previous] = self.filter_history;
        let filtered = STRING_FILTER_GAIN
            * (STRING_FILTER_SIDE_TAP * (arriving_at_bridge + before_previous)
                + (1.0 - 2.0 * STRING_FILTER_SIDE_TAP) * previous);
        self.filter_history = [arriving_at_bridge, previous];
        let bridge_reflection = -filtered;
        let nut_reflection = -self.neck.read(&self.neck_delay);

        let string_velocity = bridge_reflection + nut_reflection;
        let differential_velocity = self.bow_velocity_m_s - string_velocity;
        let bow_wave = if self.bow_on {
            differential_velocity * bow_table_reflection(differential_velocity, self.slope)
        } else {
            0.0
        };

        self.neck.push(bridge_reflection + bow_wave);
        self.bridge.push(nut_reflection + bow_wave);

        let bridge_force_n = self.wave_impedance_n_s_m * (arriving_at_bridge - bridge_reflection);
        let radiated = if self.body_enabled {
            self.body.tick(bridge_force_n)
        } else {
            bridge_force_n
        };
        let output = BowedOutput {
            bridge_force_n,
            bow_point_velocity_m_s: string_velocity + bow_wave,
            radiated,
        };
        if !all_finite([
            output.bridge_force_n,
            output.bow_point_velocity_m_s,
            output.radiated,
        ]) {
            // The voice's reset, on the run's state.
            self.neck.reset();
            self.bridge.reset();
            self.filter_history = [0.0; 2];
            self.body.reset();
            return BowedOutput::default();
        }
        output
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_values_by_hand() {
        // Plateau: |Δv| S + 0.75 ≤ 1 gives exactly 1.
        assert_eq!(bow_table_reflection(0.0, 3.0), 1.0);
        assert_eq!(bow_table_reflection(0.25, 1.0), 1.0);
        assert_eq!(bow_table_reflection(-0.05, 5.0), 1.0);
        // 1.25⁻⁴ = 0.4096; 1.75⁻⁴ = 1/9.37890625; symmetric in Δv.
        assert!((bow_table_reflection(0.5, 1.0) - 0.4096).abs() < 1e-16);
        assert!((bow_table_reflection(-0.2, 5.0) - 1.0 / 9.378_906_25).abs() < 1e-16);
        // Slope: pressure 0 → 5, 1 → 1, 0.5 → 3, clamped outside [0, 1].
        assert_eq!(bow_table_slope(0.0), 5.0);
        assert_eq!(bow_table_slope(1.0), 1.0);
        assert_eq!(bow_table_slope(0.5), 3.0);
        assert_eq!(bow_table_slope(7.0), 1.0);
    }

    #[test]
    fn table_matches_the_seed_formula_everywhere() {
        for i in -2000..=2000 {
            let dv = i as f64 * 1e-3;
            for &slope in &[1.0, 2.5, 4.0, 5.0] {
                let seed = (dv.abs() * slope + 0.75).powi(-4).min(1.0);
                let ours = bow_table_reflection(dv, slope);
                assert!(
                    (ours - seed).abs() <= 4.0 * f64::EPSILON * seed,
                    "dv={dv} S={slope}"
                );
            }
        }
    }
}
