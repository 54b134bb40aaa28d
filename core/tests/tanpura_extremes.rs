//! Stability at the extremes of every tanpura parameter, for every quality tier: k_b from 0 to
//! 1e12, losses from zero to the top of their range, the largest pluck, the thread at both ends
//! of its range and absent, output rates from 22.05 kHz to 384 kHz, every parameter changed
//! every sample, and denormal-level excitation. Each case: finite output, output bounded by a
//! few times the string tension, energy that does not grow (beyond round-off where the scheme is
//! conservative), and Newton cap hits counted and rare.

use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};

const SECONDS: f64 = 0.03;

#[derive(Debug)]
struct Outcome {
    peak_n: f64,
    tension_n: f64,
    unit_round_off: f64,
    worst_energy_growth: f64,
    cap_hits: u64,
    steps: u64,
    static_failures: u64,
    resets: u64,
}

fn run(settings: &VoiceSettings, pluck: &Pluck, sample_rate: f64) -> Outcome {
    let mut voice = TanpuraVoice::new(settings, sample_rate);
    voice.pluck(pluck);
    let initial = voice.string().energy_j();
    let mut previous = initial;
    let mut worst_growth = 0.0f64;
    let mut peak = 0.0f64;
    for _ in 0..(SECONDS * sample_rate) as usize {
        let sample = voice.next_sample() as f64;
        assert!(sample.is_finite(), "non-finite output for {settings:?}");
        peak = peak.max(sample.abs());
        let energy = voice.string().energy_j();
        assert!(energy.is_finite());
        worst_growth = worst_growth.max((energy - previous) / initial);
        previous = energy;
    }
    let stats = voice.newton_stats();
    Outcome {
        peak_n: peak,
        tension_n: voice.string().parameters().tension_n,
        unit_round_off: voice.string().unit_round_off(),
        worst_energy_growth: worst_growth,
        cap_hits: stats.cap_hits,
        steps: stats.steps,
        static_failures: voice.string().static_solve_failures(),
        resets: voice.string().non_finite_resets(),
    }
}

fn check(name: &str, outcome: &Outcome, conservative: bool) {
    assert_eq!(outcome.resets, 0, "{name}: {outcome:?}");
    assert_eq!(outcome.static_failures, 0, "{name}: {outcome:?}");
    assert!(
        outcome.peak_n <= 5.0 * outcome.tension_n,
        "{name}: output {} N against tension {} N",
        outcome.peak_n,
        outcome.tension_n
    );
    // Energy never grows: each step's H(n+1) − H(n) stays at round-off relative to H(0)
    // (the losses only remove energy; the lossless scheme conserves it). The modal tiers carry
    // their modes in f32: their H moves by a few units of f32 round-off per step.
    let f64_allowed: f64 = if conservative { 1e-11 } else { 1e-12 };
    let allowed = f64_allowed.max(16.0 * outcome.unit_round_off);
    assert!(
        outcome.worst_energy_growth <= allowed,
        "{name}: energy grew by {:e} of H(0)",
        outcome.worst_energy_growth
    );
    assert!(
        outcome.cap_hits * 100 <= outcome.steps,
        "{name}: {} cap hits in {} steps",
        outcome.cap_hits,
        outcome.steps
    );
}

fn every_tier(name: &str, settings: VoiceSettings, pluck: Pluck, sample_rate: f64) {
    let conservative = settings.gamma_per_s == 0.0 && settings.eta_s == 0.0;
    for quality in Quality::ALL {
        let settings = VoiceSettings {
            quality,
            ..settings
        };
        let outcome = run(&settings, &pluck, sample_rate);
        check(
            &format!("{name} at {}", quality.name()),
            &outcome,
            conservative,
        );
    }
}

#[test]
fn bridge_stiffness_from_zero_to_1e12() {
    for stiffness in [0.0, 1e4, 1e8, 1e10, 1e12] {
        let settings = VoiceSettings {
            bridge_stiffness_n_m2: stiffness,
            ..VoiceSettings::default()
        };
        every_tier(
            &format!("k_b = {stiffness:e}"),
            settings,
            Pluck::default(),
            44_100.0,
        );
    }
}

#[test]
fn losses_from_zero_to_the_top_of_their_range() {
    let (gamma_max, eta_max) = (VoiceSettings::GAMMA_RANGE.1, VoiceSettings::ETA_RANGE.1);
    for (gamma, eta) in [
        (0.0, 0.0),
        (gamma_max, 0.0),
        (0.0, eta_max),
        (gamma_max, eta_max),
    ] {
        let settings = VoiceSettings {
            gamma_per_s: gamma,
            eta_s: eta,
            ..VoiceSettings::default()
        };
        every_tier(
            &format!("γ = {gamma}, η = {eta:e}"),
            settings,
            Pluck::default(),
            44_100.0,
        );
    }
}

#[test]
fn largest_pluck_and_thread_at_both_ends_and_absent() {
    let largest = Pluck {
        amplitude_m: Pluck::AMPLITUDE_RANGE_M.1,
        width_m: Pluck::WIDTH_RANGE_M.0,
        position_m: 0.1,
    };
    every_tier("largest pluck", VoiceSettings::default(), largest, 44_100.0);
    for (enabled, position) in [(true, 0.030), (true, 0.045), (false, 0.040)] {
        let settings = VoiceSettings {
            thread_enabled: enabled,
            thread_position_m: position,
            ..VoiceSettings::default()
        };
        every_tier(
            &format!("thread {enabled} at {position}"),
            settings,
            largest,
            44_100.0,
        );
    }
}

#[test]
fn pitch_extremes() {
    let (lowest, highest) = VoiceSettings::FUNDAMENTAL_RANGE_HZ;
    for pitch in [lowest, highest] {
        let settings = VoiceSettings {
            fundamental_hz: pitch,
            ..VoiceSettings::default()
        };
        every_tier(
            &format!("f0 = {pitch}"),
            settings,
            Pluck::default(),
            44_100.0,
        );
    }
}

#[test]
fn output_rates_from_22050_to_384000() {
    for rate in [22_050.0, 48_000.0, 96_000.0, 192_000.0, 384_000.0] {
        // The cheapest and the most expensive tier bracket the others at every rate.
        for quality in [Quality::Live, Quality::Reference] {
            let settings = VoiceSettings {
                quality,
                ..VoiceSettings::default()
            };
            let outcome = run(&settings, &Pluck::default(), rate);
            check(&format!("{rate} Hz at {}", quality.name()), &outcome, false);
        }
    }
}

#[test]
fn every_parameter_changed_every_sample() {
    for quality in Quality::ALL {
        let base = VoiceSettings {
            quality,
            ..VoiceSettings::default()
        };
        let mut voice = TanpuraVoice::new(&base, 44_100.0);
        voice.pluck(&Pluck::default());
        let samples = 600;
        for k in 0..samples {
            let phase = k as f64 / samples as f64;
            let wobble = (phase * 37.0).sin();
            let settings = VoiceSettings {
                fundamental_hz: 150.0 + 50.0 * wobble,
                bridge_stiffness_n_m2: 10f64.powf(4.0 + 8.0 * phase),
                thread_enabled: k % 97 != 0,
                thread_position_m: 0.0375 + 0.0075 * wobble,
                bridge_beyond_thread: k % 2 == 0,
                gamma_per_s: 10.0 * (1.0 + wobble),
                eta_s: 5e-7 * (1.0 - wobble),
                nut_pickup_weight: phase,
                quality,
            };
            voice.set_settings(&settings);
            if k % 150 == 0 {
                voice.pluck(&Pluck::default());
            }
            let sample = voice.next_sample();
            assert!(sample.is_finite(), "{quality:?} at sample {k}");
            assert!(sample.abs() < 1e4, "{quality:?} at sample {k}: {sample}");
        }
        assert_eq!(voice.string().non_finite_resets(), 0);
        assert_eq!(voice.string().static_solve_failures(), 0);
    }
}

#[test]
fn denormal_level_excitation_sleeps_instead_of_computing() {
    for quality in Quality::ALL {
        let settings = VoiceSettings {
            quality,
            ..VoiceSettings::default()
        };
        let mut voice = TanpuraVoice::new(&settings, 44_100.0);
        voice.pluck(&Pluck {
            amplitude_m: 1e-300,
            ..Pluck::default()
        });
        let mut samples = 0;
        while voice.is_active() && samples < 10_000 {
            assert!(voice.next_sample().is_finite());
            samples += 1;
        }
        assert!(!voice.is_active(), "{quality:?} still computing");
        // Asleep, it outputs exact zeros and takes no steps.
        let steps = voice.newton_stats().steps;
        for _ in 0..1000 {
            assert_eq!(voice.next_sample(), 0.0);
        }
        assert_eq!(voice.newton_stats().steps, steps);
    }
}

#[test]
fn a_sleeping_string_wakes_exactly_on_its_next_pluck() {
    for quality in Quality::ALL {
        let settings = VoiceSettings {
            quality,
            gamma_per_s: 20.0,
            ..VoiceSettings::default()
        };
        let mut fresh = TanpuraVoice::new(&settings, 44_100.0);
        let mut slept = TanpuraVoice::new(&settings, 44_100.0);
        slept.pluck(&Pluck::default());
        let mut samples = 0;
        while slept.is_active() {
            slept.next_sample();
            samples += 1;
            assert!(samples < 44_100 * 10, "{quality:?} never fell asleep");
        }
        let steps_when_asleep = slept.newton_stats().steps;
        for _ in 0..500 {
            assert_eq!(slept.next_sample(), 0.0);
        }
        assert_eq!(
            slept.newton_stats().steps,
            steps_when_asleep,
            "asleep means no steps"
        );
        fresh.pluck(&Pluck::default());
        slept.pluck(&Pluck::default());
        for k in 0..2000 {
            let (a, b) = (fresh.next_sample(), slept.next_sample());
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "{quality:?} sample {k}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn changing_only_the_losses_keeps_the_tuning_a_full_retune_would_give() {
    for quality in Quality::ALL {
        let before = VoiceSettings {
            quality,
            ..VoiceSettings::default()
        };
        let after = VoiceSettings {
            gamma_per_s: 5.0,
            eta_s: 3e-7,
            nut_pickup_weight: 0.3,
            ..before
        };
        let mut changed = TanpuraVoice::new(&before, 44_100.0);
        changed.set_settings(&after);
        let fresh = TanpuraVoice::new(&after, 44_100.0);
        let (changed, fresh) = (changed.string(), fresh.string());
        assert_eq!(
            changed.as_fd().map(|string| string.config()),
            fresh.as_fd().map(|string| string.config()),
            "{quality:?}"
        );
        assert_eq!(
            changed.as_modal().map(|string| string.config()),
            fresh.as_modal().map(|string| string.config()),
            "{quality:?}"
        );
        assert_eq!(changed.rest_nut_force_n(), fresh.rest_nut_force_n());
    }
}
