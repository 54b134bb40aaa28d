//! What a listener compares between two renders of the same pluck: the pitch it settles to, how
//! it glides there, the level in each fractional-octave band (so that a band a tier leaves empty
//! counts), and the course of the jawari formant. Defined once here and used by the bench's
//! playing-range grid (`cargo xtask bench`) and the tests that hold the tiers to the reference.
//!
//! All four are computed from spectra (the contact dynamics amplify round-off, so two tiers'
//! waveforms part within milliseconds while their sound does not):
//!
//! - **sustained pitch**: the fundamental's frequency over 0.3–1.5 s after the pluck, the strongest
//!   peak within a semitone of the nominal pitch, refined on the windowed DFT
//!   ([`peak_frequency_hz`]);
//! - **pitch glide**: the fundamental in 0.1 s frames every 0.05 s over the first 0.3 s, where the
//!   jawari's amplitude-dependent pitch falls; two renders are compared frame by frame;
//! - **band levels**: 1/6-octave band levels (dB) from 40 Hz to 16 kHz or 0.99 of the Nyquist
//!   frequency, in 4096-sample frames; two renders differ by the RMS of their level differences
//!   over the bands within 60 dB of the reference frame's loudest, a band the other render leaves
//!   below that floor counting as the floor, averaged over frames;
//! - **centroid course**: the power-weighted mean frequency above 5.5 f₀ (where the jawari's
//!   formant moves; up to 15 kHz) in each frame; two renders differ by the mean relative
//!   difference over the frames where the reference sounds.

use super::{
    band_power, cents, first_partials_hz, peak_frequency_hz, power_spectrum, spectral_centroid_hz,
    third_octave_distance_db,
};

/// Where the sustained pitch is measured, seconds after the pluck.
pub const SUSTAIN_WINDOW_S: (f64, f64) = (0.3, 1.5);
/// The span of the glide, seconds after the pluck, and its frames' length and hop.
pub const GLIDE_SPAN_S: f64 = 0.3;
pub const GLIDE_FRAME_S: f64 = 0.1;
pub const GLIDE_HOP_S: f64 = 0.05;
/// Band-level and centroid frames, samples.
pub const FRAME: usize = 4096;
/// Bands per octave.
pub const BANDS_PER_OCTAVE: f64 = 6.0;
/// Lowest band edge and the upper limit of the bands (capped at 0.99 of Nyquist), Hz.
pub const BANDS_FROM_HZ: f64 = 40.0;
pub const BANDS_TO_HZ: f64 = 16_000.0;
/// Bands further below the reference frame's loudest than this do not count, dB.
pub const BAND_FLOOR_DB: f64 = 60.0;
/// The centroid is taken above this multiple of the fundamental.
pub const CENTROID_FROM_PARTIAL: f64 = 5.5;
pub const CENTROID_TO_HZ: f64 = 15_000.0;

/// How far a render lies from the reference render of the same pluck.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ListeningDifference {
    /// Sustained pitch, cents (signed: negative is flat of the reference).
    pub sustained_cents: f64,
    /// Largest pitch difference over the glide's frames, cents (absolute).
    pub glide_cents: f64,
    /// Fractional-octave band levels, RMS difference, dB.
    pub band_level_db: f64,
    /// Centroid course, mean relative difference (0.1 = 10 %).
    pub centroid_error: f64,
}

/// The search band for a fundamental near `nominal_hz`: a semitone either side.
fn fundamental_band(nominal_hz: f64) -> (f64, f64) {
    let semitone = 2f64.powf(1.0 / 12.0);
    (nominal_hz / semitone, nominal_hz * semitone)
}

fn seconds_to_samples(seconds: f64, sample_rate_hz: f64) -> usize {
    (seconds * sample_rate_hz).round() as usize
}

/// The fundamental's frequency over [`SUSTAIN_WINDOW_S`] (or what of it the signal holds), Hz.
pub fn sustained_pitch_hz(signal: &[f64], sample_rate_hz: f64, nominal_hz: f64) -> f64 {
    let start = seconds_to_samples(SUSTAIN_WINDOW_S.0, sample_rate_hz).min(signal.len());
    let end = seconds_to_samples(SUSTAIN_WINDOW_S.1, sample_rate_hz).clamp(start, signal.len());
    let (low, high) = fundamental_band(nominal_hz);
    peak_frequency_hz(&signal[start..end], sample_rate_hz, low, high)
}

/// The fundamental in each glide frame over the first [`GLIDE_SPAN_S`], Hz.
pub fn glide_course_hz(signal: &[f64], sample_rate_hz: f64, nominal_hz: f64) -> Vec<f64> {
    let frame = seconds_to_samples(GLIDE_FRAME_S, sample_rate_hz);
    let hop = seconds_to_samples(GLIDE_HOP_S, sample_rate_hz);
    let span = seconds_to_samples(GLIDE_SPAN_S, sample_rate_hz).min(signal.len());
    let (low, high) = fundamental_band(nominal_hz);
    (0..)
        .map(|k| k * hop)
        .take_while(|start| start + frame <= span)
        .map(|start| peak_frequency_hz(&signal[start..start + frame], sample_rate_hz, low, high))
        .collect()
}

/// The band edges: 1/6 octave from [`BANDS_FROM_HZ`] up to 16 kHz or 0.99 of Nyquist.
pub fn band_edges_hz(sample_rate_hz: f64) -> Vec<f64> {
    let top = BANDS_TO_HZ.min(0.99 * 0.5 * sample_rate_hz);
    let ratio = 2f64.powf(1.0 / BANDS_PER_OCTAVE);
    let mut edges = vec![BANDS_FROM_HZ];
    while *edges.last().unwrap_or(&top) * ratio <= top * 1.000_001 {
        let next = edges[edges.len() - 1] * ratio;
        edges.push(next);
    }
    edges
}

/// Band levels (dB) of each [`FRAME`]-sample frame: one row per frame, one column per band of
/// [`band_edges_hz`]. An empty band is −300 dB.
pub fn band_levels_db(signal: &[f64], sample_rate_hz: f64) -> Vec<Vec<f64>> {
    let bin = sample_rate_hz / FRAME as f64;
    let edges = band_edges_hz(sample_rate_hz);
    (0..signal.len() / FRAME)
        .map(|frame| {
            let spectrum = power_spectrum(signal, frame * FRAME, FRAME, FRAME);
            edges
                .windows(2)
                .map(|band| 10.0 * (band_power(&spectrum, bin, band[0], band[1]) + 1e-30).log10())
                .collect()
        })
        .collect()
}

/// The bands of one frame that the band-level measure counts (the reference's level above
/// [`BAND_FLOOR_DB`] below its loudest band), each with its index and the render's level, floored
/// there, less the reference's, dB.
pub fn counted_band_differences_db<'a>(
    levels: &'a [f64],
    reference: &'a [f64],
) -> impl Iterator<Item = (usize, f64)> + 'a {
    let floor = reference.iter().copied().fold(f64::MIN, f64::max) - BAND_FLOOR_DB;
    levels
        .iter()
        .zip(reference)
        .enumerate()
        .filter(move |(_, (_, r))| **r > floor)
        .map(move |(band, (x, r))| (band, x.max(floor) - r))
}

/// RMS difference (dB) of two renders' band levels, averaged over frames; see the module doc.
pub fn band_level_distance_db(levels: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    let frames = levels.len().min(reference.len());
    let mut total = 0.0;
    let mut counted = 0usize;
    for (mine, theirs) in levels.iter().zip(reference).take(frames) {
        let (sum, count) = counted_band_differences_db(mine, theirs)
            .fold((0.0, 0usize), |(sum, count), (_, difference)| {
                (sum + difference.powi(2), count + 1)
            });
        if count > 0 {
            total += (sum / count as f64).sqrt();
            counted += 1;
        }
    }
    total / counted.max(1) as f64
}

/// The centroid above [`CENTROID_FROM_PARTIAL`] · f₀ of each frame, Hz (0 for a silent frame).
pub fn centroid_course_hz(signal: &[f64], sample_rate_hz: f64, fundamental_hz: f64) -> Vec<f64> {
    let bin = sample_rate_hz / FRAME as f64;
    let top = CENTROID_TO_HZ.min(0.5 * sample_rate_hz);
    (0..signal.len() / FRAME)
        .map(|frame| {
            let spectrum = power_spectrum(signal, frame * FRAME, FRAME, FRAME);
            spectral_centroid_hz(&spectrum, bin, CENTROID_FROM_PARTIAL * fundamental_hz, top)
        })
        .collect()
}

/// Mean relative difference of two centroid courses over the frames where the reference has
/// one; a frame where `course` is silent counts as a 100 % difference.
pub fn centroid_course_error(course: &[f64], reference: &[f64]) -> f64 {
    let pairs: Vec<(f64, f64)> = course
        .iter()
        .zip(reference)
        .filter(|(_, r)| **r > 0.0)
        .map(|(x, r)| (*x, *r))
        .collect();
    pairs.iter().map(|(x, r)| (x - r).abs() / r).sum::<f64>() / pairs.len().max(1) as f64
}

/// The bench's one-string measures of `output` (fundamental `fundamental_hz`) against
/// `yardstick` (`yardstick_hz`), both at `sample_rate_hz`: the largest cents error of the first
/// ten partials, the third-octave spectral distance (dB) and the centroid course's error (a
/// fraction), each render at its own f₀.
pub fn one_string_errors(
    output: &[f64],
    fundamental_hz: f64,
    yardstick: &[f64],
    yardstick_hz: f64,
    sample_rate_hz: f64,
) -> (f64, f64, f64) {
    let mine = first_partials_hz(output, sample_rate_hz, fundamental_hz, 10);
    let theirs = first_partials_hz(yardstick, sample_rate_hz, yardstick_hz, 10);
    let cents_error = mine
        .iter()
        .zip(&theirs)
        .map(|(a, b)| cents(*a, *b).abs())
        .fold(0.0, f64::max);
    let distance = third_octave_distance_db(output, yardstick, sample_rate_hz);
    let formant = centroid_course_error(
        &centroid_course_hz(output, sample_rate_hz, fundamental_hz),
        &centroid_course_hz(yardstick, sample_rate_hz, yardstick_hz),
    );
    (cents_error, distance, formant)
}

/// The four measures of `render` against `reference`, two renders of one pluck at the same
/// sample rate whose nominal pitch is `nominal_hz`.
pub fn compare(
    render: &[f64],
    reference: &[f64],
    sample_rate_hz: f64,
    nominal_hz: f64,
) -> ListeningDifference {
    let reference_pitch = sustained_pitch_hz(reference, sample_rate_hz, nominal_hz);
    let sustained_cents = cents(
        sustained_pitch_hz(render, sample_rate_hz, nominal_hz),
        reference_pitch,
    );
    let glide_cents = glide_course_hz(render, sample_rate_hz, nominal_hz)
        .iter()
        .zip(&glide_course_hz(reference, sample_rate_hz, nominal_hz))
        .map(|(a, b)| cents(*a, *b).abs())
        .fold(0.0, f64::max);
    let (levels, reference_levels) = (
        band_levels_db(render, sample_rate_hz),
        band_levels_db(reference, sample_rate_hz),
    );
    let band_level_db = band_level_distance_db(&levels, &reference_levels);
    let centroid_error = centroid_course_error(
        &centroid_course_hz(render, sample_rate_hz, reference_pitch),
        &centroid_course_hz(reference, sample_rate_hz, reference_pitch),
    );
    ListeningDifference {
        sustained_cents,
        glide_cents,
        band_level_db,
        centroid_error,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const RATE: f64 = 44_100.0;

    /// A decaying harmonic tone: partials n·f₀ (n ≤ `partials`) at amplitude 1/n.
    fn tone(f0: f64, partials: usize, seconds: f64) -> Vec<f64> {
        (0..(seconds * RATE) as usize)
            .map(|i| {
                let t = i as f64 / RATE;
                (1..=partials)
                    .map(|n| (2.0 * PI * n as f64 * f0 * t).sin() / n as f64)
                    .sum::<f64>()
                    * (-t).exp()
            })
            .collect()
    }

    #[test]
    fn a_render_equal_to_the_reference_differs_by_nothing() {
        let a = tone(150.0, 40, 1.6);
        let difference = compare(&a, &a, RATE, 150.0);
        assert_eq!(difference.sustained_cents, 0.0);
        assert_eq!(difference.glide_cents, 0.0);
        assert_eq!(difference.band_level_db, 0.0);
        assert_eq!(difference.centroid_error, 0.0);
    }

    #[test]
    fn a_detuned_render_is_measured_in_cents_in_sustain_and_glide() {
        let reference = tone(150.0, 10, 1.6);
        let sharp = tone(150.0 * 2f64.powf(5.0 / 1200.0), 10, 1.6);
        let difference = compare(&sharp, &reference, RATE, 150.0);
        assert!(
            (difference.sustained_cents - 5.0).abs() < 0.05,
            "{difference:?}"
        );
        // Short frames see the same 5 cents, to their coarser precision.
        assert!((difference.glide_cents - 5.0).abs() < 0.5, "{difference:?}");
    }

    #[test]
    fn a_missing_top_band_counts_as_the_floor() {
        // The reference's partials reach 6 kHz; the render stops at 3 kHz. Every frame has
        // about four bands of upper partials the render leaves empty.
        let reference = tone(200.0, 30, 1.0);
        let dull = tone(200.0, 15, 1.0);
        let difference = compare(&dull, &reference, RATE, 200.0);
        assert!(difference.band_level_db > 10.0, "{difference:?}");
        assert!(difference.centroid_error > 0.2, "{difference:?}");
        assert!(difference.sustained_cents.abs() < 0.01, "{difference:?}");
    }

    #[test]
    fn bands_reach_16_khz_or_just_below_nyquist() {
        let edges = band_edges_hz(44_100.0);
        assert!(
            (edges[edges.len() - 1] - 16_000.0).abs() < 16_000.0 * (2f64.powf(1.0 / 6.0) - 1.0)
        );
        assert!(*edges.last().unwrap() <= 16_000.0 * 1.000_001);
        let low_rate = band_edges_hz(22_050.0);
        assert!(*low_rate.last().unwrap() <= 0.99 * 11_025.0 * 1.000_001);
        assert!(*low_rate.last().unwrap() > 0.99 * 11_025.0 / 2f64.powf(1.0 / 6.0));
    }
}
