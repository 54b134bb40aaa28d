//! Helmholtz motion of the rounded-corner voice (issue 4): for a bow force inside Schelleng's
//! range, after the attack the bow-point velocity sticks for (1 − β) of each period and slips
//! for β (each within 2 % of the period), the bridge force is a sawtooth, and the pitch is
//! within 2 cents of the target.

mod bowed_common;
use bowed_common::*;

/// Correlation coefficient of one period of `signal` (resampled onto `n` points starting at
/// each candidate phase) with the ideal sawtooth of the Helmholtz bridge force, best over phase
/// and sign.
fn sawtooth_correlation(signal: &[f64], period: f64) -> f64 {
    let periods = (signal.len() as f64 / period).floor() as usize - 1;
    let n = period.round() as usize;
    // Average the signal over the periods (fractional period: interpolate) to one cycle.
    let mut cycle = vec![0.0; n];
    for (j, c) in cycle.iter_mut().enumerate() {
        for k in 0..periods {
            let t = k as f64 * period + j as f64 * period / n as f64;
            let i = t.floor() as usize;
            let frac = t - i as f64;
            *c += (1.0 - frac) * signal[i] + frac * signal[i + 1];
        }
        *c /= periods as f64;
    }
    let mean = cycle.iter().sum::<f64>() / n as f64;
    let centred: Vec<f64> = cycle.iter().map(|x| x - mean).collect();
    let norm = centred.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut best: f64 = 0.0;
    for shift in 0..n {
        let mut dot = 0.0;
        let mut saw_norm = 0.0;
        for (j, x) in centred.iter().enumerate() {
            let phase = ((j + shift) % n) as f64 / n as f64;
            let saw = phase - 0.5;
            dot += x * saw;
            saw_norm += saw * saw;
        }
        best = best.max(dot.abs() / (norm * saw_norm.sqrt()));
    }
    best
}

fn check(controls: Controls) {
    let mut voice = violin_string(&controls);
    let fmax = voice.schelleng_max_force_n();
    let period = controls.period_samples();
    let run = run_string(&mut voice, &controls, 1.5, 100.0);
    let p = pattern(&run.sticking, period);
    let stick_error = p.worst_stick_error(controls.bow_position, period);
    let slip_error = p.worst_slip_error(controls.bow_position, period);
    let bridge: Vec<f64> = run.outputs.iter().map(|o| o.bridge_force_n).collect();
    // Slip onsets are whole samples; over 100 periods that resolves the period to 1/99 sample.
    let pitch_cents = cents(p.mean_period(), period);
    let saw = sawtooth_correlation(&bridge, period);
    println!(
        "{controls:?} (F_max {fmax:.3} N): {:.3} slips/period, stick error {:.2} %, slip error {:.2} %, pitch {pitch_cents:+.3} cents, sawtooth correlation {saw:.4}",
        p.slips_per_period,
        100.0 * stick_error,
        100.0 * slip_error
    );
    assert!(
        (p.slips_per_period - 1.0).abs() < 0.03,
        "{} slips per period",
        p.slips_per_period
    );
    assert!(
        stick_error <= 0.02,
        "stick time off by {:.2} % of the period",
        100.0 * stick_error
    );
    assert!(
        slip_error <= 0.02,
        "slip time off by {:.2} % of the period",
        100.0 * slip_error
    );
    assert!(
        pitch_cents.abs() <= 2.0,
        "pitch off by {pitch_cents:.3} cents"
    );
    assert!(
        saw >= 0.95,
        "bridge force not sawtooth-like: correlation {saw:.4}"
    );
}

#[test]
fn helmholtz_motion_violin_a3_beta_tenth() {
    check(Controls::violin(0.1, 0.35));
}

#[test]
fn helmholtz_motion_violin_a4_fractional_delays() {
    // 48 kHz / 440 Hz = 109.09 samples: both round trips are fractional.
    check(Controls {
        sample_rate_hz: 48_000.0,
        pitch_hz: 440.0,
        bow_position: 0.13,
        bow_force_n: 0.3,
        bow_velocity_m_s: 0.1,
    });
}

#[test]
fn helmholtz_motion_wide_beta_high_rate() {
    check(Controls {
        sample_rate_hz: 96_000.0,
        pitch_hz: 196.0,
        bow_position: 0.2,
        bow_force_n: 0.12,
        bow_velocity_m_s: 0.1,
    });
}
