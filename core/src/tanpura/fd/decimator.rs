//! Anti-aliasing decimation from the oversampled internal rate to the output rate.
//!
//! The tanpura runs at `M` times the output rate (seed 000: M = 4, Δt = 1/176 400 s). Before
//! keeping every M-th sample, everything that would fold back into the audible band must go:
//! content near `k·f_out ± f` lands on `f`. With a passband up to `f_p = 0.45 f_out` (20 kHz at
//! 44.1 kHz), the band to reject starts at `f_out − f_p`; a linear-phase Kaiser-windowed sinc
//! with its cut-off at `f_out/2` and ≥ 90 dB stop-band attenuation does it. Kaiser's formula
//! sizes the filter: `taps ≈ (A − 7.95)/(14.36 Δf/f_in) + 1` with `Δf = f_out − 2f_p`. For M = 4
//! that is 231 taps (rounded up to odd length), evaluated once per output sample (a polyphase decimator computes only the
//! outputs it keeps).

/// Stop-band attenuation of the decimation filter, dB.
pub const STOPBAND_ATTENUATION_DB: f64 = 90.0;
/// Passband edge as a fraction of the output rate.
pub const PASSBAND_EDGE: f64 = 0.45;

/// A decimating FIR filter, allocation-free after construction.
#[derive(Debug, Clone)]
pub struct Decimator {
    factor: usize,
    taps: Vec<f64>,
    /// The last `taps.len()` inputs, stored twice so that a contiguous window always exists.
    history: Vec<f64>,
    write: usize,
    phase: usize,
}

/// The zeroth-order modified Bessel function of the first kind, by its power series.
fn bessel_i0(x: f64) -> f64 {
    let half = 0.5 * x;
    let mut term = 1.0;
    let mut sum = 1.0;
    for k in 1..64 {
        let ratio = half / k as f64;
        term *= ratio * ratio;
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
    }
    sum
}

/// Kaiser-windowed sinc low-pass taps for decimation by `factor`, DC gain 1.
pub fn design_taps(factor: usize) -> Vec<f64> {
    if factor <= 1 {
        return vec![1.0];
    }
    let attenuation = STOPBAND_ATTENUATION_DB;
    let transition = (1.0 - 2.0 * PASSBAND_EDGE) / factor as f64; // Δf / f_in
    let mut count = ((attenuation - 7.95) / (14.36 * transition)).ceil() as usize + 1;
    if count.is_multiple_of(2) {
        count += 1; // odd length: a centre tap, integer group delay
    }
    let beta = 0.1102 * (attenuation - 8.7);
    let cutoff = 0.5 / factor as f64; // f_out/2 over f_in, in cycles per sample
    let centre = (count - 1) as f64 / 2.0;
    let mut taps: Vec<f64> = (0..count)
        .map(|i| {
            let t = i as f64 - centre;
            let sinc = if t == 0.0 {
                2.0 * cutoff
            } else {
                (2.0 * std::f64::consts::PI * cutoff * t).sin() / (std::f64::consts::PI * t)
            };
            let r = t / centre;
            let window = bessel_i0(beta * (1.0 - r * r).max(0.0).sqrt()) / bessel_i0(beta);
            sinc * window
        })
        .collect();
    let sum: f64 = taps.iter().sum();
    for tap in &mut taps {
        *tap /= sum;
    }
    taps
}

impl Decimator {
    /// A decimator by `factor` (1 passes samples through). Allocates.
    pub fn new(factor: usize) -> Self {
        let taps = design_taps(factor.max(1));
        let length = taps.len();
        Self {
            factor: factor.max(1),
            taps,
            history: vec![0.0; 2 * length],
            write: 0,
            phase: 0,
        }
    }

    pub fn factor(&self) -> usize {
        self.factor
    }

    pub fn taps(&self) -> &[f64] {
        &self.taps
    }

    /// Group delay in output samples.
    pub fn delay_output_samples(&self) -> f64 {
        (self.taps.len() - 1) as f64 / 2.0 / self.factor as f64
    }

    pub fn reset(&mut self) {
        self.history.fill(0.0);
        self.write = 0;
        self.phase = 0;
    }

    /// Feeds one internal-rate sample; returns an output sample on every `factor`-th call.
    #[inline]
    pub fn push(&mut self, sample: f64) -> Option<f64> {
        let length = self.taps.len();
        self.history[self.write] = sample;
        self.history[self.write + length] = sample;
        self.write = if self.write + 1 == length {
            0
        } else {
            self.write + 1
        };
        self.phase += 1;
        if self.phase < self.factor {
            return None;
        }
        self.phase = 0;
        // history[write..write + length] holds the inputs oldest first; the taps are symmetric.
        let window = &self.history[self.write..self.write + length];
        Some(window.iter().zip(&self.taps).map(|(x, h)| x * h).sum())
    }
}

/// A whole render at the output rate: calls `next_internal` (one internal-rate step, returning
/// its sample) `factor` times per output sample through a fresh [`Decimator`] by `factor`, for
/// `samples` output samples. Allocates: for offline tools (the bench, the examples, tests), not
/// the audio thread.
pub fn render_decimated(
    factor: usize,
    samples: usize,
    mut next_internal: impl FnMut() -> f64,
) -> Vec<f64> {
    let mut decimator = Decimator::new(factor);
    let mut output = Vec::with_capacity(samples);
    while output.len() < samples {
        if let Some(sample) = decimator.push(next_internal()) {
            output.push(sample);
        }
    }
    output
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady-state gain of the taps at `frequency` (cycles per input sample).
    fn gain(taps: &[f64], frequency: f64) -> f64 {
        let (mut re, mut im) = (0.0, 0.0);
        for (i, h) in taps.iter().enumerate() {
            let phase = 2.0 * std::f64::consts::PI * frequency * i as f64;
            re += h * phase.cos();
            im += h * phase.sin();
        }
        (re * re + im * im).sqrt()
    }

    #[test]
    fn passband_is_flat_and_aliasing_band_is_rejected() {
        for factor in [2, 4, 8] {
            let taps = design_taps(factor);
            let output_rate = 1.0 / factor as f64; // in cycles per input sample
            for k in 0..=20 {
                let f = PASSBAND_EDGE * output_rate * k as f64 / 20.0;
                let g = gain(&taps, f);
                assert!((g - 1.0).abs() < 1e-3, "M={factor} passband {f}: {g}");
            }
            // Everything that folds into the passband is at least 85 dB down.
            for k in 0..=200 {
                let f = (1.0 - PASSBAND_EDGE) * output_rate
                    + (0.5 - (1.0 - PASSBAND_EDGE) * output_rate) * k as f64 / 200.0;
                let g = gain(&taps, f);
                assert!(g < 10f64.powf(-85.0 / 20.0), "M={factor} stopband {f}: {g}");
            }
        }
    }

    #[test]
    fn four_times_oversampling_uses_231_taps() {
        assert_eq!(design_taps(4).len(), 231);
    }

    #[test]
    fn dc_passes_with_unit_gain_after_the_filter_fills() {
        let mut decimator = Decimator::new(4);
        let mut last = 0.0;
        for _ in 0..4 * 400 {
            if let Some(y) = decimator.push(0.25) {
                last = y;
            }
        }
        assert!((last - 0.25).abs() < 1e-12);
    }

    #[test]
    fn factor_one_passes_samples_through() {
        let mut decimator = Decimator::new(1);
        assert_eq!(decimator.push(0.5), Some(0.5));
        assert_eq!(decimator.push(-0.125), Some(-0.125));
    }
}
