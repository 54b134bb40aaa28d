//! The plugin's default tier against the reference over a small grid of the playing range
//! (issue 15): keys low, middle and high, a moderate and the hardest velocity, each a single
//! pluck compared by the measures of `core/src/analysis/listening.rs`, the ones the bench's
//! playing-range grid reports (`cargo xtask bench`).
//!
//! The keys lie outside the stretch (keys 48–54 at the seed's geometry) where the bridge crest's
//! rest contact appears as the tension rises: there the tiers' tunings, each linearised about its
//! own rest state, part by up to 14 cents (the bench's worst case, an open target). Elsewhere the
//! live tier's sustained pitch agrees within about 2.3 cents (the modal string rests on the
//! thread only where the reference also rests on the crest; `docs/modal-tanpura.md` §8); this
//! test fails if that, or its band levels, or the reference's own tuning, parts.

use javari_core::analysis::cents;
use javari_core::analysis::listening::{compare, sustained_pitch_hz};
use javari_core::analysis::playing_range::{render, GridPoint, NOTE_SECONDS};
use javari_core::tanpura::quality::Quality;

const SAMPLE_RATE: f64 = 44_100.0;

#[test]
fn the_live_tier_sounds_like_the_reference_across_the_range() {
    let points: Vec<GridPoint> = [39u8, 57, 63]
        .iter()
        .flat_map(|&key| {
            [40u8, 127].map(|velocity| GridPoint {
                key,
                velocity,
                pluck_position_m: 0.35,
            })
        })
        .collect();
    // The reference renders dominate the time: one thread per pluck.
    let renders: Vec<(Vec<f64>, Vec<f64>)> = std::thread::scope(|scope| {
        let handles: Vec<_> = points
            .iter()
            .map(|point| {
                scope.spawn(move || {
                    (
                        render(Quality::Live, point, NOTE_SECONDS, SAMPLE_RATE),
                        render(Quality::Reference, point, NOTE_SECONDS, SAMPLE_RATE),
                    )
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|handle| handle.join().expect("render thread"))
            .collect()
    });
    for (point, (live, reference)) in points.iter().zip(&renders) {
        let nominal = point.nominal_hz();
        let difference = compare(live, reference, SAMPLE_RATE, nominal);
        let label = point.label();
        eprintln!("{label}: {difference:?}");
        // Measured: 0.1–2.25 cents, 2.9–10.4 dB.
        assert!(
            difference.sustained_cents.abs() <= 3.0,
            "{label}: sustained pitch {:.2} cents from the reference",
            difference.sustained_cents
        );
        assert!(
            difference.band_level_db <= 12.0,
            "{label}: band levels {:.1} dB RMS from the reference",
            difference.band_level_db
        );
        // The reference is tuned to the key (measured within 0.3 cents here).
        let reference_pitch = sustained_pitch_hz(reference, SAMPLE_RATE, nominal);
        assert!(
            cents(reference_pitch, nominal).abs() <= 1.0,
            "{label}: the reference sounds {:.2} cents from its key",
            cents(reference_pitch, nominal)
        );
    }
}

/// At the crest keys the studio tier shares the reference's rest state (its raised EI acts on
/// the vibration only, `tanpura/fd/mod.rs`, "Rest preload"), so with the linearised tuning of
/// both, plucks that lift the string off the crest or leave it there do so alike: at keys 49 and
/// 50, where every pluck from velocity 40 up lifts the reference's string off the crest,
/// measured within 0.80 cents and 2.7 dB. Before stop 34 the studio's raised EI also moved its
/// rest state, and key 49 at velocity 40 sounded 15.1 cents from the reference. (At a key where
/// the string is bistable, such as 53, the hardest pluck can still lift one tier's string off
/// the crest and not the other's: the calibration as played sets those strings' jawari.)
#[test]
fn the_studio_tier_sounds_like_the_reference_at_the_crest_keys() {
    let points: Vec<GridPoint> = [49u8, 50]
        .iter()
        .flat_map(|&key| {
            [40u8, 127].map(|velocity| GridPoint {
                key,
                velocity,
                pluck_position_m: 0.35,
            })
        })
        .collect();
    let renders: Vec<(Vec<f64>, Vec<f64>)> = std::thread::scope(|scope| {
        let handles: Vec<_> = points
            .iter()
            .map(|point| {
                scope.spawn(move || {
                    (
                        render(Quality::Studio, point, NOTE_SECONDS, SAMPLE_RATE),
                        render(Quality::Reference, point, NOTE_SECONDS, SAMPLE_RATE),
                    )
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|handle| handle.join().expect("render thread"))
            .collect()
    });
    for (point, (studio, reference)) in points.iter().zip(&renders) {
        let difference = compare(studio, reference, SAMPLE_RATE, point.nominal_hz());
        let label = point.label();
        eprintln!("{label}: {difference:?}");
        assert!(
            difference.sustained_cents.abs() <= 1.0,
            "{label}: sustained pitch {:.2} cents from the reference",
            difference.sustained_cents
        );
        assert!(
            difference.band_level_db <= 5.0,
            "{label}: band levels {:.1} dB RMS from the reference",
            difference.band_level_db
        );
    }
}
