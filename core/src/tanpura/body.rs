//! The tanpura's body and its radiation: a bank of resonances between the bridge and the
//! listener, driven by the total bridge force of all strings.
//!
//! Each resonance k is a damped oscillator driven by the bridge force F, with its frequency
//! `f_k`, its quality factor `Q_k` (decay `σ_k = π f_k / Q_k`) and its gain `G_k`, the peak of its
//! force-to-output response: continuous-time
//!
//! ```text
//! H_k(s) = G_k · (2σ_k s) / (s² + 2σ_k s + ω_k²),      output = Σ_k H_k * F,
//! ```
//!
//! a band-pass whose magnitude is `G_k` at `ω_k` (the mechanical reading: the velocity of a unit
//! stiffness oscillator, scaled). Each is advanced by the exact two-pole recursion in mid-point
//! form of the modal string (`docs/modal-tanpura.md`, eq. M1–M2, `modal/modes.rs`): the poles sit
//! exactly at `e^{(−σ_k ± iω_d,k)Δt}` at any sample rate, and with the oscillator's energy
//! `E_k = r_k²/2 + (a_k/2b_k) p_k²` every step satisfies `ΔE_k = s_k F − ((1 − e^{−2σΔt})/2b_k) s_k²`
//! exactly: the body only ever loses the energy the force puts in (passive). The output is the
//! mid-point velocity `s_k/Δt`, weighted so that the discrete response at `f_k` is exactly the
//! data's `G_k`.
//!
//! The body is one-way: the bridge is rigid for the strings (the seed's model), so the body
//! colours the sound without changing the strings' motion.
//!
//! Hand-written rather than a filter crate: a few dozen two-pole resonators once per sample on
//! the audio thread, allocation-free after [`Body::new`].

use crate::tanpura::modal::modes::recursion_coefficients;
use std::f64::consts::PI;

/// The tanpura's body, bridge force to radiated sound, fitted by `scripts/fit_body.py` to the
/// impulse response van Walstijn, Bridges & Mehes measured (DAFx-16, section 3.3 and Fig. 5:
/// impact hammer at the bridge, microphone at 80 cm, 2048 samples at 44.1 kHz, published with the
/// paper as `hb.wav`). The paper filters the bridge force with that response truncated to a
/// 2048-tap FIR and notes that a parallel second-order (IIR) form would be far cheaper; this is
/// that form, restricted to band-pass sections so that each is a passive oscillator. The measured
/// body is a high-pass to a first approximation (the paper's words): about 35 dB weaker below
/// 300 Hz than at its 0.7 and 1.5 kHz peaks, so the strings' fundamentals reach the listener
/// mostly through their overtones. The gains are scaled so that the body's mean power gain over
/// 100 Hz–10 kHz is 1.
///
/// Eighteen resonances; the fit's RMS error is 4.5 dB over 60 Hz–16 kHz (1/12-octave smoothed).
pub const TANPURA_BODY: [BodyResonance; 18] = [
    BodyResonance {
        frequency_hz: 716.9,
        quality: 10.72,
        gain: 2.9719,
    },
    BodyResonance {
        frequency_hz: 1153.5,
        quality: 6.45,
        gain: 0.9790,
    },
    BodyResonance {
        frequency_hz: 1525.9,
        quality: 11.86,
        gain: 2.6477,
    },
    BodyResonance {
        frequency_hz: 1675.0,
        quality: 3.74,
        gain: 0.4307,
    },
    BodyResonance {
        frequency_hz: 1788.0,
        quality: 4.15,
        gain: 1.4534,
    },
    BodyResonance {
        frequency_hz: 2134.6,
        quality: 11.86,
        gain: 0.5361,
    },
    BodyResonance {
        frequency_hz: 2432.3,
        quality: 9.79,
        gain: 2.1031,
    },
    BodyResonance {
        frequency_hz: 3042.4,
        quality: 13.40,
        gain: 0.9023,
    },
    BodyResonance {
        frequency_hz: 3565.0,
        quality: 11.86,
        gain: 0.5368,
    },
    BodyResonance {
        frequency_hz: 4138.7,
        quality: 13.28,
        gain: 1.0634,
    },
    BodyResonance {
        frequency_hz: 5081.2,
        quality: 13.40,
        gain: 1.7732,
    },
    BodyResonance {
        frequency_hz: 7876.2,
        quality: 3.76,
        gain: 0.2960,
    },
    BodyResonance {
        frequency_hz: 8974.7,
        quality: 10.82,
        gain: 0.4723,
    },
    BodyResonance {
        frequency_hz: 10131.4,
        quality: 8.85,
        gain: 0.3925,
    },
    BodyResonance {
        frequency_hz: 11761.7,
        quality: 13.28,
        gain: 0.3004,
    },
    BodyResonance {
        frequency_hz: 13402.0,
        quality: 13.28,
        gain: 0.4319,
    },
    BodyResonance {
        frequency_hz: 13654.3,
        quality: 13.53,
        gain: 0.3552,
    },
    BodyResonance {
        frequency_hz: 15558.6,
        quality: 13.53,
        gain: 1.0476,
    },
];

/// One resonance of the body's force-to-radiation response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyResonance {
    pub frequency_hz: f64,
    /// Q = f / bandwidth (−3 dB).
    pub quality: f64,
    /// Peak gain of the resonance's force-to-output response (output in newtons of equivalent
    /// bridge force, so that the engine's full-scale mapping applies unchanged).
    pub gain: f64,
}

/// |S/F| of the recursion (M1) with unit stiffness at the normalised frequency `theta` (rad per
/// sample): `b / (1 − a/(z + 1) + b/(z − 1))`, `z = e^{iθ}`.
fn step_response_magnitude(a: f64, b: f64, theta: f64) -> f64 {
    // 1/(z + 1) and 1/(z − 1) for z on the unit circle.
    let (cos, sin) = (theta.cos(), theta.sin());
    let reciprocal = |re: f64, im: f64| {
        let norm = re * re + im * im;
        (re / norm, -im / norm)
    };
    let (plus_re, plus_im) = reciprocal(cos + 1.0, sin);
    let (minus_re, minus_im) = reciprocal(cos - 1.0, sin);
    let re = 1.0 - a * plus_re + b * minus_re;
    let im = -a * plus_im + b * minus_im;
    b / (re * re + im * im).sqrt()
}

/// The resonators of one body; allocation-free after [`Body::new`].
#[derive(Debug, Clone)]
pub struct Body {
    resonances: Vec<BodyResonance>,
    sample_rate_hz: f64,
    /// Per resonance: the recursion coefficients, the output weight of s, the loss factor.
    a: Vec<f64>,
    b: Vec<f64>,
    output_weight: Vec<f64>,
    loss_factor: Vec<f64>,
    kinetic_factor: Vec<f64>,
    /// The state r, p of each oscillator (unit stiffness: r is the displacement per newton).
    displacement: Vec<f64>,
    velocity: Vec<f64>,
    /// Book of the force's work and the losses, for the passivity tests.
    work_j: f64,
    losses_j: f64,
}

impl Body {
    /// A body with these resonances at this sample rate; resonances at or above 0.45 of the
    /// sample rate are kept silent (their weight is zero). Allocates.
    pub fn new(resonances: &[BodyResonance], sample_rate_hz: f64) -> Self {
        let count = resonances.len();
        let zeros = || vec![0.0; count];
        let mut body = Self {
            resonances: resonances.to_vec(),
            sample_rate_hz,
            a: zeros(),
            b: zeros(),
            output_weight: zeros(),
            loss_factor: zeros(),
            kinetic_factor: zeros(),
            displacement: zeros(),
            velocity: zeros(),
            work_j: 0.0,
            losses_j: 0.0,
        };
        body.set_sample_rate(sample_rate_hz);
        body
    }

    /// Recomputes the coefficients for a sample rate and silences the body. Allocation-free.
    pub fn set_sample_rate(&mut self, sample_rate_hz: f64) {
        let rate = if sample_rate_hz.is_finite() && sample_rate_hz > 0.0 {
            sample_rate_hz
        } else {
            44_100.0
        };
        self.sample_rate_hz = rate;
        let time_step = 1.0 / rate;
        for (k, resonance) in self.resonances.iter().enumerate() {
            let audible = resonance.frequency_hz > 0.0
                && resonance.frequency_hz < 0.45 * rate
                && resonance.quality > 0.5
                && resonance.gain.is_finite();
            if !audible {
                self.a[k] = 0.0;
                self.b[k] = 0.0;
                self.output_weight[k] = 0.0;
                self.loss_factor[k] = 0.0;
                self.kinetic_factor[k] = 0.0;
                continue;
            }
            let omega = 2.0 * PI * resonance.frequency_hz;
            let decay = 0.5 * omega / resonance.quality;
            let (a, b, det) = recursion_coefficients(omega, decay, time_step);
            self.a[k] = a;
            self.b[k] = b;
            self.loss_factor[k] = (1.0 - det) / (2.0 * b);
            self.kinetic_factor[k] = a / (2.0 * b);
            // The output weight makes the discrete response exactly G_k at f_k: from (M1),
            // S/F = b / (1 − a/(z + 1) + b/(z − 1)) at z = e^{iω_kΔt}.
            self.output_weight[k] =
                resonance.gain / step_response_magnitude(a, b, omega * time_step);
        }
        self.reset();
    }

    /// Silences the body and clears its books.
    pub fn reset(&mut self) {
        self.displacement.fill(0.0);
        self.velocity.fill(0.0);
        self.work_j = 0.0;
        self.losses_j = 0.0;
    }

    /// One sample: the radiated output for the bridge force `force_n` over this step.
    #[inline]
    pub fn tick(&mut self, force_n: f64) -> f64 {
        let mut output = 0.0;
        let modes = self
            .displacement
            .iter_mut()
            .zip(self.velocity.iter_mut())
            .zip(self.a.iter().zip(&self.b))
            .zip(&self.output_weight);
        for (((r, p), (&a, &b)), &weight) in modes {
            // s = a p − b r + b F (eq. M1 with unit stiffness: Ψ = 1).
            let step = a * *p - b * (*r - force_n);
            *r += step;
            *p = step - *p;
            output += weight * step;
        }
        output
    }

    /// [`Body::tick`] that also books the force's work and the losses (tests, tools).
    pub fn tick_booked(&mut self, force_n: f64) -> f64 {
        let mut output = 0.0;
        for k in 0..self.displacement.len() {
            let (a, b) = (self.a[k], self.b[k]);
            let step = a * self.velocity[k] - b * (self.displacement[k] - force_n);
            self.displacement[k] += step;
            self.velocity[k] = step - self.velocity[k];
            output += self.output_weight[k] * step;
            self.work_j += step * force_n;
            self.losses_j += self.loss_factor[k] * step * step;
        }
        output
    }

    /// Σ_k r_k²/2 + (a_k/2b_k) p_k²: the oscillators' discrete energy (unit stiffness, J per N²).
    pub fn energy_j(&self) -> f64 {
        self.displacement
            .iter()
            .zip(&self.velocity)
            .zip(&self.kinetic_factor)
            .map(|((r, p), kinetic)| 0.5 * r * r + kinetic * p * p)
            .sum()
    }

    /// The work the force has done and the losses since the last reset (from
    /// [`Body::tick_booked`]).
    pub fn work_and_losses_j(&self) -> (f64, f64) {
        (self.work_j, self.losses_j)
    }

    pub fn resonances(&self) -> &[BodyResonance] {
        &self.resonances
    }

    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RATE: f64 = 44_100.0;

    fn resonance(frequency_hz: f64, quality: f64, gain: f64) -> BodyResonance {
        BodyResonance {
            frequency_hz,
            quality,
            gain,
        }
    }

    /// |H(f)| from the impulse response (long enough to decay), by the DFT at f.
    fn response_at(body: &mut Body, frequency_hz: f64, length: usize) -> f64 {
        body.reset();
        let impulse: Vec<f64> = (0..length)
            .map(|n| body.tick(if n == 0 { 1.0 } else { 0.0 }))
            .collect();
        let (mut re, mut im) = (0.0, 0.0);
        for (n, value) in impulse.iter().enumerate() {
            let phase = 2.0 * PI * frequency_hz * n as f64 / RATE;
            re += value * phase.cos();
            im -= value * phase.sin();
        }
        (re * re + im * im).sqrt()
    }

    #[test]
    fn each_resonance_peaks_at_its_frequency_with_its_gain() {
        for (frequency, quality, gain) in [
            (110.0, 15.0, 0.8),
            (1_000.0, 40.0, 1.5),
            (6_000.0, 8.0, 0.3),
        ] {
            let mut body = Body::new(&[resonance(frequency, quality, gain)], RATE);
            let length = (20.0 * quality / frequency * RATE) as usize + 4096;
            let peak = response_at(&mut body, frequency, length);
            assert!(
                (peak / gain - 1.0).abs() < 0.02,
                "{frequency} Hz: {peak} vs {gain}"
            );
            // Half an octave away the band-pass is well below its peak.
            let away = response_at(&mut body, frequency * 1.41, length);
            assert!(away < 0.5 * gain, "{frequency} Hz: {away}");
        }
    }

    #[test]
    fn the_body_never_gives_back_more_than_the_force_put_in() {
        let resonances: Vec<BodyResonance> = (0..12)
            .map(|k| resonance(90.0 * 1.6f64.powi(k), 10.0 + 3.0 * k as f64, 1.0))
            .collect();
        let mut body = Body::new(&resonances, RATE);
        // A noisy force, then silence.
        let mut seed = 12345u64;
        let mut previous = body.energy_j();
        for n in 0..40_000 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let force = if n < 20_000 {
                ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
            } else {
                0.0
            };
            body.tick_booked(force);
            let energy = body.energy_j();
            if n >= 20_000 {
                assert!(
                    energy <= previous * (1.0 + 1e-12),
                    "energy rose without a force"
                );
            }
            previous = energy;
        }
        let (work, losses) = body.work_and_losses_j();
        let balance = body.energy_j() + losses - work;
        assert!(balance.abs() < 1e-10 * work.abs().max(1e-30), "{balance:e}");
        assert!(losses > 0.0 && losses <= work);
    }

    #[test]
    fn resonances_above_the_band_stay_silent_and_a_bad_rate_falls_back() {
        let mut body = Body::new(&[resonance(30_000.0, 10.0, 1.0)], RATE);
        assert!((0..100).all(|n| body.tick(if n == 0 { 1.0 } else { 0.0 }) == 0.0));
        let body = Body::new(&[resonance(100.0, 10.0, 1.0)], f64::NAN);
        assert_eq!(body.sample_rate_hz(), 44_100.0);
    }

    #[test]
    fn the_tanpura_body_is_audible_at_every_supported_rate() {
        for rate in [22_050.0, 44_100.0, 48_000.0, 96_000.0, 192_000.0] {
            let mut body = Body::new(&TANPURA_BODY, rate);
            let out: Vec<f64> = (0..4096)
                .map(|n| body.tick(if n == 0 { 1.0 } else { 0.0 }))
                .collect();
            assert!(out.iter().all(|v| v.is_finite()));
            assert!(out.iter().any(|v| v.abs() > 1e-6), "{rate} Hz");
        }
    }
}
