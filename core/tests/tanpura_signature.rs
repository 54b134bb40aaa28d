//! The tanpura's signature, as shapes (seed 000, sections 5.2–5.3 and Figures 4–5): with bridge
//! and thread the nut force carries a formant band whose centre falls over the first seconds, fed
//! by energy moving up from the fundamental; with k_b = 0 beyond the thread the modes decay
//! independently and the upper partials' share of the energy never grows. Once a period a
//! packet of high frequencies (the precursor) reaches the nut ahead of the main pulse, the higher
//! ones the earlier, as the string's stiffness has them travel faster; of the finger pluck's
//! two packets the second fades.
//!
//! Every tier is held to the formant's shapes. The draft tier, whose upper band's share of the
//! nut force fell from the pluck on (0.030 at 0.05 s, 0.004 at 3 s; with k_b = 0 beyond the
//! thread 0.043 and 0.004), so that its bridge fed neither the formant nor the precursor, was
//! withdrawn in stop 62 (`docs/modal-tanpura.md` §14).

use javari_core::analysis::precursor::{fold_precursor, PrecursorFold};
use javari_core::analysis::{band_power, power_spectrum, spectral_centroid_hz};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};

/// The formant's signature must hold for every tier: the seed's FD scheme (reference), the modal
/// scheme on the reference's grid (fine, the default tier, and studio, the same string at the
/// reference's step) and on the continuous string's modes (live).
const TIERS: [Quality; 4] = Quality::ALL;

const SAMPLE_RATE: f64 = 44_100.0;
const WINDOW: usize = 8192;
const TIMES_S: [f64; 6] = [0.05, 0.2, 0.5, 1.0, 2.0, 3.0];

/// The nut force of the default pluck over `seconds`.
fn nut_force(settings: &VoiceSettings, seconds: f64) -> Vec<f64> {
    let mut voice = TanpuraVoice::new(settings, SAMPLE_RATE);
    voice.pluck(&Pluck::default());
    let length = (seconds * SAMPLE_RATE) as usize;
    (0..length).map(|_| voice.next_sample() as f64).collect()
}

/// (centroid of the band above 5.5 f0 in Hz, that band's share of the total power) per window.
fn nut_force_evolution(settings: &VoiceSettings) -> Vec<(f64, f64)> {
    let nut_force = nut_force(settings, TIMES_S[TIMES_S.len() - 1] + 0.2);
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

/// The precursor is held on the tiers whose string is the reference's grid (fine, studio) and on
/// the reference. The live tier carries the packet in the band above 10 f0 (a quarter period holds
/// 0.65 of it over 0.1–0.5 s, 0.10 of a period ahead of the main pulse) but not above 40 f0 (0.29,
/// as without the bridge beyond the thread): its modes stop at 20 kHz and its bridge points lie
/// 2 mm apart.
const PRECURSOR_TIERS: [Quality; 3] = [Quality::Fine, Quality::Studio, Quality::Reference];

/// The nut force's band above `packet_above_f0` times the fundamental, folded on the period over
/// `from_s..to_s`, against the main pulse of the band below 10 f0.
fn precursor(
    settings: &VoiceSettings,
    force: &[f64],
    packet_above_f0: f64,
    from_s: f64,
    to_s: f64,
) -> PrecursorFold {
    fold_precursor(
        force,
        SAMPLE_RATE,
        settings.fundamental_hz,
        10.0 * settings.fundamental_hz,
        packet_above_f0 * settings.fundamental_hz,
        (from_s * SAMPLE_RATE) as usize,
        (to_s * SAMPLE_RATE) as usize,
    )
}

/// Seed 000, section 5.2 and Figure 4, on the default pluck, each fold over part of the first
/// half second (`analysis::precursor`), the main pulse taken on the band below 10 f0. Measured on
/// fine / studio / reference: over 0.1–0.5 s a quarter period holds 0.70 / 0.71 / 0.71 of the
/// band above 10 f0, centred 0.13 / 0.12 / 0.13 of a period ahead of the main pulse; the band
/// above 40 f0 arrives earlier, 0.20 / 0.21 / 0.23 of a period ahead; the half period opposite
/// the packet holds 0.16 of the band over the first 0.1 s and 0.11–0.12 over 0.1–0.5 s. With
/// k_b = 0 beyond the thread a quarter holds 0.29, about what a band spread evenly over the
/// period gives (0.25) plus the beating of its strongest partials.
#[test]
fn a_precursor_reaches_the_nut_once_a_period_ahead_of_the_main_pulse() {
    for quality in PRECURSOR_TIERS {
        let settings = VoiceSettings {
            quality,
            ..VoiceSettings::default()
        };
        let force = nut_force(&settings, 0.6);
        let attack = precursor(&settings, &force, 10.0, 0.0, 0.1);
        let held = precursor(&settings, &force, 10.0, 0.1, 0.5);
        let highest = precursor(&settings, &force, 40.0, 0.1, 0.5);
        let summary = format!("{quality:?}: {attack:?} {held:?} {highest:?}");
        assert!(held.packet_share >= 0.6, "one packet a period: {summary}");
        assert!(
            (0.05..=0.25).contains(&held.lead_periods),
            "the packet ahead of the main pulse: {summary}"
        );
        assert!(
            highest.lead_periods > held.lead_periods && highest.lead_periods <= 0.4,
            "the higher band arrives the earlier: {summary}"
        );
        assert!(
            held.opposite_share < attack.opposite_share,
            "the pluck's second packet fades: {summary}"
        );

        let without = VoiceSettings {
            bridge_beyond_thread: false,
            ..settings
        };
        let free = precursor(&without, &nut_force(&without, 0.6), 10.0, 0.1, 0.5);
        assert!(
            free.packet_share <= 0.45,
            "{quality:?}: without the bridge beyond the thread the high band is not one packet: {free:?}"
        );
    }
}
