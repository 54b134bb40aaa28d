//! An optional instrument-body filter: a few resonances driven by the bridge force.
//!
//! Each resonance is a two-pole band-pass (the constant-peak-gain form of R. Bristow-Johnson's
//! "Audio EQ Cookbook": b = [α, 0, −α]/(1 + α), a = [1, −2 cos ω, 1 − α]/(1 + α),
//! α = sin ω / (2Q)), so its gain at the centre frequency is exactly its `gain`. The resonances
//! run in parallel and their outputs add. This is a deliberately small stand-in for a measured
//! body response: it colours the bridge force the way the main air and wood modes of a violin do.

/// One body resonance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyResonance {
    /// Centre frequency, Hz (> 0).
    pub frequency_hz: f64,
    /// Quality factor (> 0).
    pub quality: f64,
    /// Gain at the centre frequency, in output units per newton of bridge force.
    pub gain_per_n: f64,
}

/// Most resonances a body filter holds (fixed storage: no allocation).
pub const MAX_BODY_RESONANCES: usize = 8;

/// Violin-like modes: the A0 air mode (≈ 275 Hz), the B1− and B1+ corpus modes (≈ 460 and
/// 550 Hz) and the broad bridge hill (≈ 2.5 kHz), after the values commonly reported in the
/// violin-acoustics literature (Woodhouse, "The acoustics of the violin: a review", 2014).
pub const VIOLIN_BODY: [BodyResonance; 4] = [
    BodyResonance {
        frequency_hz: 275.0,
        quality: 15.0,
        gain_per_n: 1.0,
    },
    BodyResonance {
        frequency_hz: 460.0,
        quality: 20.0,
        gain_per_n: 0.8,
    },
    BodyResonance {
        frequency_hz: 550.0,
        quality: 20.0,
        gain_per_n: 1.0,
    },
    BodyResonance {
        frequency_hz: 2500.0,
        quality: 2.0,
        gain_per_n: 0.6,
    },
];

/// Resonances are filtered four at a time: one group's sections are independent lanes of the
/// same arithmetic, which the compiler turns into vector instructions.
const LANES: usize = 4;

const GROUPS: usize = MAX_BODY_RESONANCES.div_ceil(LANES);

/// Four band-pass sections side by side (structure of arrays). Lanes past the bank's count have
/// zero coefficients and zero state, so they output exactly 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SectionGroup {
    /// b0 (b2 = −b0, b1 = 0 for a band-pass), a1 and a2.
    b0: [f64; LANES],
    a1: [f64; LANES],
    a2: [f64; LANES],
    /// The last output y_n, and the second state of transposed form II one and two samples
    /// back, `s_n = b2 x_n − a2 y_n` and `s_{n−1}`.
    y1: [f64; LANES],
    s_last: [f64; LANES],
    s_before: [f64; LANES],
}

/// The sum of a group's four outputs as two pairs, `(y₀ + y₂) + (y₁ + y₃)`: one vector addition
/// of the register halves and one scalar one, where adding them in turn took four.
#[inline(always)]
fn lane_sum(y: [f64; LANES]) -> f64 {
    (y[0] + y[2]) + (y[1] + y[3])
}

/// One sample of `x` through `groups`, their outputs summed in group order (0 without groups):
/// the one summation of the sample and block paths.
#[inline(always)]
fn group_sum(groups: &mut [SectionGroup], x: f64) -> f64 {
    let mut groups = groups.iter_mut();
    let Some(first) = groups.next() else {
        return 0.0;
    };
    let mut sum = lane_sum(first.tick(x));
    for group in groups {
        sum += lane_sum(group.tick(x));
    }
    sum
}

impl SectionGroup {
    /// One sample through the four sections: transposed direct form II with b1 = 0 and
    /// b2 = −b0 (a band-pass), its first state substituted, so that
    /// `y_{n+1} = (b0 x_{n+1} + s_{n−1}) − a1 y_n` and `s_{n+1} = −b0 x_{n+1} − a2 y_{n+1}`. The
    /// recursion from one output to the next is then one multiplication and one subtraction
    /// (the form with s1 chained a multiplication and two additions), and `b2 x = −(b0 x)` is
    /// formed once.
    #[inline]
    fn tick(&mut self, x: f64) -> [f64; LANES] {
        let mut y = [0.0; LANES];
        for lane in 0..LANES {
            let input = self.b0[lane] * x;
            y[lane] = (input + self.s_before[lane]) - self.a1[lane] * self.y1[lane];
            self.s_before[lane] = self.s_last[lane];
            self.s_last[lane] = -input - self.a2[lane] * y[lane];
        }
        self.y1 = y;
        y
    }

    fn reset(&mut self) {
        self.y1 = [0.0; LANES];
        self.s_last = [0.0; LANES];
        self.s_before = [0.0; LANES];
    }
}

/// Parallel bank of body resonances.
#[derive(Clone, Debug)]
pub struct BodyFilter {
    resonances: [BodyResonance; MAX_BODY_RESONANCES],
    groups: [SectionGroup; GROUPS],
    /// Groups holding at least one resonance.
    active_groups: usize,
    count: usize,
    sample_rate_hz: f64,
}

impl BodyFilter {
    /// A bank with `resonances` (at most [`MAX_BODY_RESONANCES`]; extra ones are ignored).
    pub fn new(resonances: &[BodyResonance], sample_rate_hz: f64) -> Self {
        let mut filter = Self {
            resonances: [BodyResonance {
                frequency_hz: 1.0,
                quality: 1.0,
                gain_per_n: 0.0,
            }; MAX_BODY_RESONANCES],
            groups: [SectionGroup::default(); GROUPS],
            active_groups: 0,
            count: 0,
            sample_rate_hz,
        };
        filter.set_resonances(resonances);
        filter
    }

    /// Replace the resonances and recompute coefficients (the state of the resonances kept is
    /// kept; that of resonances dropped is zeroed).
    pub fn set_resonances(&mut self, resonances: &[BodyResonance]) {
        self.count = resonances.len().min(MAX_BODY_RESONANCES);
        self.resonances[..self.count].copy_from_slice(&resonances[..self.count]);
        self.active_groups = self.count.div_ceil(LANES);
        self.update_coefficients();
    }

    /// Recompute coefficients for a new sample rate.
    pub fn prepare(&mut self, sample_rate_hz: f64) {
        self.sample_rate_hz = sample_rate_hz;
        self.update_coefficients();
    }

    fn update_coefficients(&mut self) {
        for index in 0..MAX_BODY_RESONANCES {
            let group = &mut self.groups[index / LANES];
            let lane = index % LANES;
            if index >= self.count {
                group.b0[lane] = 0.0;
                group.a1[lane] = 0.0;
                group.a2[lane] = 0.0;
                group.y1[lane] = 0.0;
                group.s_last[lane] = 0.0;
                group.s_before[lane] = 0.0;
                continue;
            }
            let resonance = &self.resonances[index];
            // A resonance at or above Nyquist cannot be represented: keep it just below.
            let nyquist_guard = 0.49 * self.sample_rate_hz;
            let frequency = resonance.frequency_hz.min(nyquist_guard).max(1e-3);
            let omega = 2.0 * core::f64::consts::PI * frequency / self.sample_rate_hz;
            let alpha = omega.sin() / (2.0 * resonance.quality.max(1e-3));
            let a0 = 1.0 + alpha;
            group.b0[lane] = resonance.gain_per_n * alpha / a0;
            group.a1[lane] = -2.0 * omega.cos() / a0;
            group.a2[lane] = (1.0 - alpha) / a0;
        }
    }

    /// Filter one sample of bridge force (N).
    #[inline]
    pub fn tick(&mut self, bridge_force_n: f64) -> f64 {
        // The idle lanes add exact zeros.
        group_sum(&mut self.groups[..self.active_groups], bridge_force_n)
    }

    /// Zero the filter states.
    pub fn reset(&mut self) {
        for group in &mut self.groups {
            group.reset();
        }
    }

    /// How many groups of four resonances hold at least one resonance (0 to 2): the `G` of a
    /// [`BodyRun`].
    pub(crate) fn active_groups(&self) -> usize {
        self.active_groups
    }

    /// A copy of the first `G` groups, for a run of samples whose filter state should live in
    /// registers; [`Self::store_groups`] puts it back.
    #[inline]
    pub(crate) fn copy_groups<const G: usize>(&self) -> [SectionGroup; G] {
        core::array::from_fn(|index| self.groups.get(index).copied().unwrap_or_default())
    }

    /// Store groups copied out by [`Self::copy_groups`].
    #[inline]
    pub(crate) fn store_groups<const G: usize>(&mut self, groups: &[SectionGroup; G]) {
        for (stored, group) in self.groups.iter_mut().zip(groups) {
            *stored = *group;
        }
    }
}

/// The body filter during a run of samples: `G` groups, a number fixed at compile time so that
/// every loop unrolls, borrowed from a local copy (their state then stays in registers).
#[derive(Debug)]
pub(crate) struct BodyRun<'a, const G: usize> {
    groups: &'a mut [SectionGroup; G],
}

impl<'a, const G: usize> BodyRun<'a, G> {
    /// A run over `groups` (from [`BodyFilter::copy_groups`]).
    #[inline]
    pub(crate) fn new(groups: &'a mut [SectionGroup; G]) -> Self {
        Self { groups }
    }

    /// As [`BodyFilter::tick`] (the same arithmetic in the same order).
    #[inline]
    pub(crate) fn tick(&mut self, bridge_force_n: f64) -> f64 {
        group_sum(self.groups, bridge_force_n)
    }

    /// [`Self::tick`] for each force of a run, into `out`. Never inlined, so that it is compiled
    /// for the baseline unit even when its caller is compiled for AVX2 (`bow_table.rs`): inlined
    /// into the AVX2 block path the body cost 25 µs per 0.1 s of the bench's bowed note, against
    /// 11 µs on 128-bit registers (divan, `scene::process`; the 2-core AMD EPYC splits 256-bit
    /// operations in two, and the sum across the lanes pays for the extractions).
    #[inline(never)]
    pub(crate) fn filter_run(&mut self, forces: &[f64], out: &mut [f64]) {
        for (filtered, &force) in out.iter_mut().zip(forces) {
            *filtered = self.tick(force);
        }
    }

    /// As [`BodyFilter::reset`].
    pub(crate) fn reset(&mut self) {
        for group in self.groups.iter_mut() {
            group.reset();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steady_gain(filter: &mut BodyFilter, frequency_hz: f64, sample_rate_hz: f64) -> f64 {
        filter.reset();
        let n = (sample_rate_hz * 2.0) as usize;
        let mut peak: f64 = 0.0;
        for i in 0..n {
            let x = (2.0 * core::f64::consts::PI * frequency_hz * i as f64 / sample_rate_hz).sin();
            let y = filter.tick(x);
            if i > n / 2 {
                peak = peak.max(y.abs());
            }
        }
        peak
    }

    #[test]
    fn single_resonance_has_its_gain_at_centre_and_rejects_far_away() {
        let sample_rate_hz = 48_000.0;
        let resonance = BodyResonance {
            frequency_hz: 500.0,
            quality: 10.0,
            gain_per_n: 0.7,
        };
        let mut filter = BodyFilter::new(&[resonance], sample_rate_hz);
        let at_centre = steady_gain(&mut filter, 500.0, sample_rate_hz);
        assert!((at_centre - 0.7).abs() < 2e-3, "{at_centre}");
        // Two octaves away a Q = 10 band-pass is down by 1/√(1 + Q²(4 − 1/4)²) ≈ 0.0266.
        let far = steady_gain(&mut filter, 2000.0, sample_rate_hz);
        let expected = 0.7 / (1.0 + 100.0 * (3.75f64).powi(2)).sqrt();
        assert!((far - expected).abs() < 2e-3, "{far} vs {expected}");
    }
}
