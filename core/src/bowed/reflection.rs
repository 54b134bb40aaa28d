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

use super::delay_line::{DelayCursor, DelayHistory, FractionalDelay};

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
/// `new()` sizes the history and the tap storage for the longest delay and widest pulse the
/// voice can ask for; `set_*` and the per-sample methods never allocate. What changes only with
/// the controls is prepared when they change, not per sample: the raised-cosine shape (its
/// `cos` calls) only when the width or the tap count changes, the split of the round-trip delay
/// into whole samples and a fraction whenever the delay changes.
#[derive(Clone, Debug)]
pub struct ReflectionFunction {
    history: DelayHistory,
    taps: Vec<f64>,
    tap_count: usize,
    first_tap_delay: usize,
    delay_samples: f64,
    round_trip: FractionalDelay,
    /// The unnormalised raised-cosine values of the last `set_pulse`, kept so that a change of
    /// delay alone (a pitch glide, vibrato, a moving bow) does not recompute them.
    shape: Vec<f64>,
    shape_sum: f64,
    shape_half_width: f64,
    shape_half_count: usize,
}

impl ReflectionFunction {
    /// Capacity for a centre delay up to `max_delay_samples` and a pulse up to
    /// `max_width_samples` wide.
    pub fn new(max_delay_samples: f64, max_width_samples: f64) -> Self {
        let max_taps = max_width_samples.max(0.0).ceil() as usize + 3;
        let longest = max_delay_samples.max(1.0).ceil() as usize + max_taps + 2;
        let mut taps = vec![0.0; max_taps];
        taps[0] = -1.0;
        Self {
            history: DelayHistory::new(longest),
            taps,
            tap_count: 1,
            first_tap_delay: 1,
            delay_samples: 1.0,
            round_trip: FractionalDelay::new(1.0, 1.0),
            shape: vec![0.0; max_taps],
            shape_sum: 0.0,
            // NaN: no shape cached yet.
            shape_half_width: f64::NAN,
            shape_half_count: 0,
        }
    }

    /// Largest tap count this function can hold.
    pub fn max_taps(&self) -> usize {
        self.taps.len()
    }

    /// Longest delay (samples) the history can serve for a pulse of `tap_count` taps.
    pub fn max_delay_samples(&self) -> f64 {
        (self.history.size() - self.taps.len() - 2) as f64
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
        if half_width != self.shape_half_width || half_count != self.shape_half_count {
            let mut sum = 0.0;
            for (index, value) in self.shape[..symmetric_count].iter_mut().enumerate() {
                let k = index as f64 - half_count as f64;
                *value = if half_count == 0 {
                    1.0
                } else {
                    let phase = core::f64::consts::PI * k / (2.0 * half_width);
                    let c = phase.cos();
                    c * c
                };
                sum += *value;
            }
            self.shape_sum = sum;
            self.shape_half_width = half_width;
            self.shape_half_count = half_count;
        }
        let area = if area.is_finite() { area } else { 0.0 };
        let gain = -area / self.shape_sum;
        // Linear interpolation towards one sample more delay: tap j gets (1 − φ) base[j] +
        // φ base[j − 1], with base zero outside 0..symmetric_count.
        for index in 0..=symmetric_count {
            let current = if index < symmetric_count {
                self.shape[index]
            } else {
                0.0
            };
            let previous = if index > 0 {
                self.shape[index - 1]
            } else {
                0.0
            };
            self.taps[index] = gain * ((1.0 - fraction) * current + fraction * previous);
        }
        self.tap_count = symmetric_count + 1;
        self.first_tap_delay = whole_delay - half_count;
        self.set_delay(delay);
    }

    /// Set the taps directly: `taps[j]` applies at delay `first_tap_delay + j` (≥ 1). For
    /// reproducing a paper's discrete reflection function such as eq. 22's [σ, λ, σ] (with its
    /// sign). Extra taps beyond capacity are ignored, and the first delay is lowered if the last
    /// tap would reach beyond the history; the centroid becomes the reported delay.
    pub fn set_taps(&mut self, first_tap_delay: usize, taps: &[f64]) {
        let count = taps.len().min(self.taps.len()).max(1);
        let first = first_tap_delay.max(1).min(self.history.size() + 1 - count);
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
        self.set_delay(if sum != 0.0 {
            moment / sum
        } else {
            first as f64
        });
    }

    fn set_delay(&mut self, delay_samples: f64) {
        self.delay_samples = delay_samples;
        self.round_trip = FractionalDelay::new(delay_samples, self.max_delay_samples());
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
        let window = self.history.window(self.first_tap_delay, self.tap_count);
        convolve(&self.taps[..self.tap_count], window)
    }

    /// The outgoing wave of `delay_samples` ago (≥ 1), linearly interpolated.
    #[inline]
    pub fn outgoing_delayed(&self, delay_samples: f64) -> f64 {
        self.history.read(&FractionalDelay::new(
            delay_samples,
            self.max_delay_samples(),
        ))
    }

    /// The outgoing wave of one round trip ([`Self::delay_samples`]) ago, linearly
    /// interpolated: [`Self::outgoing_delayed`] at the centre delay, with the delay split when it
    /// was set rather than per sample.
    #[inline]
    pub fn outgoing_round_trip_ago(&self) -> f64 {
        self.history.read(&self.round_trip)
    }

    /// Store this sample's outgoing wave.
    #[inline]
    pub fn push(&mut self, outgoing: f64) {
        self.history.push(outgoing);
    }

    /// Zero the history (taps are kept).
    pub fn reset(&mut self) {
        self.history.reset();
    }

    /// The function for a run of samples with its taps fixed, its history's write position in
    /// a register (see [`DelayHistory::cursor`]).
    #[inline]
    pub fn cursor(&mut self) -> ReflectionCursor<'_> {
        ReflectionCursor {
            taps: &self.taps[..self.tap_count],
            first_tap_delay: self.first_tap_delay,
            round_trip: self.round_trip,
            history: self.history.cursor(),
        }
    }
}

/// A [`ReflectionFunction`] borrowed for a run of samples: the same per-sample methods.
#[derive(Debug)]
pub struct ReflectionCursor<'a> {
    taps: &'a [f64],
    first_tap_delay: usize,
    round_trip: FractionalDelay,
    history: DelayCursor<'a>,
}

impl ReflectionCursor<'_> {
    /// As [`ReflectionFunction::incoming`].
    #[inline(always)]
    pub fn incoming(&self) -> f64 {
        let window = self.history.window(self.first_tap_delay, self.taps.len());
        convolve(self.taps, window)
    }

    /// As [`ReflectionFunction::outgoing_round_trip_ago`].
    #[inline]
    pub fn outgoing_round_trip_ago(&self) -> f64 {
        self.history.read(&self.round_trip)
    }

    /// As [`ReflectionFunction::push`].
    #[inline]
    pub fn push(&mut self, outgoing: f64) {
        self.history.push(outgoing);
    }

    /// The longest run of samples whose reads ([`Self::incoming`] and
    /// [`Self::outgoing_round_trip_ago`]) see only waves pushed before the run.
    #[inline]
    pub fn run_reach(&self) -> usize {
        self.first_tap_delay.min(self.round_trip.whole())
    }

    /// [`Self::incoming`] of each of the next `into.len()` samples, the same arithmetic, for a
    /// run no longer than [`Self::run_reach`] whose waves are pushed after it
    /// ([`Self::push_run`]). False, with nothing read, for a longer run.
    #[inline(always)]
    pub fn incoming_run(&self, into: &mut [f64]) -> bool {
        let count = into.len();
        if count == 0 || count > self.first_tap_delay {
            return false;
        }
        let taps = self.taps.len();
        // Sample k's window ends k samples after the first's.
        let span = self
            .history
            .window(self.first_tap_delay + 1 - count, taps + count - 1);
        if span.len() != taps + count - 1 {
            return false;
        }
        for (k, value) in into.iter_mut().enumerate() {
            *value = convolve(self.taps, &span[k..k + taps]);
        }
        true
    }

    /// [`Self::outgoing_round_trip_ago`] of each of the next `into.len()` samples, on the
    /// terms of [`Self::incoming_run`].
    #[inline(always)]
    pub fn round_trip_run(&self, into: &mut [f64]) -> bool {
        self.history.read_run(&self.round_trip, into)
    }

    /// Pushes a run's outgoing waves in order, as that many [`Self::push`] calls would.
    #[inline]
    pub fn push_run(&mut self, outgoing: &[f64]) {
        self.history.push_run(outgoing);
    }

    /// As [`ReflectionFunction::reset`].
    pub fn reset(&mut self) {
        self.history.reset();
    }
}

/// Σ_j taps[j] · window[len − 1 − j]: the window runs oldest first, and tap 0 (the shortest
/// delay) meets its newest value. Added in tap order.
///
/// A pulse has only a few taps (2 to 8 for a violin at 44.1 to 192 kHz), so a loop over a
/// run-time count costs more in loop control than in arithmetic: the common counts get a
/// fixed-length version that the compiler unrolls, chosen once per call by a jump.
#[inline(always)]
fn convolve(taps: &[f64], window: &[f64]) -> f64 {
    match taps.len() {
        1 => convolve_fixed::<1>(taps, window),
        2 => convolve_fixed::<2>(taps, window),
        3 => convolve_fixed::<3>(taps, window),
        4 => convolve_fixed::<4>(taps, window),
        5 => convolve_fixed::<5>(taps, window),
        6 => convolve_fixed::<6>(taps, window),
        7 => convolve_fixed::<7>(taps, window),
        8 => convolve_fixed::<8>(taps, window),
        _ => convolve_any(taps, window),
    }
}

#[inline(always)]
fn convolve_fixed<const N: usize>(taps: &[f64], window: &[f64]) -> f64 {
    match (taps.first_chunk::<N>(), window.last_chunk::<N>()) {
        (Some(taps), Some(window)) => {
            let mut sum = 0.0;
            for j in 0..N {
                sum += taps[j] * window[N - 1 - j];
            }
            sum
        }
        _ => convolve_any(taps, window),
    }
}

fn convolve_any(taps: &[f64], window: &[f64]) -> f64 {
    let mut sum = 0.0;
    for (&tap, &past) in taps.iter().zip(window.iter().rev()) {
        sum += tap * past;
    }
    sum
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
