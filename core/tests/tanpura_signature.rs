//! The tanpura's signature, as shapes (seed 000, section 5.3 and Figure 5): with bridge and
//! thread the nut force carries a formant band whose centre falls over the first seconds, fed by
//! energy moving up from the fundamental; with k_b = 0 beyond the thread the modes decay
//! independently and the upper partials' share of the energy never grows.

use javari_core::analysis::{band_power, power_spectrum, spectral_centroid_hz};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};

/// The signature must hold for every discretisation: the seed's FD scheme (reference), the modal
/// scheme on the reference's grid (fine, the default tier) and on the continuous string's modes
/// (live).
const TIERS: [Quality; 3] = [Quality::Live, Quality::Fine, Quality::Reference];

const SAMPLE_RATE: f64 = 44_100.0;
const WINDOW: usize = 8192;
const TIMES_S: [f64; 6] = [0.05, 0.2, 0.5, 1.0, 2.0, 3.0];

/// (centroid of the band above 5.5 f0 in Hz, that band's share of the total power) per window.
fn nut_force_evolution(settings: &VoiceSettings) -> Vec<(f64, f64)> {
    let mut voice = TanpuraVoice::new(settings, SAMPLE_RATE);
    voice.pluck(&Pluck::default());
    let length = ((TIMES_S[TIMES_S.len() - 1] + 0.2) * SAMPLE_RATE) as usize;
    let nut_force: Vec<f64> = (0..length).map(|_| voice.next_sample() as f64).collect();
    let bin = SAMPLE_RATE / WINDOW as f64;
    let upper_band = 5.5 * settings.fundamental_hz;
    TIMES_S
        .iter()
        .map(|t| {
            let spectrum = power_spectrum(&nut_force, (t * SAMPLE_RATE) as usize, WINDOW, WINDOW);
            let total = band_power(&spectrum, bin, 20.0, 20_000.0);
            let upper = band_power(&spectrum, bin, upper_band, 20_000.0);
            let centroid = spectral_centroid_hz(&spectrum, bin, upper_band, 15_000.0);
            (centroid, upper / total)
        })
        .collect()
}

#[test]
fn with_bridge_and_thread_the_formant_centre_falls_and_energy_moves_up() {
    for quality in TIERS {
        let evolution = nut_force_evolution(&VoiceSettings {
            quality,
            ..VoiceSettings::default()
        });
        for pair in evolution.windows(2) {
            assert!(
                pair[1].0 < pair[0].0,
                "{quality:?}: the formant centre must fall: {evolution:?}"
            );
        }
        let (first, last) = (evolution[0].0, evolution[evolution.len() - 1].0);
        assert!(
            last < 0.6 * first,
            "{quality:?}: fell from {first} Hz only to {last} Hz"
        );
        // The collisions feed the upper partials: their share rises well above the pluck's own.
        let peak_share = evolution.iter().map(|e| e.1).fold(0.0, f64::max);
        assert!(
            peak_share > 1.5 * evolution[0].1,
            "{quality:?}: {evolution:?}"
        );
    }
}

#[test]
fn without_the_bridge_beyond_the_thread_upper_partials_never_gain_share() {
    for quality in TIERS {
        let settings = VoiceSettings {
            bridge_beyond_thread: false,
            quality,
            ..VoiceSettings::default()
        };
        let evolution = nut_force_evolution(&settings);
        for pair in evolution.windows(2) {
            assert!(
                pair[1].1 <= pair[0].1,
                "{quality:?}: upper-partial share grew: {evolution:?}"
            );
        }
    }
}
