//! The cheap tier (issue 4; seed 004): the STK bow table min{(|Δv⁺|·S + 0.75)⁻⁴, 1},
//! S = 5 − 4·pressure, reproduced exactly, and the waveguide around it playing in tune.

mod bowed_common;
use bowed_common::*;
use javari_core::bowed::{bow_table_reflection, bow_table_slope, BowedVoice};

#[test]
fn bow_table_is_the_seed_formula() {
    // The seed's plotted ranges: Δv⁺ in [−1, 1], slopes 1, 2.5, 4, 5 and the meshgrid to 10.
    for i in -100..=100 {
        let dv = i as f64 / 100.0;
        for &slope in &[1.0, 2.5, 4.0, 5.0, 10.0] {
            let seed = (dv.abs() * slope + 0.75).powf(-4.0).min(1.0);
            let ours = bow_table_reflection(dv, slope);
            assert!(
                (ours - seed).abs() <= 4.0 * f64::EPSILON * seed,
                "Δv = {dv}, S = {slope}: {ours} vs {seed}"
            );
        }
    }
    // STK: setSlope(5 − 4 · normalised pressure).
    for i in 0..=10 {
        let pressure = i as f64 / 10.0;
        assert_eq!(bow_table_slope(pressure), 5.0 - 4.0 * pressure);
    }
}

#[test]
fn bow_table_pressure_follows_bow_force() {
    let mut voice = bow_table_string(&Controls::violin(0.1, 0.0));
    assert_eq!(voice.slope(), 5.0);
    voice.set_bow_force_n(1.0); // half of the default 2 N full-pressure force
    assert_eq!(voice.slope(), 3.0);
    voice.set_bow_force_n(50.0);
    assert_eq!(voice.slope(), 1.0);
}

fn pitch_error_cents(sample_rate_hz: f64, pitch_hz: f64, bow_position: f64) -> f64 {
    let controls = Controls {
        sample_rate_hz,
        pitch_hz,
        bow_position,
        bow_force_n: 1.0,
        bow_velocity_m_s: 0.1,
    };
    let mut voice = bow_table_string(&controls);
    let outputs = run_outputs(&mut voice, &controls, 1.5, 100.0);
    let bridge: Vec<f64> = outputs.iter().map(|o| o.bridge_force_n).collect();
    let peak = bridge.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    assert!(
        peak > 1e-3,
        "the bow-table string must sound (peak bridge force {peak} N)"
    );
    let measured_hz = fundamental_hz(&bridge, sample_rate_hz, pitch_hz);
    let error = 1200.0 * (measured_hz / pitch_hz).log2();
    println!("bow table {sample_rate_hz} Hz, {pitch_hz} Hz, β = {bow_position}: {error:+.3} cents");
    error
}

#[test]
fn bow_table_tier_plays_in_tune() {
    for &(rate, pitch, beta) in &[
        (44_100.0, 220.0, 0.127),
        (48_000.0, 440.0, 0.1),
        (48_000.0, 659.3, 0.2),
        (96_000.0, 196.0, 0.127),
    ] {
        let error = pitch_error_cents(rate, pitch, beta);
        assert!(
            error.abs() <= 2.0,
            "{pitch} Hz at {rate} Hz: {error:+.3} cents"
        );
    }
}
