//! The seed's precursor as numbers (seed 000, section 5.2 and Figure 4): a packet of high
//! frequencies that reaches the nut once per period ahead of the main pulse, because the string's
//! stiffness makes them travel faster, and that the bridge keeps feeding once per cycle; of the
//! two packets a finger pluck starts with (one in each half of the waveform), the second fades.
//!
//! Over a span of a nut-force signal, [`fold_precursor`] measures that shape by synchronous
//! averaging:
//!
//! 1. the span's period, from its fundamental's frequency ([`super::peak_frequency_hz`] within
//!    10 % of the nominal);
//! 2. the high band, where the packet is sought, and the low band, where the main pulse is (each
//!    from one FFT of the span with a margin on either side, the bins outside the band zeroed: a
//!    zero-phase filter, so the packet and the pulse keep their places);
//! 3. the high band's energy `h²` and the low band folded on that period into [`PHASE_BINS`]
//!    phase bins (each bin the mean of its samples);
//! 4. the packet: the quarter period (circularly) that holds the most folded energy, its share
//!    of the whole period's, and its centre; the opposite half period's share;
//! 5. the main pulse: the phase of the folded low band's steepest change, and the packet's lead
//!    on it as a fraction of the period.
//!
//! A packet locked to the period keeps its place through the fold; high partials that merely
//! beat with each other drift through the period and fold into a flat profile (a quarter holds
//! about a quarter of the energy). Offline only: it allocates.

use super::{peak_frequency_hz, REAL_PLANNER};

/// Phase bins of one period in the fold.
pub const PHASE_BINS: usize = 64;

/// The fold of one span of a signal on its period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrecursorFold {
    /// The span's period, samples.
    pub period_samples: f64,
    /// The share of the high band's energy in the quarter period that holds the most of it.
    pub packet_share: f64,
    /// The share in the half period centred opposite that quarter's centre.
    pub opposite_share: f64,
    /// How far the packet's centre lies ahead of the folded low band's steepest change, as a
    /// fraction of the period in `[0, 1)`.
    pub lead_periods: f64,
}

/// Folds `signal[start..end]` (samples at `sample_rate_hz`, a string near `nominal_hz`) on its
/// period and measures its high band (above `packet_above_hz`) against its main pulse (the
/// steepest change of the band below `pulse_below_hz`) as [`PrecursorFold`] describes.
///
/// Panics if the span is shorter than four nominal periods or runs past the signal.
pub fn fold_precursor(
    signal: &[f64],
    sample_rate_hz: f64,
    nominal_hz: f64,
    pulse_below_hz: f64,
    packet_above_hz: f64,
    start: usize,
    end: usize,
) -> PrecursorFold {
    let nominal_period = sample_rate_hz / nominal_hz;
    assert!(
        start < end && end <= signal.len() && (end - start) as f64 >= 4.0 * nominal_period,
        "the span must lie in the signal and hold four periods"
    );
    let span = &signal[start..end];
    let period = sample_rate_hz
        / peak_frequency_hz(span, sample_rate_hz, 0.9 * nominal_hz, 1.1 * nominal_hz);
    let (low_band, high_band) = split_bands(
        signal,
        start,
        end,
        pulse_below_hz / sample_rate_hz,
        packet_above_hz / sample_rate_hz,
    );
    let energy: Vec<f64> = high_band.iter().map(|h| h * h).collect();
    let energy_profile = fold(&energy, period);
    let waveform = fold(&low_band, period);

    let quarter = PHASE_BINS / 4;
    let total: f64 = energy_profile.iter().sum();
    let (packet_start, packet_energy) = (0..PHASE_BINS)
        .map(|first| (first, circular_sum(&energy_profile, first, quarter)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("the period has bins");
    let packet_centre = packet_start as f64 + quarter as f64 / 2.0;
    let opposite_first = (packet_start + quarter / 2 + PHASE_BINS / 4) % PHASE_BINS;
    let opposite_energy = circular_sum(&energy_profile, opposite_first, PHASE_BINS / 2);

    let steepest_bin = (0..PHASE_BINS)
        .max_by(|&a, &b| {
            let change = |bin: usize| (waveform[(bin + 1) % PHASE_BINS] - waveform[bin]).abs();
            change(a).total_cmp(&change(b))
        })
        .expect("the period has bins");
    let steepest = steepest_bin as f64 + 0.5;
    let lead = (steepest - packet_centre).rem_euclid(PHASE_BINS as f64) / PHASE_BINS as f64;
    PrecursorFold {
        period_samples: period,
        packet_share: packet_energy / total,
        opposite_share: opposite_energy / total,
        lead_periods: lead,
    }
}

/// `signal[start..end]` below `low_cutoff` and above `high_cutoff` (cycles per sample): the span
/// and a margin of up to a quarter of its length on either side (so the transform's wrap-around
/// falls outside the span), transformed once, and each band transformed back with the bins
/// outside it zeroed.
fn split_bands(
    signal: &[f64],
    start: usize,
    end: usize,
    low_cutoff: f64,
    high_cutoff: f64,
) -> (Vec<f64>, Vec<f64>) {
    let margin = (end - start) / 4;
    let first = start.saturating_sub(margin);
    let last = (end + margin).min(signal.len());
    let length = last - first;
    let (forward, inverse) = REAL_PLANNER.with(|planner| {
        let mut planner = planner.borrow_mut();
        (
            planner.plan_fft_forward(length),
            planner.plan_fft_inverse(length),
        )
    });
    let mut frame = forward.make_input_vec();
    frame.copy_from_slice(&signal[first..last]);
    let mut spectrum = forward.make_output_vec();
    forward
        .process(&mut frame, &mut spectrum)
        .expect("buffers come from the plan itself");
    let band = |keep: &dyn Fn(f64) -> bool| -> Vec<f64> {
        let mut part: Vec<_> = spectrum
            .iter()
            .enumerate()
            .map(|(bin, &value)| {
                if keep(bin as f64 / length as f64) {
                    value
                } else {
                    Default::default()
                }
            })
            .collect();
        // The real inverse wants the Nyquist bin's imaginary part zero, as a real input gives.
        if length.is_multiple_of(2) {
            if let Some(last_bin) = part.last_mut() {
                last_bin.im = 0.0;
            }
        }
        let mut output = inverse.make_output_vec();
        inverse
            .process(&mut part, &mut output)
            .expect("buffers come from the plan itself");
        output[start - first..end - first]
            .iter()
            .map(|value| value / length as f64)
            .collect()
    };
    (
        band(&|frequency| frequency < low_cutoff),
        band(&|frequency| frequency >= high_cutoff),
    )
}

/// The mean of `values` in each of [`PHASE_BINS`] bins of phase `(i / period) mod 1`.
fn fold(values: &[f64], period: f64) -> [f64; PHASE_BINS] {
    let mut sums = [0.0; PHASE_BINS];
    let mut counts = [0usize; PHASE_BINS];
    for (i, value) in values.iter().enumerate() {
        let phase = (i as f64 / period).fract();
        let bin = ((phase * PHASE_BINS as f64) as usize).min(PHASE_BINS - 1);
        sums[bin] += value;
        counts[bin] += 1;
    }
    for (sum, count) in sums.iter_mut().zip(counts) {
        *sum /= count.max(1) as f64;
    }
    sums
}

/// The sum of `width` consecutive bins from `first`, wrapping around the period.
fn circular_sum(profile: &[f64; PHASE_BINS], first: usize, width: usize) -> f64 {
    (first..first + width)
        .map(|bin| profile[bin % PHASE_BINS])
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const RATE: f64 = 44_100.0;

    /// A smooth wave at `frequency` (two harmonics, its one steepest change a rise at phase 0),
    /// plus a burst of its 26th harmonic (4.9 kHz) centred `lead` of a period before each rise, and a
    /// steady 3111 Hz tone beside it.
    fn wave_with_bursts(frequency: f64, lead: f64, burst_amplitude: f64, steady: f64) -> Vec<f64> {
        let period = RATE / frequency;
        (0..(RATE * 0.4) as usize)
            .map(|i| {
                let phase = (i as f64 / period).fract();
                let wave = (2.0 * PI * phase).sin() + 0.3 * (4.0 * PI * phase).sin();
                let offset = (phase + lead + 0.5).fract() - 0.5;
                let envelope = (-(offset * period / 8.0).powi(2)).exp();
                let time = i as f64 / RATE;
                wave + burst_amplitude * envelope * (2.0 * PI * 26.0 * i as f64 / period).sin()
                    + steady * (2.0 * PI * 3_111.0 * time).sin()
            })
            .collect()
    }

    #[test]
    fn a_locked_burst_is_found_ahead_of_the_rise() {
        let frequency = 189.0;
        let signal = wave_with_bursts(frequency, 0.1, 0.3, 0.0);
        let fold = fold_precursor(
            &signal,
            RATE,
            frequency * 1.02,
            2_000.0,
            2_000.0,
            4410,
            15_000,
        );
        assert!(
            (fold.period_samples - RATE / frequency).abs() < 0.05,
            "{fold:?}"
        );
        assert!(fold.packet_share > 0.9, "{fold:?}");
        assert!(fold.opposite_share < 0.02, "{fold:?}");
        assert!((fold.lead_periods - 0.1).abs() < 0.03, "{fold:?}");
    }

    #[test]
    fn a_steady_tone_folds_flat() {
        let frequency = 189.0;
        let signal = wave_with_bursts(frequency, 0.1, 0.0, 0.3);
        let fold = fold_precursor(&signal, RATE, frequency, 2_000.0, 2_000.0, 4410, 15_000);
        assert!(
            fold.packet_share < 0.3 && fold.opposite_share > 0.45,
            "{fold:?}"
        );
    }
}
