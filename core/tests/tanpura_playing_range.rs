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
