//! Shared measurement helpers for the bowed-voice tests: run a voice at steady controls and
//! measure the stick/slip pattern at the bow and the period.
#![allow(dead_code)]

use javari_core::bowed::{
    BowTableString, BowedCapacity, BowedOutput, BowedString, BowedVoice, ContactState,
    StringConstants,
};

/// Steady bowing controls.
#[derive(Clone, Copy, Debug)]
pub struct Controls {
    pub sample_rate_hz: f64,
    pub pitch_hz: f64,
    pub bow_position: f64,
    pub bow_force_n: f64,
    pub bow_velocity_m_s: f64,
}

impl Controls {
    pub fn violin(bow_position: f64, bow_force_n: f64) -> Self {
        Self {
            sample_rate_hz: 44_100.0,
            pitch_hz: 220.0,
            bow_position,
            bow_force_n,
            bow_velocity_m_s: 0.1,
        }
    }

    pub fn period_samples(&self) -> f64 {
        self.sample_rate_hz / self.pitch_hz
    }
}

pub fn violin_string(controls: &Controls) -> BowedString {
    let mut voice = BowedString::new(BowedCapacity::default(), StringConstants::violin_a());
    apply(&mut voice, controls);
    voice
}

pub fn bow_table_string(controls: &Controls) -> BowTableString {
    let mut voice = BowTableString::new(BowedCapacity::default(), StringConstants::violin_a());
    apply(&mut voice, controls);
    voice
}

pub fn apply<V: BowedVoice>(voice: &mut V, controls: &Controls) {
    voice.prepare(controls.sample_rate_hz).unwrap();
    voice.set_pitch_hz(controls.pitch_hz);
    voice.set_bow_position(controls.bow_position);
    voice.set_bow_velocity_m_s(controls.bow_velocity_m_s);
    voice.set_bow_force_n(controls.bow_force_n);
    voice.set_body_enabled(false);
}

/// Samples of one steady run: contact state (rounded-corner voice only) and outputs.
pub struct Run {
    pub sticking: Vec<bool>,
    pub outputs: Vec<BowedOutput>,
}

/// Run the rounded-corner voice for `seconds` and keep the last `keep_periods` periods.
pub fn run_string(
    voice: &mut BowedString,
    controls: &Controls,
    seconds: f64,
    keep_periods: f64,
) -> Run {
    let total = (controls.sample_rate_hz * seconds) as usize;
    let keep = (keep_periods * controls.period_samples()).round() as usize;
    let mut run = Run {
        sticking: Vec::with_capacity(keep),
        outputs: Vec::with_capacity(keep),
    };
    for i in 0..total {
        let output = voice.next_sample();
        if i >= total - keep {
            run.sticking
                .push(voice.last_bow_point().state == ContactState::Sticking);
            run.outputs.push(output);
        }
    }
    run
}

/// Run any voice and keep the outputs of the last `keep_periods` periods.
pub fn run_outputs<V: BowedVoice>(
    voice: &mut V,
    controls: &Controls,
    seconds: f64,
    keep_periods: f64,
) -> Vec<BowedOutput> {
    let total = (controls.sample_rate_hz * seconds) as usize;
    let keep = (keep_periods * controls.period_samples()).round() as usize;
    let mut outputs = Vec::with_capacity(keep);
    for i in 0..total {
        let output = voice.next_sample();
        if i >= total - keep {
            outputs.push(output);
        }
    }
    outputs
}

/// The stick/slip pattern of a run.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Complete slip episodes per nominal period.
    pub slips_per_period: f64,
    /// Lengths of complete sticking runs, samples.
    pub stick_runs: Vec<usize>,
    /// Lengths of complete slipping runs, samples.
    pub slip_runs: Vec<usize>,
    /// Sample indices where a slip begins.
    pub slip_onsets: Vec<usize>,
}

pub fn pattern(sticking: &[bool], period_samples: f64) -> Pattern {
    let mut stick_runs = Vec::new();
    let mut slip_runs = Vec::new();
    let mut slip_onsets = Vec::new();
    // Runs that touch either end of the window are incomplete and not counted.
    let mut run_start: Option<usize> = None;
    for i in 1..sticking.len() {
        if sticking[i] != sticking[i - 1] {
            if let Some(start) = run_start {
                let length = i - start;
                if sticking[i - 1] {
                    stick_runs.push(length);
                } else {
                    slip_runs.push(length);
                }
            }
            if !sticking[i] {
                slip_onsets.push(i);
            }
            run_start = Some(i);
        }
    }
    Pattern {
        slips_per_period: slip_onsets.len() as f64 * period_samples / sticking.len() as f64,
        stick_runs,
        slip_runs,
        slip_onsets,
    }
}

impl Pattern {
    /// Largest deviation of a sticking run from (1 − β) P, as a fraction of P (∞ if none).
    pub fn worst_stick_error(&self, bow_position: f64, period_samples: f64) -> f64 {
        let target = (1.0 - bow_position) * period_samples;
        worst(&self.stick_runs, target, period_samples)
    }

    /// Largest deviation of a slipping run from β P, as a fraction of P (∞ if none).
    pub fn worst_slip_error(&self, bow_position: f64, period_samples: f64) -> f64 {
        worst(
            &self.slip_runs,
            bow_position * period_samples,
            period_samples,
        )
    }

    /// Exactly one slip per period: one slip onset per period (±1 over the window, which need
    /// not start on a period boundary) and every sticking run within 10 % of P of (1 − β) P,
    /// so no period holds a second slip.
    pub fn has_single_slip(&self, bow_position: f64, period_samples: f64) -> bool {
        (self.slips_per_period - 1.0).abs() < 0.03
            && self.worst_stick_error(bow_position, period_samples) <= 0.1
    }

    /// Helmholtz motion: one slip per period, every stick (1 − β) P and every slip β P within
    /// 2 % of P.
    pub fn is_helmholtz(&self, bow_position: f64, period_samples: f64) -> bool {
        (self.slips_per_period - 1.0).abs() < 0.03
            && self.worst_stick_error(bow_position, period_samples) <= 0.02
            && self.worst_slip_error(bow_position, period_samples) <= 0.02
    }

    /// Mean period from the first to the last slip onset, samples.
    pub fn mean_period(&self) -> f64 {
        let n = self.slip_onsets.len();
        (self.slip_onsets[n - 1] - self.slip_onsets[0]) as f64 / (n - 1) as f64
    }
}

fn worst(runs: &[usize], target: f64, period_samples: f64) -> f64 {
    if runs.is_empty() {
        return f64::INFINITY;
    }
    runs.iter()
        .map(|&r| (r as f64 - target).abs() / period_samples)
        .fold(0.0, f64::max)
}

/// Period of a sawtooth-like signal, samples: crossings of its mean in the direction of its
/// steepest edge (the Helmholtz flyback), linearly interpolated, at most one per half of the
/// nominal period so that ripple near the mean is not counted.
pub fn period_by_crossings(signal: &[f64], nominal_period: f64) -> f64 {
    let mean = signal.iter().sum::<f64>() / signal.len() as f64;
    let steepest = signal
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(0.0_f64, |a, d| if d.abs() > a.abs() { d } else { a });
    let direction = if steepest < 0.0 { -1.0 } else { 1.0 };
    let mut crossings: Vec<f64> = Vec::new();
    for i in 1..signal.len() {
        let a = direction * (signal[i - 1] - mean);
        let b = direction * (signal[i] - mean);
        if a < 0.0 && b >= 0.0 {
            let t = i as f64 - 1.0 + a / (a - b);
            if crossings
                .last()
                .is_none_or(|last| t - last > 0.5 * nominal_period)
            {
                crossings.push(t);
            }
        }
    }
    let n = crossings.len();
    (crossings[n - 1] - crossings[0]) / (n - 1) as f64
}

pub fn cents(measured_period: f64, target_period: f64) -> f64 {
    1200.0 * (target_period / measured_period).log2()
}

/// Fundamental frequency of `signal` (Hz) near `guess_hz`: the peak of the Hann-windowed
/// discrete-time Fourier transform, searched on a 0.05-cent grid within ±60 cents and refined
/// by a parabola through the three highest points.
pub fn fundamental_hz(signal: &[f64], sample_rate_hz: f64, guess_hz: f64) -> f64 {
    let n = signal.len();
    let mean = signal.iter().sum::<f64>() / n as f64;
    let windowed: Vec<f64> = signal
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let w = 0.5 - 0.5 * (2.0 * core::f64::consts::PI * i as f64 / (n - 1) as f64).cos();
            w * (x - mean)
        })
        .collect();
    let power = |cents: f64| {
        let f = guess_hz * (cents / 1200.0).exp2();
        let step = 2.0 * core::f64::consts::PI * f / sample_rate_hz;
        let (mut re, mut im) = (0.0, 0.0);
        let (sin_step, cos_step) = step.sin_cos();
        let (mut s, mut c) = (0.0_f64, 1.0_f64);
        for x in &windowed {
            re += x * c;
            im -= x * s;
            let next_c = c * cos_step - s * sin_step;
            s = s * cos_step + c * sin_step;
            c = next_c;
        }
        re * re + im * im
    };
    let grid = 0.05;
    let mut best = (-60.0, power(-60.0));
    let mut k = -60.0 + grid;
    while k <= 60.0 {
        let p = power(k);
        if p > best.1 {
            best = (k, p);
        }
        k += grid;
    }
    let (left, right) = (power(best.0 - grid), power(best.0 + grid));
    let denominator = left - 2.0 * best.1 + right;
    let offset = if denominator != 0.0 {
        0.5 * grid * (left - right) / denominator
    } else {
        0.0
    };
    guess_hz * ((best.0 + offset) / 1200.0).exp2()
}
