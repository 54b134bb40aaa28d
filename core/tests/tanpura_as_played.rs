//! Strings tuned by their sustained pitch as played (issue 11; `tanpura/as_played.rs`): at the
//! live tier (the plugin's default until stop 43), a note plucked at velocities 40 to 110, and
//! each first drone string as the drone plucks it, sounds within 2 cents of its target over
//! 0.3–1.5 s after the pluck. The jawari's tests below take the studio and reference tiers.
//!
//! The notes are those where the linearised tuning alone is furthest off at this tier (up to
//! 2.9 cents, `examples/as_played.rs`); the test checks that too, so that it would fail if
//! the calibration stopped being applied.

use javari_core::analysis::cents;
use javari_core::analysis::listening::sustained_pitch_hz;
use javari_core::engine::drone::DronePattern;
use javari_core::engine::{Engine, EngineEvent, EngineSettings, TimedEvent};
use javari_core::tanpura::as_played::{Calibration, CALIBRATION_SECONDS};
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::FirstString;

const SAMPLE_RATE: f64 = 44_100.0;
const TOLERANCE_CENTS: f64 = 2.0;

fn settings() -> EngineSettings {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    settings
}

/// Measures every string `notes` plucks with `settings`, on two threads.
fn calibrate(settings: &EngineSettings, notes: &[u8]) -> Vec<Calibration> {
    let requests = Engine::planned_strings(settings, notes);
    std::thread::scope(|scope| {
        let halves: Vec<_> = requests
            .chunks(requests.len().div_ceil(2).max(1))
            .map(|chunk| {
                scope.spawn(move || {
                    chunk
                        .iter()
                        .map(|request| Calibration::measure(request, SAMPLE_RATE))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        halves
            .into_iter()
            .flat_map(|half| half.join().expect("a calibration thread panicked"))
            .collect()
    })
}

/// The same string with its thread left where the player put it, centred by the two passes
/// alone.
fn unmoved(calibration: &Calibration) -> Calibration {
    Calibration {
        offset_cents: javari_core::tanpura::as_played::as_played_offset_cents(
            &calibration.request.settings,
            &calibration.request.pluck,
            calibration.request.velocities,
            SAMPLE_RATE,
        ),
        thread_offset_m: 0.0,
        ..*calibration
    }
}

/// One note-on at velocity `velocity` (0–1) and the output up to the end of the sustain window.
fn render(engine: &mut Engine, note: u8, velocity: f32) -> Vec<f64> {
    let samples = (CALIBRATION_SECONDS * SAMPLE_RATE).round() as usize;
    let mut output = vec![0.0f32; samples];
    let events = [TimedEvent {
        offset: 0,
        event: EngineEvent::NoteOn { note, velocity },
    }];
    for (index, block) in output.chunks_mut(64).enumerate() {
        let events: &[TimedEvent] = if index == 0 { &events } else { &[] };
        engine.process(events, block);
    }
    output.iter().map(|&x| f64::from(x)).collect()
}

#[test]
fn notes_sound_within_two_cents_at_velocities_40_to_110() {
    let settings = settings();
    let keys = [41u8, 50, 53, 55, 58];
    let calibrations = calibrate(&settings, &keys);
    assert_eq!(calibrations.len(), keys.len());
    let mut worst_linearised: f64 = 0.0;
    for &key in &keys {
        let target = settings.tuning.note_hz(key);
        let mut tuned = Engine::new(&settings, SAMPLE_RATE, 1);
        for calibration in &calibrations {
            tuned.set_calibration(calibration);
        }
        let mut linearised = Engine::new(&settings, SAMPLE_RATE, 1);
        for velocity in [40u8, 75, 110] {
            let velocity = f32::from(velocity) / 127.0;
            tuned.reset();
            let heard = sustained_pitch_hz(&render(&mut tuned, key, velocity), SAMPLE_RATE, target);
            let off = cents(heard, target);
            assert!(
                off.abs() <= TOLERANCE_CENTS,
                "key {key} at velocity {:.0}: {off:+.2} cents as played",
                velocity * 127.0
            );
            linearised.reset();
            let heard =
                sustained_pitch_hz(&render(&mut linearised, key, velocity), SAMPLE_RATE, target);
            worst_linearised = worst_linearised.max(cents(heard, target).abs());
        }
    }
    assert!(
        worst_linearised > TOLERANCE_CENTS,
        "the linearised tuning is already within {TOLERANCE_CENTS} cents ({worst_linearised:.2}): \
         these keys no longer test the calibration"
    );
}

#[test]
fn every_first_drone_string_sounds_within_two_cents_as_the_drone_plucks_it() {
    for first_string in FirstString::ALL {
        let mut settings = settings();
        settings.drone.enabled = true;
        settings.drone.first_string = first_string;
        settings.drone.pattern = DronePattern::Four;
        // The second string comes 12 s later: the window hears the first string alone.
        settings.drone.tempo_sync = false;
        settings.drone.free_tempo_bpm = 20.0;
        settings.drone.pluck_spacing_beats = 4.0;
        // Sa = D3: the first strings lie where the linearised tuning is furthest off.
        let sa = 50u8;
        let calibrations = calibrate(&settings, &[sa]);
        let mut engine = Engine::new(&settings, SAMPLE_RATE, 4);
        for calibration in &calibrations {
            engine.set_calibration(calibration);
        }
        let target = settings.tuning.note_hz(sa) * first_string.ratio();
        let heard = sustained_pitch_hz(&render(&mut engine, sa, 1.0), SAMPLE_RATE, target);
        let off = cents(heard, target);
        assert!(
            off.abs() <= TOLERANCE_CENTS,
            "first string {first_string:?} on Sa = {sa}: {off:+.2} cents as played"
        );
    }
}

/// Issue 11 at the reference tier (`render`'s default): where the string at rest just touches
/// the bridge's crest (keys 51 and 52 with the seed's 40 mm thread), a soft pluck stays on the
/// crest and a firm one lifts it off, and no tension centres both within 2 cents. The
/// calibration then moves the string's thread by at most 0.3 mm, as a player sets the jawari,
/// and the note sounds within 2 cents at velocities 40 to 110 through the engine, with its level
/// above 2 kHz kept within 3 dB of the unmoved string's. Without the move the same string is
/// more than 2 cents off, so the test fails if the engine stopped applying it.
#[test]
fn reference_notes_at_the_crest_settle_with_the_thread_moved_as_a_player_sets_it() {
    use javari_core::tanpura::as_played::{brightness_db, THREAD_STEPS, THREAD_STEP_M};
    let mut settings = settings();
    settings.voice.quality = Quality::Reference;
    let keys = [51u8, 52];
    let calibrations = calibrate(&settings, &keys);
    assert_eq!(calibrations.len(), keys.len());
    std::thread::scope(|scope| {
        for (&key, calibration) in keys.iter().zip(&calibrations) {
            let settings = &settings;
            scope.spawn(move || {
                let moved_m = calibration.thread_offset_m;
                assert!(
                    moved_m != 0.0 && moved_m.abs() <= THREAD_STEPS as f64 * THREAD_STEP_M + 1e-12,
                    "key {key}: thread moved by {:.3} mm",
                    moved_m * 1e3
                );
                let unmoved = unmoved(calibration);
                let target = settings.tuning.note_hz(key);
                let mut worst = [0.0f64; 2];
                let mut brightness = [0.0f64; 2];
                for (index, calibration) in [calibration, &unmoved].into_iter().enumerate() {
                    let mut engine = Engine::new(settings, SAMPLE_RATE, 1);
                    engine.set_calibration(calibration);
                    for velocity in [40u8, 75, 110] {
                        engine.reset();
                        let signal = render(&mut engine, key, f32::from(velocity) / 127.0);
                        let heard = sustained_pitch_hz(&signal, SAMPLE_RATE, target);
                        worst[index] = worst[index].max(cents(heard, target).abs());
                        if velocity != 75 {
                            brightness[index] += 0.5 * brightness_db(&signal, SAMPLE_RATE);
                        }
                    }
                }
                assert!(
                    worst[0] <= TOLERANCE_CENTS,
                    "key {key}: {:.2} cents off as played with the thread moved by {:+.2} mm",
                    worst[0],
                    moved_m * 1e3
                );
                assert!(
                    worst[1] > TOLERANCE_CENTS,
                    "key {key}: already within {TOLERANCE_CENTS} cents unmoved ({:.2})",
                    worst[1]
                );
                assert!(
                    brightness[0] >= brightness[1] - 3.0,
                    "key {key}: level above 2 kHz {:.1} dB moved against {:.1} dB unmoved",
                    brightness[0],
                    brightness[1]
                );
            });
        }
    });
}

/// A string can be bistable between ends that agree: the reference tier's key 54 plucked at
/// 0.20 m, centred by its soft and firm plucks alone, has them within
/// [`UNSETTLED_SPREAD_CENTS`] of each other while a pluck midway sounds more than 2 cents off
/// the note. The calibration checks that pluck too, and sets the jawari. (The studio tier at
/// 2× oversampling was bistable there too; at 3× its ends alone lie 5.1 cents apart, and its
/// jawari is the reference's.)
#[test]
fn a_string_bistable_between_agreeing_ends_gets_its_jawari_set() {
    use javari_core::tanpura::as_played::UNSETTLED_SPREAD_CENTS;
    let mut settings = settings();
    settings.voice.quality = Quality::Reference;
    settings.pluck.position_m = 0.20;
    let key = 54u8;
    let calibration = calibrate(&settings, &[key])[0];
    assert!(
        calibration.thread_offset_m != 0.0,
        "the thread was not moved"
    );
    let unmoved = unmoved(&calibration);
    let target = settings.tuning.note_hz(key);
    let heard = |calibration: &Calibration| {
        std::thread::scope(|scope| {
            let handles: Vec<_> = [40u8, 75, 110]
                .map(|velocity| {
                    let settings = &settings;
                    scope.spawn(move || {
                        let mut engine = Engine::new(settings, SAMPLE_RATE, 1);
                        engine.set_calibration(calibration);
                        let signal = render(&mut engine, key, f32::from(velocity) / 127.0);
                        cents(sustained_pitch_hz(&signal, SAMPLE_RATE, target), target)
                    })
                })
                .into_iter()
                .collect();
            handles
                .into_iter()
                .map(|handle| handle.join().expect("a render panicked"))
                .collect::<Vec<f64>>()
        })
    };
    let [soft, midway, firm] = heard(&unmoved)[..] else {
        unreachable!()
    };
    assert!(
        (soft - firm).abs() <= UNSETTLED_SPREAD_CENTS,
        "the ends alone would have called it unsettled: {soft:.2}, {firm:.2} cents"
    );
    assert!(
        midway.abs() > TOLERANCE_CENTS,
        "midway already within {TOLERANCE_CENTS} cents unmoved: {midway:.2}"
    );
    let moved = heard(&calibration);
    assert!(
        moved.iter().all(|off| off.abs() <= TOLERANCE_CENTS),
        "as played with the thread moved by {:+.2} mm: {moved:.2?} cents",
        calibration.thread_offset_m * 1e3
    );
}

/// A string of `settings` at `key` calibrated as played, at the studio tier and at the reference
/// (on two threads): each tier's thread move and its sustained pitches at `velocities`, cents
/// from the note.
fn studio_and_reference_as_played(
    settings: &EngineSettings,
    key: u8,
    velocities: [u8; 2],
) -> [(f64, [f64; 2]); 2] {
    let target = settings.tuning.note_hz(key);
    let heard = |quality: Quality| {
        let mut settings = *settings;
        settings.voice.quality = quality;
        let calibration = calibrate(&settings, &[key])[0];
        let mut engine = Engine::new(&settings, SAMPLE_RATE, 1);
        engine.set_calibration(&calibration);
        let pitches = velocities.map(|velocity| {
            engine.reset();
            let signal = render(&mut engine, key, f32::from(velocity) / 127.0);
            cents(sustained_pitch_hz(&signal, SAMPLE_RATE, target), target)
        });
        (calibration.thread_offset_m, pitches)
    };
    std::thread::scope(|scope| {
        let studio = scope.spawn(|| heard(Quality::Studio));
        let reference = heard(Quality::Reference);
        [
            studio.join().expect("the studio's calibration panicked"),
            reference,
        ]
    })
}

/// One jawari for the instrument (issue 15; `as_played.rs`, *One jawari for the instrument*):
/// the studio tier's string rests where the reference's rests, and its calibration takes the
/// reference's thread move. Set on its own scheme, the studio's jawari for key 54 plucked at
/// 0.20 m lay a step (0.05 mm) from the reference's, and its softest touch stayed on the crest
/// where the reference's lifted off: 14.8 cents apart.
#[test]
fn the_studio_plays_the_jawari_the_reference_sets() {
    let mut settings = settings();
    settings.pluck.position_m = 0.20;
    let [studio, reference] = studio_and_reference_as_played(&settings, 54, [1, 127]);
    assert!(
        reference.0 != 0.0,
        "the reference's jawari was not set: the case this test is about is gone"
    );
    assert!(
        (studio.0 - reference.0).abs() < 1e-12,
        "thread moved by {:+.3} mm (studio) and {:+.3} mm (reference)",
        studio.0 * 1e3,
        reference.0 * 1e3
    );
    for (index, velocity) in [1, 127].into_iter().enumerate() {
        assert!(
            (studio.1[index] - reference.1[index]).abs() <= 1.0,
            "velocity {velocity}: studio {:.2} cents, reference {:.2} cents",
            studio.1[index],
            reference.1[index]
        );
    }
}

/// Key 53 (on the bench's grid since stop 57, which takes every crest key; every third key
/// before) is bistable at hard plucks: as played, the reference's pluck at velocity 127 stays on
/// the branch about 2.8 cents above its pluck at 115. The fine tier, stepped at the output rate,
/// takes the other branch at 127 (−6.67 against +3.54 cents, `examples/as_played.rs`, stop 57);
/// the same string stepped at twice the output rate (the studio of stops 57–58) followed the
/// reference at 110 and 127 but lay 2.52 cents from it at 115 (a sweep of velocities 88–127,
/// stop 58, `docs/tiers-log.md`): the contact's time step (`docs/modal-tanpura.md` §13). The
/// studio tier, stepped at the reference's own step, follows it at both, which this test holds
/// to 1 cent (measured: +0.60 and +3.53 cents against +0.70 and +3.54); at twice the output
/// rate it fails at 115 (+3.21 cents, stop 59).
#[test]
fn at_a_bistable_key_the_studio_plays_the_references_hard_plucks() {
    let key = 53u8;
    let [(_, studio), (_, reference)] =
        studio_and_reference_as_played(&settings(), key, [115, 127]);
    println!(
        "key {key} at velocities 115 and 127: studio {studio:.2?}, reference {reference:.2?} cents"
    );
    assert!(
        reference[1] - reference[0] > 1.5,
        "the reference's hardest pluck no longer sounds above its pluck at 115: the case this \
         test is about is gone ({reference:.2?} cents)"
    );
    for (index, velocity) in [115, 127].into_iter().enumerate() {
        assert!(
            (studio[index] - reference[index]).abs() <= 1.0,
            "velocity {velocity}: studio {:.2} cents, reference {:.2} cents",
            studio[index],
            reference[index]
        );
    }
}
