//! Extremes (issue 4): bow force 0 to 100 × F_max, bow velocity 0 to 5 m/s, β from 0.01 to 0.5,
//! sample rates 22.05 kHz to 384 kHz, pitches 41.2 Hz to 2 kHz, both tiers: no NaN or Inf, and
//! bounded output.
//!
//! Bounds. Rounded-corner voice: the friction force never exceeds μ_s F_b (sticking is only
//! accepted below it and μ(w) ≤ μ_s while sliding), and each reflection function is an inverted
//! pulse of area A < 1 with taps of one sign, so ‖r‖₁ = A. Every outgoing wave is an incoming
//! wave plus f/(2Z₀), hence sup|o| ≤ A sup|o| + μ_s F_b/(2Z₀), i.e. sup|o| ≤ M = μ_s F_b /
//! (2Z₀(1 − A_max)); then |v| ≤ 2 A M + μ_s F_b/(2Z₀) and |F_bridge| ≤ Z₀ (1 + A) M. Above a
//! few F_max these bounds are reached for real: the bow drags the string far before it lets go
//! (raucous motion), so the amplitude grows with F_b and is not limited by v_b/β.
//! Bow-table voice: the bow adds Δv·BowTable(Δv), whose magnitude never exceeds 0.25/S
//! (the table's maximum of x(xS + 0.75)⁻⁴ is at x = 0.25/S), and the loop loses 5 % per
//! period at the bridge, so per period at most P · 0.25/S is injected and sup|o| ≤
//! P · 0.25/(S · 0.05) + |v_b|; the test checks |v| and |F_bridge|/Z₀ against twice that.

mod bowed_common;
use bowed_common::*;
use javari_core::bowed::{
    BowTableString, BowedCapacity, BowedOutput, BowedString, BowedVoice, FrictionLaw,
    StringConstants,
};

const RATES: [f64; 6] = [22_050.0, 44_100.0, 48_000.0, 96_000.0, 192_000.0, 384_000.0];
const POSITIONS: [f64; 4] = [0.01, 0.05, 0.2, 0.5];
const VELOCITIES: [f64; 4] = [0.0, 0.01, 1.0, 5.0];
const FORCE_MULTIPLES: [f64; 4] = [0.0, 1.0, 10.0, 100.0];
const PITCHES: [f64; 3] = [41.2, 220.0, 2_000.0];

/// Drive `voice` over the grid; `bounds(rate, pitch, v_b, F_b)` gives the allowed
/// (|v|, |F_bridge|). Returns the largest fraction of either bound reached.
fn sweep<V: BowedVoice>(
    voice: &mut V,
    z0: f64,
    bounds: impl Fn(f64, f64, f64, f64) -> (f64, f64),
) -> f64 {
    let mut worst_fraction: f64 = 0.0;
    for &rate in &RATES {
        for &pitch in &PITCHES {
            for &beta in &POSITIONS {
                for &v_b in &VELOCITIES {
                    // F_max = 2 Z₀ v_b / (β (μ_s − μ_d)); with v_b = 0 use F_max at 1 m/s.
                    let f_max = 2.0 * z0 * v_b.max(1.0) / (beta * 0.5);
                    for &multiple in &FORCE_MULTIPLES {
                        let force = multiple * f_max;
                        voice.prepare(rate).unwrap();
                        voice.set_pitch_hz(pitch);
                        voice.set_bow_position(beta);
                        voice.set_bow_velocity_m_s(v_b);
                        voice.set_bow_force_n(force);
                        voice.set_body_enabled(true);
                        let (velocity_bound, force_bound) = bounds(rate, pitch, v_b, force);
                        let samples = (0.03 * rate) as usize;
                        for _ in 0..samples {
                            let BowedOutput {
                                bridge_force_n,
                                bow_point_velocity_m_s,
                                radiated,
                            } = voice.next_sample();
                            let case = format!("{rate} Hz, {pitch} Hz, β {beta}, v_b {v_b} m/s, F_b {multiple} × F_max");
                            assert!(
                                bridge_force_n.is_finite()
                                    && bow_point_velocity_m_s.is_finite()
                                    && radiated.is_finite(),
                                "non-finite output at {case}"
                            );
                            if v_b == 0.0 || force == 0.0 {
                                // Nothing excites the string: it stays at rest.
                                assert_eq!(bow_point_velocity_m_s, 0.0, "{case}");
                                assert_eq!(bridge_force_n, 0.0, "{case}");
                                continue;
                            }
                            assert!(
                                bow_point_velocity_m_s.abs() <= velocity_bound,
                                "|v| = {bow_point_velocity_m_s} > {velocity_bound} at {case}"
                            );
                            assert!(
                                bridge_force_n.abs() <= force_bound,
                                "|F| = {bridge_force_n} > {force_bound} at {case}"
                            );
                            worst_fraction = worst_fraction
                                .max(bow_point_velocity_m_s.abs() / velocity_bound)
                                .max(bridge_force_n.abs() / force_bound);
                        }
                    }
                }
            }
        }
    }
    worst_fraction
}

#[test]
fn rounded_corner_voice_stays_finite_and_bounded_at_extremes() {
    let constants = StringConstants::violin_a();
    let mut voice = BowedString::new(BowedCapacity::default(), constants);
    let z0 = constants.wave_impedance_n_s_m();
    let mu_s = voice.friction().static_coefficient();
    let area = constants.bridge_pulse.area.max(constants.nut_pulse.area);
    let worst = sweep(&mut voice, z0, |_, _, _, force| {
        let bow_wave = mu_s * force / (2.0 * z0);
        let outgoing = bow_wave / (1.0 - area);
        (
            2.0 * area * outgoing + bow_wave,
            z0 * (1.0 + area) * outgoing,
        )
    });
    println!("rounded corner: worst fraction of the passivity bound reached {worst:.4}");
}

#[test]
fn bow_table_voice_stays_finite_and_bounded_at_extremes() {
    let constants = StringConstants::violin_a();
    let mut voice = BowTableString::new(BowedCapacity::default(), constants);
    let z0 = constants.wave_impedance_n_s_m();
    let worst = sweep(&mut voice, z0, |rate, pitch, v_b, _| {
        // Slope S ≥ 1, so the bow wave is at most 0.25 m/s per sample.
        let period = rate / pitch.min(0.25 * rate);
        let outgoing = period * 0.25 / 0.05 + v_b.abs();
        (2.0 * 2.0 * outgoing, 2.0 * z0 * 2.0 * outgoing)
    });
    println!("bow table: worst fraction of the bound reached {worst:.4}");
}

#[test]
fn non_finite_inputs_are_ignored() {
    let controls = Controls::violin(0.1, 0.35);
    let mut voice = violin_string(&controls);
    for _ in 0..1000 {
        voice.next_sample();
    }
    voice.set_bow_force_n(f64::NAN);
    voice.set_bow_velocity_m_s(f64::INFINITY);
    voice.set_bow_position(f64::NAN);
    voice.set_pitch_hz(f64::NEG_INFINITY);
    assert_eq!(voice.pitch_hz(), 220.0);
    assert_eq!(voice.bow_position(), 0.1);
    for _ in 0..1000 {
        let o = voice.next_sample();
        assert!(o.radiated.is_finite() && o.bridge_force_n.is_finite());
    }
    let mut table = bow_table_string(&controls);
    table.set_bow_force_n(f64::NAN);
    table.set_pitch_hz(f64::NAN);
    for _ in 0..1000 {
        assert!(table.next_sample().radiated.is_finite());
    }
}

/// A friction law that breaks after a while, as a stand-in for any numerical blow-up.
#[derive(Clone, Copy)]
struct FailingFriction;

impl FrictionLaw for FailingFriction {
    fn static_coefficient(&self) -> f64 {
        0.8
    }
    fn dynamic_coefficient(&self) -> f64 {
        0.3
    }
    fn sliding_coefficient(&self, _slip_speed_m_s: f64) -> (f64, f64) {
        (0.3, 0.0)
    }
    fn outer_slip_speed(&self, _line: f64, _free: f64, _force: f64) -> Option<f64> {
        Some(f64::NAN)
    }
}

#[test]
fn nan_inside_the_model_silences_and_resets_the_voice() {
    let controls = Controls::violin(0.1, 0.35);
    let mut voice = BowedString::with_friction(
        BowedCapacity::default(),
        StringConstants::violin_a(),
        FailingFriction,
    );
    apply(&mut voice, &controls);
    let mut first_silenced = None;
    for n in 0..20_000 {
        let o = voice.next_sample();
        assert!(
            o.bridge_force_n.is_finite()
                && o.bow_point_velocity_m_s.is_finite()
                && o.radiated.is_finite()
        );
        if n > 0 && o == BowedOutput::default() {
            first_silenced = Some(n);
            break;
        }
    }
    // The first slip hits the NaN: that sample is silenced and every state zeroed, so with the
    // bow lifted the string is exactly at rest afterwards.
    assert!(first_silenced.is_some(), "the NaN was never detected");
    voice.set_bow_force_n(0.0);
    for _ in 0..100 {
        assert_eq!(voice.next_sample(), BowedOutput::default());
    }
}
