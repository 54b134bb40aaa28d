//! Signal analysis for tests, benchmarks and the offline tools: FFT, windowed spectra, precise
//! partial frequencies, spectral centroids and band energies; [`listening`] defines what a
//! listener compares between two renders, [`playing_range`] the grid of plucks the tiers are
//! compared on, [`precursor`] the seed's precursor in the nut force, [`refined`] the reference's
//! string on finer grids. Not used on the audio thread (the editor's spectrum calls [`fft`] on
//! the GUI thread).
//!
//! The transforms are rustfft's (complex) and realfft's (real input), planned once per length and
//! thread and reused: these tools call them thousands of times with a handful of lengths.

pub mod listening;
pub mod playing_range;
pub mod precursor;
pub mod refined;

use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use rustfft::FftPlanner;
use std::cell::RefCell;
use std::f64::consts::PI;

thread_local! {
    /// Plans by length (the planners cache them), one set per thread: the editor's GUI thread
    /// and each render or analysis worker plan their own.
    static COMPLEX_PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
    static REAL_PLANNER: RefCell<RealFftPlanner<f64>> = RefCell::new(RealFftPlanner::new());
}

/// In-place forward complex DFT, unnormalised: `X[k] = Σ x[j] e^{−2πi jk/n}` (any length;
/// powers of two are the fastest). Allocates a buffer per call: not for the audio thread.
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    assert_eq!(im.len(), n, "FFT real and imaginary parts differ in length");
    if n == 0 {
        return;
    }
    let plan = COMPLEX_PLANNER.with(|planner| planner.borrow_mut().plan_fft_forward(n));
    let mut buffer: Vec<Complex<f64>> = re
        .iter()
        .zip(im.iter())
        .map(|(&re, &im)| Complex::new(re, im))
        .collect();
    plan.process(&mut buffer);
    for ((re, im), value) in re.iter_mut().zip(im.iter_mut()).zip(buffer) {
        *re = value.re;
        *im = value.im;
    }
}

/// The Hann window of length `n`.
pub fn hann(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos())
        .collect()
}

/// Power spectrum (|X|², bins 0..=fft_size/2) of `signal[start..start + n]` with a Hann window,
/// zero-padded to `fft_size` (≥ n; a power of two is the fastest). Samples past the end of
/// `signal` count as zeros.
pub fn power_spectrum(signal: &[f64], start: usize, n: usize, fft_size: usize) -> Vec<f64> {
    assert!(n <= fft_size, "the FFT size must hold the windowed frame");
    let window = hann(n);
    let plan = REAL_PLANNER.with(|planner| planner.borrow_mut().plan_fft_forward(fft_size));
    let mut frame = plan.make_input_vec();
    for (i, (sample, weight)) in frame.iter_mut().zip(&window).enumerate() {
        *sample = signal.get(start + i).copied().unwrap_or(0.0) * weight;
    }
    let mut spectrum = plan.make_output_vec();
    plan.process(&mut frame, &mut spectrum)
        .expect("buffers come from the plan itself");
    spectrum.iter().map(|bin| bin.norm_sqr()).collect()
}

/// `|Σ x[i] w[i] e^{−2πi f i / fs}|²` for one frequency (Hann-windowed DFT at any frequency).
pub fn windowed_dft_power<T: Copy + Into<f64>>(
    signal: &[T],
    sample_rate_hz: f64,
    frequency_hz: f64,
) -> f64 {
    let n = signal.len();
    let windowed: Vec<f64> = signal
        .iter()
        .zip(hann(n))
        .map(|(&sample, weight)| sample.into() * weight)
        .collect();
    dft_power(&windowed, sample_rate_hz, frequency_hz)
}

/// |DFT|² of an already windowed `signal` at `frequency_hz` (any frequency, not only a bin).
///
/// A rotating phasor instead of sin/cos per sample, renormalised every 1024 samples against
/// drift. The signal is cut into [`DFT_CHAINS`] equal contiguous parts, each with its own phasor
/// and sums, so that their multiply-add chains run side by side (the pitch searches of the
/// calibration and the bench call this some hundred times per pluck); the few samples left over
/// take sin/cos each.
fn dft_power(windowed: &[f64], sample_rate_hz: f64, frequency_hz: f64) -> f64 {
    let omega = 2.0 * PI * frequency_hz / sample_rate_hz;
    let (step_sin, step_cos) = omega.sin_cos();
    let part = windowed.len() / DFT_CHAINS;
    let mut re = [0.0f64; DFT_CHAINS];
    let mut im = [0.0f64; DFT_CHAINS];
    let mut c = [0.0f64; DFT_CHAINS];
    let mut s = [0.0f64; DFT_CHAINS];
    for chain in 0..DFT_CHAINS {
        (s[chain], c[chain]) = (omega * (chain * part) as f64).sin_cos();
    }
    for i in 0..part {
        for chain in 0..DFT_CHAINS {
            let x = windowed[chain * part + i];
            re[chain] += x * c[chain];
            im[chain] -= x * s[chain];
            let next_c = c[chain] * step_cos - s[chain] * step_sin;
            s[chain] = s[chain] * step_cos + c[chain] * step_sin;
            c[chain] = next_c;
        }
        if i % 1024 == 1023 {
            for chain in 0..DFT_CHAINS {
                let norm = (c[chain] * c[chain] + s[chain] * s[chain]).sqrt();
                c[chain] /= norm;
                s[chain] /= norm;
            }
        }
    }
    let (mut re, mut im): (f64, f64) = (re.iter().sum(), im.iter().sum());
    for (i, &x) in windowed.iter().enumerate().skip(DFT_CHAINS * part) {
        let (sin, cos) = (omega * i as f64).sin_cos();
        re += x * cos;
        im -= x * sin;
    }
    re * re + im * im
}

/// Independent phasor chains of [`dft_power`].
const DFT_CHAINS: usize = 4;

pub fn peak_frequency_hz(signal: &[f64], sample_rate_hz: f64, low_hz: f64, high_hz: f64) -> f64 {
    let duration = signal.len() as f64 / sample_rate_hz;
    let n = signal.len();
    let windowed: Vec<f64> = signal
        .iter()
        .zip(hann(n))
        .map(|(&sample, weight)| sample * weight)
        .collect();
    // Coarse scan at a quarter of the window's resolution.
    let step = 0.25 / duration;
    let mut best = (low_hz, -1.0);
    let mut f = low_hz;
    while f <= high_hz {
        let power = dft_power(&windowed, sample_rate_hz, f);
        if power > best.1 {
            best = (f, power);
        }
        f += step;
    }
    let (mut a, mut b) = ((best.0 - step).max(low_hz), (best.0 + step).min(high_hz));
    let ratio = (5.0f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - ratio * (b - a);
    let mut x2 = a + ratio * (b - a);
    let mut p1 = dft_power(&windowed, sample_rate_hz, x1);
    let mut p2 = dft_power(&windowed, sample_rate_hz, x2);
    for _ in 0..60 {
        if p1 > p2 {
            b = x2;
            x2 = x1;
            p2 = p1;
            x1 = b - ratio * (b - a);
            p1 = dft_power(&windowed, sample_rate_hz, x1);
        } else {
            a = x1;
            x1 = x2;
            p1 = p2;
            x2 = a + ratio * (b - a);
            p2 = dft_power(&windowed, sample_rate_hz, x2);
        }
        if b - a < 1e-7 {
            break;
        }
    }
    0.5 * (a + b)
}

/// Cents from `reference_hz` to `frequency_hz`.
pub fn cents(frequency_hz: f64, reference_hz: f64) -> f64 {
    1200.0 * (frequency_hz / reference_hz).log2()
}

/// Power-weighted mean frequency of `spectrum` (bins of width `bin_hz`) within a band, Hz.
pub fn spectral_centroid_hz(spectrum: &[f64], bin_hz: f64, low_hz: f64, high_hz: f64) -> f64 {
    let (mut weighted, mut total) = (0.0, 0.0);
    for (k, power) in spectrum.iter().enumerate() {
        let f = k as f64 * bin_hz;
        if f >= low_hz && f <= high_hz {
            weighted += f * power;
            total += power;
        }
    }
    if total > 0.0 {
        weighted / total
    } else {
        0.0
    }
}

/// Total power of `spectrum` within `[low_hz, high_hz]`.
pub fn band_power(spectrum: &[f64], bin_hz: f64, low_hz: f64, high_hz: f64) -> f64 {
    spectrum
        .iter()
        .enumerate()
        .filter(|(k, _)| {
            let f = *k as f64 * bin_hz;
            f >= low_hz && f <= high_hz
        })
        .map(|(_, p)| p)
        .sum()
}

/// The frequencies of the first `count` partials of `signal` from 0.5 s on, each the peak within
/// ±3 % of n·`fundamental_hz`, Hz: the cents measure of the bench's one-string scene
/// (`cargo xtask bench`).
pub fn first_partials_hz(
    signal: &[f64],
    sample_rate_hz: f64,
    fundamental_hz: f64,
    count: usize,
) -> Vec<f64> {
    let start = (0.5 * sample_rate_hz) as usize;
    let signal = &signal[start.min(signal.len())..];
    (1..=count)
        .map(|n| {
            let expected = n as f64 * fundamental_hz;
            peak_frequency_hz(signal, sample_rate_hz, expected * 0.97, expected * 1.03)
        })
        .collect()
}

/// Frame length of [`third_octave_levels_db`], samples.
pub const THIRD_OCTAVE_FRAME: usize = 4096;

/// The edges of [`third_octave_levels_db`]'s bands, Hz: from 40 Hz up by thirds of an octave,
/// the last at or above 16 kHz (band k spans edges k and k + 1).
pub fn third_octave_edges_hz() -> Vec<f64> {
    let mut edges = vec![40.0f64];
    while edges[edges.len() - 1] < 16_000.0 {
        edges.push(edges[edges.len() - 1] * 2f64.powf(1.0 / 3.0));
    }
    edges
}

/// Third-octave band levels (dB) of each [`THIRD_OCTAVE_FRAME`]-sample frame, 40 Hz to 16 kHz
/// ([`third_octave_edges_hz`]).
pub fn third_octave_levels_db(signal: &[f64], sample_rate_hz: f64) -> Vec<Vec<f64>> {
    let bin = sample_rate_hz / THIRD_OCTAVE_FRAME as f64;
    let edges = third_octave_edges_hz();
    (0..signal.len() / THIRD_OCTAVE_FRAME)
        .map(|frame| {
            let spectrum = power_spectrum(
                signal,
                frame * THIRD_OCTAVE_FRAME,
                THIRD_OCTAVE_FRAME,
                THIRD_OCTAVE_FRAME,
            );
            edges
                .windows(2)
                .map(|band| 10.0 * (band_power(&spectrum, bin, band[0], band[1]) + 1e-30).log10())
                .collect()
        })
        .collect()
}

/// The bench's spectral distance of `signal` from `reference`: the RMS difference of their
/// third-octave band levels (dB) over the bands within 60 dB of the reference frame's loudest
/// band, averaged over frames; a band the signal leaves empty counts as the 60 dB it lies below
/// that floor. A timbre distance that small pitch differences do not dominate.
pub fn third_octave_distance_db(signal: &[f64], reference: &[f64], sample_rate_hz: f64) -> f64 {
    let (a, b) = (
        third_octave_levels_db(signal, sample_rate_hz),
        third_octave_levels_db(reference, sample_rate_hz),
    );
    let frames = a.len().min(b.len());
    let mut total = 0.0;
    for frame in 0..frames {
        let floor = b[frame].iter().cloned().fold(f64::MIN, f64::max) - 60.0;
        let (mut sum, mut count) = (0.0, 0usize);
        for (x, r) in a[frame].iter().zip(&b[frame]) {
            if *r > floor {
                sum += (x.max(floor) - r).powi(2);
                count += 1;
            }
        }
        total += (sum / count.max(1) as f64).sqrt();
    }
    total / frames.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// X[k] = Σ x[j] e^{−2πi jk/n}, summed term by term.
    fn direct_dft(re: &[f64], im: &[f64]) -> Vec<(f64, f64)> {
        let n = re.len();
        (0..n)
            .map(|k| {
                (0..n).fold((0.0, 0.0), |(sum_re, sum_im), j| {
                    let angle = -2.0 * PI * (j * k) as f64 / n as f64;
                    let (sin, cos) = angle.sin_cos();
                    (
                        sum_re + re[j] * cos - im[j] * sin,
                        sum_im + re[j] * sin + im[j] * cos,
                    )
                })
            })
            .collect()
    }

    #[test]
    fn fft_of_a_bin_centred_sine_has_one_peak() {
        let n = 64;
        let mut re: Vec<f64> = (0..n)
            .map(|i| (2.0 * PI * 5.0 * i as f64 / n as f64).cos())
            .collect();
        let mut im = vec![0.0; n];
        fft(&mut re, &mut im);
        assert!((re[5] - 32.0).abs() < 1e-9 && (re[59] - 32.0).abs() < 1e-9);
        let others: f64 = (0..n)
            .filter(|&k| k != 5 && k != 59)
            .map(|k| re[k].abs() + im[k].abs())
            .sum();
        assert!(others < 1e-9);
    }

    #[test]
    fn fft_equals_the_direct_dft() {
        for n in [1, 8, 12, 16] {
            let re: Vec<f64> = (0..n).map(|i| (0.7 * i as f64).sin() + 0.1).collect();
            let im: Vec<f64> = (0..n).map(|i| (1.3 * i as f64).cos() - 0.2).collect();
            let expected = direct_dft(&re, &im);
            let (mut out_re, mut out_im) = (re.clone(), im.clone());
            fft(&mut out_re, &mut out_im);
            for k in 0..n {
                assert!((out_re[k] - expected[k].0).abs() < 1e-12, "n {n}, bin {k}");
                assert!((out_im[k] - expected[k].1).abs() < 1e-12, "n {n}, bin {k}");
            }
        }
    }

    #[test]
    fn power_spectrum_is_the_hann_windowed_zero_padded_dft() {
        // A frame that starts inside the signal and runs past its end (zeros), padded 24 → 32.
        let signal: Vec<f64> = (0..40)
            .map(|i| (0.37 * i as f64).sin() * 0.8 + 0.05)
            .collect();
        let (start, n, fft_size) = (20, 24, 32);
        let window = hann(n);
        let mut re = vec![0.0; fft_size];
        for i in 0..n {
            re[i] = signal.get(start + i).copied().unwrap_or(0.0) * window[i];
        }
        let expected = direct_dft(&re, &vec![0.0; fft_size]);
        let spectrum = power_spectrum(&signal, start, n, fft_size);
        assert_eq!(spectrum.len(), fft_size / 2 + 1);
        for (k, power) in spectrum.iter().enumerate() {
            let want = expected[k].0 * expected[k].0 + expected[k].1 * expected[k].1;
            assert!((power - want).abs() < 1e-12 * want.max(1.0), "bin {k}");
        }
        // The window is the periodic Hann: zero at the first sample, one at the centre.
        assert_eq!(window[0], 0.0);
        assert!((window[n / 2] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn the_chained_dft_power_is_the_direct_sum() {
        // Lengths with every remainder after the four parts, long enough for the renormalisation.
        for n in [3usize, 4, 4097, 10_001, 10_002, 10_003] {
            let signal: Vec<f64> = (0..n)
                .map(|i| (0.37 * i as f64).sin() + 0.5 * (1.91 * i as f64).cos())
                .collect();
            for frequency_hz in [0.0, 13.7, 617.3, 2_345.6] {
                let omega = 2.0 * PI * frequency_hz / 8_000.0;
                let (mut re, mut im) = (0.0, 0.0);
                for (i, &x) in signal.iter().enumerate() {
                    re += x * (omega * i as f64).cos();
                    im -= x * (omega * i as f64).sin();
                }
                let direct = re * re + im * im;
                let chained = dft_power(&signal, 8_000.0, frequency_hz);
                let scale = signal.iter().map(|x| x * x).sum::<f64>() * n as f64;
                assert!(
                    (chained - direct).abs() <= 1e-10 * scale,
                    "n {n}, {frequency_hz} Hz: {chained} against {direct}"
                );
            }
        }
    }

    #[test]
    fn peak_frequency_is_found_to_a_millihertz() {
        let rate = 8000.0;
        let f = 187.1234;
        let signal: Vec<f64> = (0..16000)
            .map(|i| {
                let t = i as f64 / rate;
                (2.0 * PI * f * t).sin() + 0.5 * (2.0 * PI * 2.0 * f * t).sin()
            })
            .collect();
        let found = peak_frequency_hz(&signal, rate, 150.0, 250.0);
        assert!((found - f).abs() < 1e-3, "{found}");
    }

    #[test]
    fn centroid_of_two_equal_lines_is_their_mean() {
        let mut spectrum = vec![0.0; 100];
        spectrum[10] = 1.0;
        spectrum[30] = 1.0;
        assert!((spectrum_centroid_check(&spectrum) - 200.0).abs() < 1e-12);
    }

    fn spectrum_centroid_check(spectrum: &[f64]) -> f64 {
        spectral_centroid_hz(spectrum, 10.0, 0.0, 1000.0)
    }

    /// A sum of sines at 100, 200, … Hz with the given amplitudes, 2 s at 8 kHz.
    fn harmonics(amplitudes: &[f64]) -> Vec<f64> {
        (0..16_000)
            .map(|j| {
                let t = j as f64 / 8_000.0;
                amplitudes
                    .iter()
                    .enumerate()
                    .map(|(n, a)| a * (2.0 * PI * 100.0 * (n + 1) as f64 * t).sin())
                    .sum()
            })
            .collect()
    }

    #[test]
    fn first_partials_are_found_where_they_are() {
        let partials = first_partials_hz(&harmonics(&[1.0, 0.5, 0.3]), 8_000.0, 100.0, 3);
        for (n, partial) in partials.iter().enumerate() {
            assert!(
                (partial - 100.0 * (n + 1) as f64).abs() < 0.01,
                "{partials:?}"
            );
        }
    }

    #[test]
    fn the_third_octave_distance_is_zero_to_itself_and_counts_a_missing_band() {
        let full = harmonics(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5]);
        assert_eq!(third_octave_distance_db(&full, &full, 8_000.0), 0.0);
        // Without its 1 kHz partial, 6 dB below the loudest: that band counts as the 60 dB
        // floor below the loudest band, 54 dB off, among the bands within 60 dB of it.
        let missing = harmonics(&[1.0]);
        let distance = third_octave_distance_db(&missing, &full, 8_000.0);
        assert!(distance > 10.0, "{distance}");
    }
}
