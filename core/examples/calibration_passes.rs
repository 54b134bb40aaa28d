//! What a second centring pass of the as-played calibration (`tanpura/as_played.rs`) adds after
//! the first: `cargo run --release -p javari-core --example calibration_passes -- TIER…`
//! (default: reference and studio; keys 36–64, the default pluck, a note's velocities). One row
//! per key: the first pass's offset, the second pass's change of it, and the spread between the
//! soft and firm ends (cents) at each pass; then, per tier, the largest second-pass change after
//! a first pass of at most [`ONE_PASS_CENTS`], the bound that lets the calibration stop after one.

use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::as_played::{
    sustained_pitch_of_pluck_hz, NOTE_VELOCITIES, ONE_PASS_CENTS,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

const SAMPLE_RATE: f64 = 44_100.0;

/// The change of offset that centres the two ends at `offset` cents, and their spread.
fn pass(voice: &mut TanpuraVoice, nominal: f64, offset: f64) -> (f64, f64) {
    let target = nominal * (offset / 1200.0f64).exp2();
    let [soft, firm] = NOTE_VELOCITIES.map(|velocity| {
        let heard = sustained_pitch_of_pluck_hz(
            voice,
            target,
            nominal,
            &Pluck::default(),
            velocity,
            SAMPLE_RATE,
        );
        1200.0 * (heard / nominal).log2()
    });
    (-0.5 * (soft + firm), firm - soft)
}

fn main() {
    let mut tiers: Vec<Quality> = std::env::args()
        .skip(1)
        .filter_map(|name| Quality::from_name(&name))
        .collect();
    if tiers.is_empty() {
        tiers = vec![Quality::Reference, Quality::Studio];
    }
    let keys: Vec<u8> = (36..=64).collect();
    for quality in tiers {
        let next = AtomicUsize::new(0);
        let rows = Mutex::new(Vec::new());
        std::thread::scope(|scope| {
            for _ in 0..std::thread::available_parallelism().map_or(2, |n| n.get()) {
                scope.spawn(|| {
                    while let Some(&key) = keys.get(next.fetch_add(1, Ordering::Relaxed)) {
                        let nominal = note_to_hz(key);
                        let settings = VoiceSettings {
                            fundamental_hz: nominal,
                            quality,
                            ..VoiceSettings::default()
                        };
                        let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
                        let (first, first_spread) = pass(&mut voice, nominal, 0.0);
                        let (second, second_spread) = pass(&mut voice, nominal, first);
                        rows.lock().expect("a key thread panicked").push((
                            key,
                            first,
                            second,
                            first_spread,
                            second_spread,
                        ));
                    }
                });
            }
        });
        let mut rows = rows.into_inner().expect("a key thread panicked");
        rows.sort_by_key(|row| row.0);
        println!(
            "{} tier: key, first pass, second pass's change, spread at each (cents)",
            quality.name()
        );
        let mut largest_after_small: f64 = 0.0;
        for (key, first, second, first_spread, second_spread) in rows {
            println!(
                "{key:>3} {first:>+8.3} {second:>+8.3} {first_spread:>+8.2} {second_spread:>+8.2}"
            );
            if first.abs() <= ONE_PASS_CENTS {
                largest_after_small = largest_after_small.max(second.abs());
            }
        }
        println!(
            "largest second-pass change after a first pass of at most {ONE_PASS_CENTS} cent: \
             {largest_after_small:.3} cents"
        );
    }
}
