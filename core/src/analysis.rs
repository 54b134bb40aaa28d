//! Signal analysis for tests, benchmarks and the offline tools: FFT, windowed spectra, precise
//! partial frequencies, spectral centroids and band energies. Not used on the audio thread.

use std::f64::consts::PI;

/// In-place radix-2 complex FFT (`re.len()` must be a power of two).
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    assert!(
        n.is_power_of_two() && im.len() == n,
        "FFT length must be a power of two"
    );
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut length = 2;
    while length <= n {
        let angle = -2.0 * PI / length as f64;
        for start in (0..n).step_by(length) {
            for k in 0..length / 2 {
                let (sin, cos) = (angle * k as f64).sin_cos();
                let a = start + k;
                let b = a + length / 2;
                let tr = re[b] * cos - im[b] * sin;
                let ti = re[b] * sin + im[b] * cos;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
        }
        length <<= 1;
    }
}

/// The Hann window of length `n`.
pub fn hann(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos())
        .collect()
}

/// Power spectrum (|X|², bins 0..=n/2) of `signal[start..start + n]` with a Hann window,
/// zero-padded to `fft_size` (a power of two ≥ n).
pub fn power_spectrum(signal: &[f64], start: usize, n: usize, fft_size: usize) -> Vec<f64> {
    let window = hann(n);
    let mut re = vec![0.0; fft_size];
    let mut im = vec![0.0; fft_size];
    for i in 0..n {
        re[i] = signal.get(start + i).copied().unwrap_or(0.0) * window[i];
    }
    fft(&mut re, &mut im);
    (0..=fft_size / 2)
        .map(|k| re[k] * re[k] + im[k] * im[k])
        .collect()
}

/// |Σ x[i] w[i] e^{−2πi f i / fs}|² for one frequency (Hann-windowed DFT at any frequency).
pub fn windowed_dft_power<T: Copy + Into<f64>>(
    signal: &[T],
    sample_rate_hz: f64,
    frequency_hz: f64,
) -> f64 {
    let n = signal.len();
    let omega = 2.0 * PI * frequency_hz / sample_rate_hz;
    let (mut re, mut im) = (0.0, 0.0);
    // Rotate a phasor instead of calling sin/cos per sample; renormalise to stop drift.
    let (step_sin, step_cos) = omega.sin_cos();
    let (mut c, mut s) = (1.0f64, 0.0f64);
    for (i, &sample) in signal.iter().enumerate() {
        let x: f64 = sample.into();
        let w = 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos();
        re += x * w * c;
        im -= x * w * s;
        let next_c = c * step_cos - s * step_sin;
        s = s * step_cos + c * step_sin;
        c = next_c;
        if i % 1024 == 1023 {
            let norm = (c * c + s * s).sqrt();
            c /= norm;
            s /= norm;
        }
    }
    re * re + im * im
}

/// The frequency of the strongest spectral peak within `[low_hz, high_hz]`, refined by
/// golden-section search on the windowed DFT to well under a millihertz for second-long signals.
pub fn peak_frequency_hz(signal: &[f64], sample_rate_hz: f64, low_hz: f64, high_hz: f64) -> f64 {
    let duration = signal.len() as f64 / sample_rate_hz;
    // Coarse scan at a quarter of the window's resolution.
    let step = 0.25 / duration;
    let mut best = (low_hz, -1.0);
    let mut f = low_hz;
    while f <= high_hz {
        let power = windowed_dft_power(signal, sample_rate_hz, f);
        if power > best.1 {
            best = (f, power);
        }
        f += step;
    }
    let (mut a, mut b) = ((best.0 - step).max(low_hz), (best.0 + step).min(high_hz));
    let ratio = (5.0f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - ratio * (b - a);
    let mut x2 = a + ratio * (b - a);
    let mut p1 = windowed_dft_power(signal, sample_rate_hz, x1);
    let mut p2 = windowed_dft_power(signal, sample_rate_hz, x2);
    for _ in 0..60 {
        if p1 > p2 {
            b = x2;
            x2 = x1;
            p2 = p1;
            x1 = b - ratio * (b - a);
            p1 = windowed_dft_power(signal, sample_rate_hz, x1);
        } else {
            a = x1;
            x1 = x2;
            p1 = p2;
            x2 = a + ratio * (b - a);
            p2 = windowed_dft_power(signal, sample_rate_hz, x2);
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
