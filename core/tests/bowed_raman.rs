//! Raman's limit (issue 4; Woodhouse 1993, section 2): single-tap reflection functions −λ with
//! λ → 1 and whole-sample round trips p = βP and q = (1 − β)P. The bow-point velocity must be
//! the ideal two-level Helmholtz waveform: v_b while sticking for (1 − β)P, −v_b(1/β − 1)
//! while slipping for βP, each level within 1 %.
//!
//! Raman's model with λ → 1 is only stable while α = ζ/ε stays below Woodhouse's threshold
//! (eq. 13: n/2 for β = 1/n, n even), with ε = 1 − λ and ζ = k F_b Y₀/2 from the slope of the
//! friction curve at the Helmholtz slip speed v_b/β (eq. 3). With ε = 5·10⁻⁴ that asks for a
//! friction curve nearly flat at that slip speed, v₀ = 0.01 m/s here. The companion test runs
//! the note's v₀ = 0.1 m/s at α ≈ 70 and finds the motion no longer two-level, as eq. 12
//! predicts.

mod bowed_common;
use bowed_common::*;
use javari_core::bowed::{
    BowedCapacity, BowedString, FrictionLaw, HyperbolicFriction, ReflectionPulse, StringConstants,
};

const LAMBDA: f64 = 0.9995;

struct Measured {
    worst_level_error: f64,
    slip_fraction: f64,
    alpha: f64,
}

fn raman(
    bow_position: f64,
    period_samples: usize,
    bow_force_n: f64,
    decay_velocity_m_s: f64,
) -> Measured {
    let sample_rate_hz = 44_100.0;
    let controls = Controls {
        sample_rate_hz,
        pitch_hz: sample_rate_hz / period_samples as f64,
        bow_position,
        bow_force_n,
        bow_velocity_m_s: 0.1,
    };
    let single_tap = ReflectionPulse {
        width_s: 0.0,
        area: LAMBDA,
    };
    let constants = StringConstants {
        bridge_pulse: single_tap,
        nut_pulse: single_tap,
        ..StringConstants::violin_a()
    };
    let friction = HyperbolicFriction {
        decay_velocity_m_s,
        ..HyperbolicFriction::default()
    };
    let mut voice = BowedString::with_friction(BowedCapacity::default(), constants, friction);
    apply(&mut voice, &controls);

    // Single taps −λ at whole-sample delays p and q.
    let p = (bow_position * period_samples as f64).round() as usize;
    let bridge_taps: Vec<f64> = voice
        .bridge_reflection()
        .taps()
        .iter()
        .copied()
        .filter(|t| *t != 0.0)
        .collect();
    assert_eq!(bridge_taps, vec![-LAMBDA]);
    assert_eq!(voice.bridge_reflection().first_tap_delay(), p);
    assert_eq!(voice.nut_reflection().first_tap_delay(), period_samples - p);

    let v_b = controls.bow_velocity_m_s;
    let slip_speed = v_b / bow_position;
    let (_, slope) = friction.sliding_coefficient(slip_speed);
    let zeta = slope.abs() * bow_force_n / (2.0 * voice.wave_impedance_n_s_m());
    let alpha = zeta / (1.0 - LAMBDA);

    let run = run_string(&mut voice, &controls, 30.0, 50.0);
    let stick_level = v_b;
    let slip_level = -v_b * (1.0 / bow_position - 1.0);
    let mut worst_level_error: f64 = 0.0;
    let mut slipping = 0usize;
    for (output, &sticking) in run.outputs.iter().zip(&run.sticking) {
        let level = if sticking {
            stick_level
        } else {
            slipping += 1;
            slip_level
        };
        let error = (output.bow_point_velocity_m_s - level).abs() / level.abs();
        worst_level_error = worst_level_error.max(error);
    }
    let measured = Measured {
        worst_level_error,
        slip_fraction: slipping as f64 / run.outputs.len() as f64,
        alpha,
    };
    println!(
        "λ = {LAMBDA}, β = {bow_position}, P = {period_samples}, F_b = {bow_force_n} N, v₀ = {decay_velocity_m_s} m/s: α = {alpha:.2}, worst level error {:.4} %, slip fraction {:.4}",
        100.0 * measured.worst_level_error,
        measured.slip_fraction
    );
    measured
}

#[test]
fn raman_limit_gives_two_level_helmholtz_waveform() {
    for (bow_position, period, force) in [(0.1, 200, 0.1), (0.25, 160, 0.01)] {
        let m = raman(bow_position, period, force, 0.01);
        let n = 1.0 / bow_position;
        assert!(
            m.alpha < n / 2.0,
            "case must be inside Woodhouse's stable range"
        );
        assert!(
            m.worst_level_error <= 0.01,
            "level error {:.3} %",
            100.0 * m.worst_level_error
        );
        assert!(
            (m.slip_fraction - bow_position).abs() < 1e-9,
            "slip fraction {}",
            m.slip_fraction
        );
    }
}

#[test]
fn raman_beyond_woodhouse_threshold_is_not_two_level() {
    let m = raman(0.1, 200, 0.3, 0.1);
    assert!(m.alpha > 5.0);
    assert!(
        m.worst_level_error > 0.05,
        "level error {:.3} %",
        100.0 * m.worst_level_error
    );
}
