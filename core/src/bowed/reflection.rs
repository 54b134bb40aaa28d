//! Reflection functions of the bridge side and the nut/finger side
//! (`shared/notes/bowed-model.md`, "Rounded-corner model"; Woodhouse 1993, section 3.1, eq. 21–23).
//!
//! The incoming velocity wave at the bow is the convolution of the past outgoing waves with a
//! reflection function that lumps propagation to the end of the string, the end's reflection and
//! the way back:
//!
//! ```text
//!     i(n) = Σ_k r(k) o(n − k)
//! ```
//!
//! r is centred on the round-trip delay D: 2βL/c on the bridge side, 2(1 − β)L/c on the nut
//! side. With L the vibrating length and c = 2 L f₀, these are β/f₀ and (1 − β)/f₀, so the two
//! round trips add up to exactly one period.
//!
//! Shape: a smooth inverted pulse −A·p(t − D), p a raised cosine (cos² over its full width w,
//! unit area), with A the area (just under 1: the loss per round trip) and w the width (how
//! rounded the Helmholtz corner is). It is sampled on the integer grid around ⌊D⌋, where its
//! sampled values are symmetric, and then split between ⌊D⌋ and ⌊D⌋ + 1 by linear interpolation
//! with the fractional part of D. Both steps keep the centroid (the low-frequency group delay,
//! which sets the pitch) at exactly D, and the total area at exactly A.
//!
//! Raman's model is the limiting case w → 0: a single tap −A = −λ at D (two taps when D is
//! fractional). Woodhouse's test case [σ, λ, σ] of eq. 22 is a raised cosine of width 4 samples
//! (cos²(π/4) = 1/2 gives σ = λ/2 before normalisation; any [σ, λ, σ] can be set directly with
//! [`ReflectionFunction::set_taps`]).

/// Parameters of one reflection function's pulse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectionPulse {
    /// Full width of the raised-cosine pulse, s (≥ 0; 0 is Raman's single tap).
    pub width_s: f64,
    /// Area A of the pulse (dimensionless, 0 to 1): the reflection's amplitude at low
    /// frequency, −A. 1 − A is the energy-free loss parameter ε of Woodhouse's Raman model.
    pub area: f64,
}

/// A reflection function with the history of outgoing waves it convolves.
///
/// `new()` sizes the ring buffer and the tap storage for the longest delay and widest pulse the
/// voice can ask for; `set_*` and the per-sample methods never allocate.
#[derive(Clone, Debug)]
pub struct ReflectionFunction {
    history: Vec<f64>,
    mask: usize,
    write: usize,
    taps: Vec<f64>,
    tap_count: usize,
    first_tap_delay: usize,
    delay_samples: f64,
}

impl ReflectionFunction {
    /// Capacity for a centre delay up to `max_delay_samples` and a pulse up to
    /// `max_width_samples` wide.
    pub fn new(max_delay_samples: f64, max_width_samples: f64) -> Self {
        let max_taps = max_width_samples.max(0.0).ceil() as usize + 3;
        let longest = max_delay_samples.max(1.0).ceil() as usize + max_taps + 2;
        let size = longest.next_power_of_two();
        let mut taps = vec![0.0; max_taps];
        taps[0] = -1.0;
        Self {
            history: vec![0.0; size],
            mask: size - 1,
            write: 0,
            taps,
            tap_count: 1,
            first_tap_delay: 1,
            delay_samples: 1.0,
        }
    }

    /// Largest tap count this function can hold.
    pub fn max_taps(&self) -> usize {
        self.taps.len()
    }

    /// Longest delay (samples) the history can serve for a pulse of `tap_count` taps.
    pub fn max_delay_samples(&self) -> f64 {
        (self.history.len() - self.taps.len() - 2) as f64
    }

    /// Centre the pulse on `delay_samples` (≥ 1) with full width `width_samples` and area `area`.
    ///
    /// Corner cases, clamped rather than refused because this runs on the audio thread:
    /// a delay below 1 sample is raised to 1 (the bow cannot hear its own output within the
    /// sample); a pulse that would reach below 1 sample of delay is narrowed to fit, so at tiny
    /// β the bridge-side pulse degrades gracefully to Raman's tap; a width beyond capacity is
    /// capped at capacity; a delay beyond capacity is capped.
    pub fn set_pulse(&mut self, delay_samples: f64, width_samples: f64, area: f64) {
        let delay = if delay_samples.is_finite() {
            delay_samples.clamp(1.0, self.max_delay_samples())
        } else {
            1.0
        };
        let whole = delay.floor();
        let fraction = delay - whole;
        let whole_delay = whole as usize;

        // Half-count K of the symmetric integer-grid pulse: taps at |k| < w/2, k = −K..K.
        let half_width = if width_samples.is_finite() {
            0.5 * width_samples.max(0.0)
        } else {
            0.0
        };
        let mut half_count = if half_width > 1.0 {
            (half_width.ceil() as usize).saturating_sub(1)
        } else {
            0
        };
        // 2K + 2 taps must fit, and the earliest tap must be at delay ≥ 1.
        let capacity_half = (self.taps.len() - 2) / 2;
        half_count = half_count.min(capacity_half).min(whole_delay - 1);

        let symmetric_count = 2 * half_count + 1;
        let mut base_sum = 0.0;
        for index in 0..symmetric_count {
            let k = index as f64 - half_count as f64;
            let value = if half_count == 0 {
                1.0
            } else {
                let phase = core::f64::consts::PI * k / (2.0 * half_width);
                let c = phase.cos();
                c * c
            };
            self.taps[index] = value;
            base_sum += value;
        }
        let area = if area.is_finite() { area } else { 0.0 };
        let gain = -area / base_sum;
        // Linear interpolation towards one sample more delay: tap j gets (1 − φ) base[j] +
        // φ base[j − 1]. Walk backwards so base[j − 1] is still unmodified when read.
        self.taps[symmetric_count] = 0.0;
        for index in (0..=symmetric_count).rev() {
            let current = if index < symmetric_count {
                self.taps[index]
            } else {
                0.0
            };
            let previous = if index > 0 { self.taps[index - 1] } else { 0.0 };
            self.taps[index] = gain * ((1.0 - fraction) * current + fraction * previous);
        }
        self.tap_count = symmetric_count + 1;
        self.first_tap_delay = whole_delay - half_count;
        self.delay_samples = delay;
    }

    /// Set the taps directly: `taps[j]` applies at delay `first_tap_delay + j` (≥ 1). For
    /// reproducing a paper's discrete reflection function such as eq. 22's [σ, λ, σ] (with its
    /// sign). Extra taps beyond capacity are ignored; the centroid becomes the reported delay.
    pub fn set_taps(&mut self, first_tap_delay: usize, taps: &[f64]) {
        let count = taps.len().min(self.taps.len()).max(1);
        let first = first_tap_delay.max(1);
        let mut sum = 0.0;
        let mut moment = 0.0;
        for j in 0..count {
            let value = taps.get(j).copied().unwrap_or(0.0);
            self.taps[j] = value;
            sum += value;
            moment += value * (first + j) as f64;
        }
        self.tap_count = count;
        self.first_tap_delay = first;
        self.delay_samples = if sum != 0.0 {
            moment / sum
        } else {
            first as f64
        };
    }

    /// The active taps, earliest delay first.
    pub fn taps(&self) -> &[f64] {
        &self.taps[..self.tap_count]
    }

    /// Delay of the first active tap, samples.
    pub fn first_tap_delay(&self) -> usize {
        self.first_tap_delay
    }

    /// Centre (centroid) delay of the pulse, samples.
    pub fn delay_samples(&self) -> f64 {
        self.delay_samples
    }

    /// i(n) = Σ_k r(k) o(n − k), over the outgoing waves pushed before this sample.
    #[inline]
    pub fn incoming(&self) -> f64 {
        let mut sum = 0.0;
        let mut read = self.write.wrapping_sub(self.first_tap_delay) & self.mask;
        for &tap in &self.taps[..self.tap_count] {
            sum += tap * self.history[read];
            // Each further tap reaches one sample further into the past.
            read = read.wrapping_sub(1) & self.mask;
        }
        sum
    }

    /// The outgoing wave of `delay_samples` ago (≥ 1), linearly interpolated.
    #[inline]
    pub fn outgoing_delayed(&self, delay_samples: f64) -> f64 {
        let delay = delay_samples.clamp(1.0, self.max_delay_samples());
        let whole = delay.floor();
        let fraction = delay - whole;
        let newer = self.history[self.write.wrapping_sub(whole as usize) & self.mask];
        let older = self.history[self.write.wrapping_sub(whole as usize + 1) & self.mask];
        newer + fraction * (older - newer)
    }

    /// Store this sample's outgoing wave.
    #[inline]
    pub fn push(&mut self, outgoing: f64) {
        self.history[self.write] = outgoing;
        self.write = (self.write + 1) & self.mask;
    }

    /// Zero the history (taps are kept).
    pub fn reset(&mut self) {
        self.history.iter_mut().for_each(|x| *x = 0.0);
        self.write = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn centroid(r: &ReflectionFunction) -> f64 {
        let sum: f64 = r.taps().iter().sum();
        let moment: f64 = r
            .taps()
            .iter()
            .enumerate()
            .map(|(j, t)| t * (r.first_tap_delay() + j) as f64)
            .sum();
        moment / sum
    }

    #[test]
    fn raman_limit_is_a_single_inverted_tap() {
        let mut r = ReflectionFunction::new(100.0, 20.0);
        r.set_pulse(37.0, 0.0, 0.99);
        let nonzero: Vec<_> = r.taps().iter().filter(|t| **t != 0.0).collect();
        assert_eq!(nonzero.len(), 1);
        assert_eq!(*nonzero[0], -0.99);
        // An impulse pushed now returns −λ exactly 37 samples later and at no other time.
        r.push(1.0);
        for n in 1..60 {
            let i = r.incoming();
            if n == 37 {
                assert_eq!(i, -0.99);
            } else {
                assert_eq!(i, 0.0, "sample {n}");
            }
            r.push(0.0);
        }
    }

    #[test]
    fn pulse_area_and_centroid_are_exact_for_fractional_delays() {
        let mut r = ReflectionFunction::new(500.0, 40.0);
        for &(delay, width, area) in &[
            (10.25, 6.0, 0.97),
            (123.7, 13.3, 0.9),
            (3.5, 2.5, 0.999),
            (200.01, 40.0, 0.5),
        ] {
            r.set_pulse(delay, width, area);
            let sum: f64 = r.taps().iter().sum();
            assert!((sum + area).abs() < 1e-14, "area {sum} vs {area}");
            assert!(
                (centroid(&r) - delay).abs() < 1e-10,
                "centroid {} vs {delay}",
                centroid(&r)
            );
            assert!(r.taps().iter().all(|t| *t <= 0.0), "an inverted pulse");
        }
    }

    #[test]
    fn width_four_samples_gives_woodhouse_sigma_lambda_sigma_shape() {
        // cos²(π k / 4) at k = −1, 0, 1 is [1/2, 1, 1/2]; normalised to area A = 1:
        // σ = 1/4, λ = 1/2, λ + 2σ = 1 (eq. 23).
        let mut r = ReflectionFunction::new(100.0, 20.0);
        r.set_pulse(20.0, 4.0, 1.0);
        let t = r.taps();
        assert!((t[0] + 0.25).abs() < 1e-15);
        assert!((t[1] + 0.5).abs() < 1e-15);
        assert!((t[2] + 0.25).abs() < 1e-15);
        assert_eq!(t[3], 0.0);
        assert_eq!(r.first_tap_delay(), 19);
    }

    #[test]
    fn pulse_narrows_instead_of_reaching_the_present() {
        let mut r = ReflectionFunction::new(100.0, 20.0);
        r.set_pulse(2.3, 10.0, 0.95);
        assert!(r.first_tap_delay() >= 1);
        assert!((centroid(&r) - 2.3).abs() < 1e-12);
        r.set_pulse(0.2, 10.0, 0.95);
        assert_eq!(r.first_tap_delay(), 1);
        assert!((r.delay_samples() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn explicit_sigma_lambda_sigma_taps_convolve_as_in_eq_22() {
        // Woodhouse's test case: [σ, λ, σ] = [0.05, 0.90, 0.05] (eq. 23: λ + 2σ = 1), applied
        // with the inverting sign of eq. 22, centred on a 6-sample round trip.
        let mut r = ReflectionFunction::new(50.0, 8.0);
        r.set_taps(5, &[-0.05, -0.90, -0.05]);
        assert_eq!(r.first_tap_delay(), 5);
        assert!((r.delay_samples() - 6.0).abs() < 1e-12);
        // A unit outgoing impulse comes back as −σ, −λ, −σ at delays 5, 6, 7.
        r.push(1.0);
        let mut echoes = Vec::new();
        for _ in 1..10 {
            echoes.push(r.incoming());
            r.push(0.0);
        }
        assert_eq!(
            echoes,
            vec![0.0, 0.0, 0.0, 0.0, -0.05, -0.90, -0.05, 0.0, 0.0]
        );
    }

    #[test]
    fn delayed_read_interpolates_linearly() {
        let mut r = ReflectionFunction::new(16.0, 2.0);
        for n in 0..10 {
            r.push(n as f64);
        }
        // Last pushed 9 is 1 sample ago; 2.5 samples ago lies between 8 and 7.
        assert_eq!(r.outgoing_delayed(1.0), 9.0);
        assert!((r.outgoing_delayed(2.5) - 7.5).abs() < 1e-15);
    }
}
