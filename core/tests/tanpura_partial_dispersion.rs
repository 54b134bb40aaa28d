//! The partials of a string barely plucked (velocity 1 of 127, the linear regime) on the bench's
//! one-string scene: the modal tiers' are the continuous string's, the reference grid's fall flat
//! with the square of the grid spacing (`docs/modal-tanpura.md`, section 9;
//! `examples/one_string_partials.rs`).
//!
//! The continuous string's partials are estimated by Richardson extrapolation from the reference
//! tier's grid (N = 200 at 4×) and the same scheme refined twice (N = 400 at 8×): the seed's
//! scheme is second order in space and time, so `f ≈ f₄₀₀ + (f₄₀₀ − f₂₀₀)/3`. Against that
//! estimate the live tier's first ten partials lie within half a cent (measured: 0.30 cents at
//! the tenth), while the reference's tenth lies more than two cents flat (measured: 2.7): the
//! one-cent target the issues set the tiers against the reference is below the reference's own
//! dispersion at the tenth partial.
//!
//! The yardsticks are `analysis::refined`'s offline strings: its unrefined FD string gives the
//! reference tier's partials, and its modal string is the live voice's output bit for bit.

use javari_core::analysis::refined::{modal_pluck, refined_reference_pluck};
use javari_core::analysis::{cents, first_partials_hz};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};

const OUTPUT_RATE_HZ: f64 = 44_100.0;
const SECONDS: f64 = 3.0;
const PARTIALS: usize = 10;

/// The bench's pluck at velocity 1 of 127.
fn soft_pluck() -> Pluck {
    let pluck = Pluck::default();
    Pluck {
        amplitude_m: pluck.amplitude_m / 127.0,
        ..pluck
    }
}

fn reference_partials(refinement: usize) -> Vec<f64> {
    let settings = VoiceSettings::default();
    let render = refined_reference_pluck(
        &settings,
        refinement,
        &soft_pluck(),
        SECONDS,
        OUTPUT_RATE_HZ,
    )
    .expect("the reference tier is an FD tier");
    first_partials_hz(
        &render.output,
        OUTPUT_RATE_HZ,
        settings.fundamental_hz,
        PARTIALS,
    )
}

fn tier_partials(quality: Quality) -> Vec<f64> {
    let settings = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let mut voice = TanpuraVoice::new(&settings, OUTPUT_RATE_HZ);
    voice.pluck(&soft_pluck());
    let output: Vec<f64> = (0..(SECONDS * OUTPUT_RATE_HZ) as usize)
        .map(|_| f64::from(voice.next_sample()))
        .collect();
    first_partials_hz(&output, OUTPUT_RATE_HZ, settings.fundamental_hz, PARTIALS)
}

#[test]
fn modal_partials_are_the_continuous_strings_and_the_reference_grids_fall_flat() {
    let coarse = reference_partials(1);
    let fine = reference_partials(2);
    let continuum: Vec<f64> = coarse
        .iter()
        .zip(&fine)
        .map(|(coarse, fine)| fine + (fine - coarse) / 3.0)
        .collect();
    let live = tier_partials(Quality::Live);
    for (k, (live, continuum)) in live.iter().zip(&continuum).enumerate() {
        let off = cents(*live, *continuum);
        assert!(
            off.abs() < 0.5,
            "live partial {} lies {off:.2} cents from the continuous string's",
            k + 1
        );
    }
    // The grid's error grows with the partial (Δx² k²): the fundamental is tuned, the tenth flat.
    let first = cents(coarse[0], continuum[0]);
    let tenth = cents(coarse[PARTIALS - 1], continuum[PARTIALS - 1]);
    assert!(
        first.abs() < 0.1,
        "reference fundamental {first:.2} cents off"
    );
    assert!(
        tenth < -2.0,
        "reference tenth partial only {tenth:.2} cents off"
    );
    // The voice's reference tier is the unrefined string of `refined_reference_pluck`.
    let voice = tier_partials(Quality::Reference);
    for (voice, coarse) in voice.iter().zip(&coarse) {
        assert!(cents(*voice, *coarse).abs() < 1e-6);
    }
}

#[test]
fn the_offline_modal_string_is_the_voices() {
    let settings = VoiceSettings {
        quality: Quality::Live,
        ..VoiceSettings::default()
    };
    let seconds = 0.2;
    let offline = modal_pluck(&settings, OUTPUT_RATE_HZ, 0, &Pluck::default(), seconds)
        .expect("the live tier is modal");
    let mut voice = TanpuraVoice::new(&settings, OUTPUT_RATE_HZ);
    voice.pluck(&Pluck::default());
    assert_eq!(offline.len(), (seconds * OUTPUT_RATE_HZ) as usize);
    for (index, sample) in offline.iter().enumerate() {
        assert_eq!(*sample, f64::from(voice.next_sample()), "sample {index}");
    }
}
