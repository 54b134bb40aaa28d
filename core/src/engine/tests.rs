//! Engine behaviour with the real tanpura voice: levels, voice allocation, drone timing,
//! sample accuracy, block-size independence and smoothing.

use super::render::{render, RenderOptions, Score};
use super::tuning_memory::{PlannedTension, TuningMemory, TuningPlan};
use super::*;
use crate::tanpura::quality::Quality;

const RATE: f64 = 44_100.0;

fn note_on(offset: usize, note: u8) -> TimedEvent {
    TimedEvent {
        offset,
        event: EngineEvent::NoteOn {
            note,
            velocity: 1.0,
        },
    }
}

fn run(engine: &mut Engine, events: &[TimedEvent], samples: usize) -> Vec<f32> {
    let mut output = vec![0.0; samples];
    engine.process(events, &mut output);
    output
}

fn peak(signal: &[f32]) -> f32 {
    signal.iter().fold(0.0, |peak, x| peak.max(x.abs()))
}

#[test]
fn default_pluck_peaks_near_minus_12_dbfs() {
    // Note 54 (185.0 Hz) is the equal-tempered note nearest the reference string's pitch; the
    // pitch level factor makes the result independent of which note is used anyway.
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 1);
    let output = run(&mut engine, &[note_on(0, 54)], 22_050);
    let peak_dbfs = 20.0 * f64::from(peak(&output)).log10();
    println!("default pluck peak: {peak_dbfs:.2} dBFS");
    assert!((-15.0..=-9.0).contains(&peak_dbfs), "{peak_dbfs} dBFS");
}

#[test]
fn level_is_independent_of_pitch_within_6_db() {
    let mut peaks = Vec::new();
    for note in [36u8, 60, 84] {
        let mut engine = Engine::new(&EngineSettings::default(), RATE, 1);
        let output = run(&mut engine, &[note_on(0, note)], 11_025);
        peaks.push(20.0 * f64::from(peak(&output)).log10());
    }
    println!("peaks at notes 36, 60, 84: {peaks:?} dBFS");
    let spread = peaks.iter().cloned().fold(f64::MIN, f64::max)
        - peaks.iter().cloned().fold(f64::MAX, f64::min);
    assert!(spread < 6.0, "{peaks:?}");
}

#[test]
fn output_is_exactly_silent_before_a_note_and_sounds_from_its_sample() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 2);
    let output = run(&mut engine, &[note_on(300, 57)], 2_000);
    assert!(output[..300].iter().all(|x| *x == 0.0));
    // The decimator's group delay (about 29 samples at 4×) sets when the pluck shows.
    let onset = output.iter().position(|x| x.abs() > 1e-3).unwrap();
    assert!((300..300 + 45).contains(&onset), "onset at {onset}");
}

#[test]
fn same_note_replucks_its_string_and_new_notes_take_silent_voices() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 3);
    run(&mut engine, &[note_on(0, 60), note_on(10, 64)], 64);
    assert_eq!(engine.active_voices(), 2);
    assert_eq!(engine.slots[0].key, Some(StringKey::Note(60)));
    assert_eq!(engine.slots[1].key, Some(StringKey::Note(64)));
    run(&mut engine, &[note_on(0, 60)], 64);
    assert_eq!(
        engine.active_voices(),
        2,
        "C4 is plucked again on its own string"
    );
    assert_eq!(engine.slots[0].plucked_at, 64);
}

#[test]
fn note_off_does_not_stop_a_ringing_string() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 1);
    let off = TimedEvent {
        offset: 100,
        event: EngineEvent::NoteOff { note: 60 },
    };
    let output = run(&mut engine, &[note_on(0, 60), off], 4_410);
    assert!(peak(&output[4_000..]) > 0.01);
    assert!(engine.active_voices() == 1);
}

#[test]
fn stealing_takes_the_quietest_then_the_oldest_voice() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 2);
    let quiet = TimedEvent::note_on(0, 60, 0.1);
    // C4 quietly, then E4 loudly 0.3 s later; after another 0.3 s G4 needs a voice.
    run(&mut engine, &[quiet], 13_230);
    run(&mut engine, &[note_on(0, 64)], 13_230);
    assert!(engine.slots[0].level < engine.slots[1].level);
    run(&mut engine, &[note_on(0, 67)], 64);
    assert_eq!(
        engine.slots[0].key,
        Some(StringKey::Note(67)),
        "quiet C4 stolen"
    );
    assert_eq!(engine.slots[1].key, Some(StringKey::Note(64)));
}

#[test]
fn drone_plucks_the_four_strings_in_the_cycle_at_the_host_tempo() {
    let mut settings = EngineSettings::default();
    settings.drone.enabled = true;
    let mut engine = Engine::new(&settings, RATE, 4);
    engine.set_host_tempo(Some(120.0)); // one beat = 22 050 samples
    run(&mut engine, &[note_on(0, 48)], 22_050);
    assert_eq!(engine.active_voices(), 1);
    assert_eq!(engine.slots[0].key, Some(StringKey::Drone(0)));
    let sa_hz = pitch::note_to_hz(48);
    assert_eq!(engine.slots[0].fundamental_hz, sa_hz * 0.75);
    run(&mut engine, &[], 1);
    assert_eq!(engine.active_voices(), 2, "Sa plucked at exactly one beat");
    run(&mut engine, &[], 2 * 22_050);
    assert_eq!(engine.active_voices(), 4);
    assert_eq!(engine.slots[3].fundamental_hz, sa_hz * 0.5);
    assert_eq!(engine.slots[3].plucked_at, 3 * 22_050);
}

#[test]
fn drone_without_host_tempo_uses_the_free_tempo() {
    let mut settings = EngineSettings::default();
    settings.drone.enabled = true;
    settings.drone.free_tempo_bpm = 90.0; // 29 400 samples per beat
    let mut engine = Engine::new(&settings, RATE, 4);
    run(&mut engine, &[note_on(5, 50)], 29_405);
    assert_eq!(engine.active_voices(), 1);
    run(&mut engine, &[], 1);
    assert_eq!(engine.active_voices(), 2);
    assert_eq!(engine.slots[1].plucked_at, 29_405);
}

#[test]
fn block_size_does_not_change_the_output() {
    let mut score = Score::default();
    score.note(0.0, 0.1, 57, 1.0);
    score.note(0.0123, 0.1, 64, 0.6);
    let mut settings = EngineSettings::default();
    settings.drone.enabled = false;
    let options = |block_size| RenderOptions {
        block_size,
        tail_s: 0.1,
        voice_count: 2,
        ..RenderOptions::default()
    };
    let reference = render(&settings, &score, &options(4096), &mut |_, _| {});
    for block_size in [1, 37, 64] {
        let other = render(&settings, &score, &options(block_size), &mut |_, _| {});
        assert_eq!(other, reference, "block size {block_size}");
    }
}

#[test]
fn settings_glide_to_their_targets_in_the_smoothing_time() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 1);
    run(&mut engine, &[note_on(0, 60)], 64);
    let mut settings = EngineSettings::default();
    settings.voice.bridge_stiffness_n_m2 = 1e10;
    settings.voice.gamma_per_s = 2.0;
    engine.set_settings(&settings);
    run(&mut engine, &[], 32);
    let midway = engine.current_voice;
    assert!(midway.gamma_per_s > 0.6 && midway.gamma_per_s < 2.0);
    assert!(midway.bridge_stiffness_n_m2 > 1e8 && midway.bridge_stiffness_n_m2 < 1e10);
    run(&mut engine, &[], (SMOOTHING_TIME_S * RATE) as usize + 64);
    assert_eq!(engine.current_voice.gamma_per_s, 2.0);
    let stiffness = engine.current_voice.bridge_stiffness_n_m2;
    assert!((stiffness / 1e10 - 1.0).abs() < 1e-12, "{stiffness}");
    assert_eq!(engine.slots[0].voice.settings().gamma_per_s, 2.0);
}

#[test]
fn reset_renders_exactly_as_a_new_engine() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 2);
    let first = run(&mut engine, &[note_on(3, 62)], 1_000);
    engine.reset();
    let second = run(&mut engine, &[note_on(3, 62)], 1_000);
    assert_eq!(first, second);
}

/// The editor's snapshot (`crate::snapshot`) shows the loudest ringing string exactly as the
/// engine holds it, and the Newton statistics of all strings.
#[test]
fn snapshot_equals_the_loudest_string_exactly() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 4);
    let quiet = TimedEvent::note_on(0, 48, 0.1);
    run(&mut engine, &[quiet, note_on(10, 55)], 300);
    let mut snapshot = crate::snapshot::TanpuraSnapshot::default();
    for _ in 0..4 {
        run(&mut engine, &[], 97);
        engine.fill_snapshot(&mut snapshot);
        let loudest = engine
            .slots
            .iter()
            .max_by(|a, b| a.level.total_cmp(&b.level))
            .unwrap();
        assert_eq!(snapshot.fundamental_hz, pitch::note_to_hz(55));
        assert_eq!(loudest.fundamental_hz, snapshot.fundamental_hz);
        crate::snapshot::tests::assert_snapshot_is_string(&snapshot, loudest.voice.string());
        let mut all = crate::newton::NewtonStats::default();
        for slot in &engine.slots {
            all.merge(slot.voice.newton_stats());
        }
        assert_eq!(snapshot.newton, all);
        assert_eq!(snapshot.active_voices, 2);
    }
}

#[test]
fn quality_change_keeps_ringing_strings_and_applies_from_the_next_pluck() {
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 2);
    run(&mut engine, &[note_on(0, 57)], 2_000);
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    engine.set_settings(&settings);
    let after = run(&mut engine, &[], 4_410);
    assert!(peak(&after[4_000..]) > 0.01, "the ringing string goes on");
    assert_eq!(engine.slots[0].voice.settings().quality, Quality::Reference);
    run(&mut engine, &[note_on(0, 57)], 64);
    assert_eq!(engine.slots[0].voice.settings().quality, Quality::Live);
    assert_eq!(
        engine.active_voices(),
        1,
        "the same string, now at the new tier"
    );
}

fn radiated() -> EngineSettings {
    EngineSettings {
        tanpura_output: TanpuraOutput::Radiated,
        ..EngineSettings::default()
    }
}

#[test]
fn radiated_default_pluck_peaks_near_minus_12_dbfs() {
    let mut engine = Engine::new(&radiated(), RATE, 1);
    let output = run(&mut engine, &[note_on(0, 54)], 22_050);
    let peak_dbfs = 20.0 * f64::from(peak(&output)).log10();
    println!("radiated default pluck peak: {peak_dbfs:.2} dBFS");
    assert!((-15.0..=-9.0).contains(&peak_dbfs), "{peak_dbfs} dBFS");
}

#[test]
fn radiated_output_is_the_total_bridge_force_through_the_body() {
    // Two strings ringing together: the body hears their summed bridge force.
    let events = [note_on(0, 50), note_on(3_000, 57)];
    let mut radiating = Engine::new(&radiated(), RATE, 2);
    let heard = run(&mut radiating, &events, 11_025);
    let mut bridge_settings = EngineSettings::default();
    bridge_settings.voice.nut_pickup_weight = 0.0;
    let mut bridge = Engine::new(&bridge_settings, RATE, 2);
    let forces = run(&mut bridge, &events, 11_025);
    let mut body = Body::new(&TANPURA_BODY, RATE);
    let expected: Vec<f32> = forces
        .iter()
        .map(|force| body.tick(f64::from(*force)) as f32)
        .collect();
    assert_eq!(heard, expected);
    assert!(peak(&heard) > 1e-3);
    // And it is not the pickup signal.
    let mut pickup = Engine::new(&EngineSettings::default(), RATE, 2);
    assert_ne!(run(&mut pickup, &events, 11_025), heard);
}

#[test]
fn six_string_drone_plucks_every_string_on_the_host_beat_to_the_sample() {
    let mut settings = EngineSettings::default();
    settings.drone.enabled = true;
    settings.drone.pattern = drone::DronePattern::Six;
    settings.drone.first_string = crate::tanpura::FirstString::Dha;
    let mut engine = Engine::new(&settings, RATE, 8);
    engine.set_host_tempo(Some(93.0)); // 28 451.6… samples per beat
    let beat = 60.0 * RATE / 93.0;
    run(&mut engine, &[note_on(0, 50)], (5.5 * beat) as usize);
    let sa_hz = pitch::note_to_hz(50);
    let ratios = [5.0 / 6.0, 5.0 / 6.0, 1.0, 1.0, 0.5, 0.5];
    for (string, ratio) in ratios.iter().enumerate() {
        let slot = engine
            .slots
            .iter()
            .find(|slot| slot.key == Some(StringKey::Drone(string)))
            .unwrap_or_else(|| panic!("string {string} not plucked"));
        assert_eq!(slot.plucked_at, (string as f64 * beat).ceil() as u64);
        assert_eq!(slot.fundamental_hz, sa_hz * ratio);
    }
    assert_eq!(engine.active_voices(), 6);
}

#[test]
fn reference_pitch_and_fine_tuning_tune_notes_and_the_drone() {
    let mut settings = EngineSettings {
        tuning: pitch::Tuning {
            a4_hz: 415.0,
            fine_tune_cents: 25.0,
            as_played: true,
        },
        ..EngineSettings::default()
    };
    let expected = |note: u8| 415.0 * ((f64::from(note) - 69.0) / 12.0 + 25.0 / 1200.0).exp2();
    let mut engine = Engine::new(&settings, RATE, 2);
    run(&mut engine, &[note_on(0, 57)], 64);
    let played = engine.slots.iter().find(|slot| slot.key.is_some()).unwrap();
    assert!((played.fundamental_hz / expected(57) - 1.0).abs() < 1e-12);

    settings.drone.enabled = true;
    let mut drone = Engine::new(&settings, RATE, 4);
    run(&mut drone, &[note_on(0, 50)], 64);
    let first = drone.slots.iter().find(|slot| slot.key.is_some()).unwrap();
    assert!((first.fundamental_hz / (0.75 * expected(50)) - 1.0).abs() < 1e-12);
}

#[test]
fn nan_settings_neither_panic_nor_reach_the_output() {
    // Found by the engine_events fuzz target: a NaN pluck width reached `f64::clamp` as a bound
    // and panicked on the audio thread.
    let mut settings = EngineSettings::default();
    settings.voice.quality = crate::tanpura::quality::Quality::Live;
    settings.pluck.width_m = f64::NAN;
    settings.pluck.amplitude_m = f64::NAN;
    settings.pluck.position_m = f64::NAN;
    let mut engine = Engine::new(&settings, 44_100.0, 2);
    let plucked = run(&mut engine, &[note_on(0, 48)], 2000);
    assert!(plucked.iter().all(|x| x.is_finite()));
    assert!(
        peak(&plucked) > 0.0,
        "the default pluck stands in for the NaN one"
    );

    // A NaN drone tempo plays at the default tempo instead of plucking at every sample.
    settings.drone.enabled = true;
    settings.drone.tempo_sync = false;
    settings.drone.free_tempo_bpm = f64::NAN;
    let mut engine = Engine::new(&settings, 44_100.0, 4);
    let droned = run(&mut engine, &[note_on(0, 48)], 4410);
    assert!(droned.iter().all(|x| x.is_finite()));
    assert!(
        engine.active_voices() <= 1,
        "one pluck in the first 0.1 s at 60 bpm"
    );

    // A NaN glide and vibrato on the bowed string.
    settings.drone.enabled = false;
    settings.instrument = Instrument::Bowed;
    settings.bowed.player.glide_time_s = f64::NAN;
    settings.bowed.player.max_vibrato_cents = f64::NAN;
    let mut engine = Engine::new(&settings, 44_100.0, 1);
    let legato = [note_on(0, 60), note_on(100, 64)];
    let bowed = run(&mut engine, &legato, 4410);
    assert!(bowed.iter().all(|x| x.is_finite()));
    assert!(peak(&bowed) > 0.0);
}

#[test]
fn each_drone_string_has_its_own_fine_tuning_level_and_thread() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    settings.drone.enabled = true;
    settings.drone.strings[0] = drone::DroneString {
        fine_tune_cents: -13.0,
        level_db: -6.0,
        thread_offset_m: 0.002,
    };
    settings.drone.strings[1].fine_tune_cents = 7.0;
    let mut engine = Engine::new(&settings, RATE, 4);
    engine.set_host_tempo(Some(120.0));
    run(&mut engine, &[note_on(0, 50)], 22_100);
    let sa_hz = pitch::note_to_hz(50);
    let string = |index: usize| {
        engine
            .slots
            .iter()
            .find(|slot| slot.key == Some(StringKey::Drone(index)))
            .unwrap_or_else(|| panic!("string {index} not plucked"))
    };
    let (first, second) = (string(0), string(1));
    assert!(
        (first.fundamental_hz / (0.75 * sa_hz * (-13.0f64 / 1200.0).exp2()) - 1.0).abs() < 1e-12
    );
    assert!((second.fundamental_hz / (sa_hz * (7.0f64 / 1200.0).exp2()) - 1.0).abs() < 1e-12);
    let half = 10f64.powf(-6.0 / 20.0);
    assert!((first.level_factor / pitch_level_factor(first.fundamental_hz) - half).abs() < 1e-12);
    assert_eq!(
        second.level_factor,
        pitch_level_factor(second.fundamental_hz)
    );
    let thread = settings.voice.thread_position_m;
    assert!((first.voice.settings().thread_position_m - (thread + 0.002)).abs() < 1e-12);
    assert_eq!(second.voice.settings().thread_position_m, thread);
}

#[test]
fn a_drone_string_at_minus_60_db_is_60_db_quieter() {
    let peak_of_first_string = |level_db: f64| {
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Live;
        settings.drone.enabled = true;
        settings.drone.strings[0].level_db = level_db;
        let mut engine = Engine::new(&settings, RATE, 4);
        engine.set_host_tempo(Some(60.0));
        // The second string comes a beat (1 s) later.
        f64::from(peak(&run(&mut engine, &[note_on(0, 50)], 40_000)))
    };
    let ratio_db = 20.0 * (peak_of_first_string(-60.0) / peak_of_first_string(0.0)).log10();
    assert!((ratio_db + 60.0).abs() < 1e-3, "{ratio_db} dB");
}

#[test]
fn a_calibration_retunes_its_string_from_the_next_pluck_and_is_asked_for_once() {
    use crate::tanpura::as_played::{Calibration, NOTE_VELOCITIES};
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    let mut engine = Engine::new(&settings, RATE, 2);
    run(&mut engine, &[note_on(0, 57)], 64);
    // Without a calibration the string aims at its note, and the engine asks for one, once.
    let hz = pitch::note_to_hz(57);
    assert_eq!(engine.slots[0].tuned_hz, hz);
    let request = engine
        .take_wanted_calibration()
        .expect("a calibration is wanted");
    assert_eq!(request.velocities, NOTE_VELOCITIES);
    assert_eq!(request.settings.fundamental_hz, hz);
    assert_eq!(engine.take_wanted_calibration(), None);
    // What a renderer plans is the string the engine plucks (k_b equal to round-off: the engine's
    // passes through its logarithmic glide).
    let planned = Engine::planned_strings(&settings, &[57, 57]);
    assert_eq!(planned.len(), 1);
    let calibration = Calibration {
        request: planned[0],
        sample_rate_hz: RATE,
        offset_cents: 3.0,
        thread_offset_m: 0.1e-3,
    };
    assert!(calibration.is_for(&request, RATE));
    engine.set_calibration(&calibration);
    run(&mut engine, &[note_on(0, 57)], 64);
    let slot = &engine.slots[0];
    assert!((slot.tuned_hz / (hz * (3.0f64 / 1200.0).exp2()) - 1.0).abs() < 1e-12);
    assert_eq!(slot.fundamental_hz, hz);
    // The thread moves with it, and stays moved when a ringing string takes new settings.
    let thread = |engine: &Engine| engine.slots[0].voice.settings().thread_position_m;
    let moved = request.settings.thread_position_m + 0.1e-3;
    assert!((thread(&engine) - moved).abs() < 1e-12);
    settings.voice.gamma_per_s *= 1.01;
    engine.set_settings(&settings);
    run(&mut engine, &[], 4096);
    assert_eq!(
        engine.slots[0].voice.settings().gamma_per_s,
        settings.voice.gamma_per_s
    );
    assert!((thread(&engine) - moved).abs() < 1e-12);
    assert_eq!(engine.take_wanted_calibration(), None, "it is current now");

    // Off: the linearised tuning only, and nothing is asked for.
    settings.tuning.as_played = false;
    engine.set_settings(&settings);
    run(&mut engine, &[note_on(0, 57)], 64);
    assert_eq!(engine.slots[0].tuned_hz, hz);
}

fn stereo(engine: &mut Engine, events: &[TimedEvent], samples: usize) -> (Vec<f32>, Vec<f32>) {
    let (mut left, mut right) = (vec![0.0; samples], vec![0.0; samples]);
    for (index, (left, right)) in left.chunks_mut(256).zip(right.chunks_mut(256)).enumerate() {
        let events: &[TimedEvent] = if index == 0 { events } else { &[] };
        engine.process_stereo(events, left, right);
    }
    (left, right)
}

fn radiated_drone(width: f64) -> EngineSettings {
    let mut settings = radiated();
    settings.voice.quality = Quality::Live;
    settings.drone.enabled = true;
    settings.stereo_width = width;
    settings
}

#[test]
fn the_stereo_mid_is_the_mono_output_and_width_zero_is_two_equal_channels() {
    let settings = radiated_drone(1.0);
    let samples = 3 * 44_100;
    let mut mono_engine = Engine::new(&settings, RATE, 4);
    mono_engine.set_host_tempo(Some(120.0));
    let mut mono = vec![0.0f32; samples];
    for (index, block) in mono.chunks_mut(256).enumerate() {
        let events: &[TimedEvent] = if index == 0 { &[note_on(0, 50)] } else { &[] };
        mono_engine.process(events, block);
    }
    let mut stereo_engine = Engine::new(&settings, RATE, 4);
    stereo_engine.set_host_tempo(Some(120.0));
    let (left, right) = stereo(&mut stereo_engine, &[note_on(0, 50)], samples);
    let mut side_energy = 0.0;
    for ((left, right), mono) in left.iter().zip(&right).zip(&mono) {
        // (M − S) + (M + S) = 2M up to the rounding of the two sums.
        assert!(
            (0.5 * (left + right) - mono).abs() <= 1e-6 * (left.abs() + right.abs()),
            "{left} {right} {mono}"
        );
        side_energy += f64::from(left - right).powi(2);
    }
    assert!(side_energy > 0.0, "width 1 spreads the strings");

    let mut narrow = Engine::new(&radiated_drone(0.0), RATE, 4);
    narrow.set_host_tempo(Some(120.0));
    let (left, right) = stereo(&mut narrow, &[note_on(0, 50)], samples);
    assert_eq!(left, right);
    assert_eq!(left, mono);
}

#[test]
fn the_first_drone_string_sounds_on_the_left_and_the_last_on_the_right() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    settings.drone.enabled = true;
    settings.stereo_width = 1.0;
    let mut engine = Engine::new(&settings, RATE, 4);
    engine.set_host_tempo(Some(60.0));
    // The first string alone for its first second (pickup output: no body in between).
    let (left, right) = stereo(&mut engine, &[note_on(0, 50)], 40_000);
    let energy = |signal: &[f32]| signal.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>();
    assert!(energy(&left) > 0.0);
    assert_eq!(energy(&right), 0.0, "pan −1 at full width: left only");
    assert_eq!(drone_string_pan(3, 4), 1.0);
    assert_eq!(drone_string_pan(1, 5), -0.5);
}

/// Notes 45, 50, 55 and 60 plucked one sample apart, and the block of 64 samples they start in.
fn pluck_four_notes(engine: &mut Engine) {
    let notes: Vec<TimedEvent> = [45u8, 50, 55, 60]
        .iter()
        .enumerate()
        .map(|(index, &note)| note_on(index, note))
        .collect();
    run(engine, &notes, 64);
}

#[test]
fn a_glide_retunes_a_ringing_string_every_other_tick_and_each_reaches_the_target() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    let mut engine = Engine::new(&settings, RATE, 4);
    pluck_four_notes(&mut engine);
    assert_eq!(engine.active_voices(), 4);
    settings.voice.thread_position_m = 0.042;
    engine.set_settings(&settings);
    let threads = |engine: &Engine| -> Vec<f64> {
        engine
            .slots
            .iter()
            .map(|slot| slot.voice.settings().thread_position_m)
            .collect()
    };
    // The glide's ticks, then a round of the four strings at one retune every other tick.
    let ticks_per_retune = (RETUNE_INTERVAL / CONTROL_INTERVAL) as usize;
    let ticks =
        (SMOOTHING_TIME_S * RATE / CONTROL_INTERVAL as f64).ceil() as usize + 4 * ticks_per_retune;
    let mut before = threads(&engine);
    let mut last_retune: Option<usize> = None;
    for tick in 0..ticks {
        run(&mut engine, &[], CONTROL_INTERVAL as usize);
        let after = threads(&engine);
        let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
        assert!(changed <= 1, "tick {tick}: {changed} strings retuned");
        if changed == 1 {
            if let Some(last) = last_retune {
                assert!(tick - last >= 2, "retunes at ticks {last} and {tick}");
            }
            last_retune = Some(tick);
        }
        before = after;
    }
    for (index, thread) in threads(&engine).iter().enumerate() {
        assert!((thread - 0.042).abs() < 1e-12, "string {index}: {thread}");
    }
}

#[test]
fn a_drone_sa_set_in_the_settings_plays_without_a_held_note_and_stops_when_unset() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    settings.drone.enabled = true;
    settings.drone.sa_note = Some(50);
    let mut engine = Engine::new(&settings, RATE, 4);
    engine.set_host_tempo(Some(120.0));
    // No note: the first string (Pa) is plucked at once, tuned from D3.
    run(&mut engine, &[], 64);
    let first = engine
        .slots
        .iter()
        .find(|slot| slot.key == Some(StringKey::Drone(0)))
        .expect("the first string is plucked without a note");
    assert_eq!(first.plucked_at, 0);
    assert!((first.fundamental_hz / (0.75 * pitch::note_to_hz(50)) - 1.0).abs() < 1e-12);
    // A MIDI note does not move it.
    run(&mut engine, &[note_on(0, 57)], 22_050);
    let sa = engine
        .slots
        .iter()
        .find(|slot| slot.key == Some(StringKey::Drone(1)))
        .expect("the second string");
    assert!((sa.fundamental_hz / pitch::note_to_hz(50) - 1.0).abs() < 1e-12);
    // Back to the held note, with none held: the cycle stops.
    settings.drone.sa_note = None;
    engine.set_settings(&settings);
    run(
        &mut engine,
        &[crate::engine::TimedEvent {
            offset: 0,
            event: EngineEvent::NoteOff { note: 57 },
        }],
        64,
    );
    let plucks = |engine: &Engine| {
        engine
            .slots
            .iter()
            .filter(|slot| slot.key.is_some())
            .count()
    };
    let before = plucks(&engine);
    run(&mut engine, &[], 4 * 22_050);
    assert_eq!(plucks(&engine), before, "no pluck after the cycle stopped");
    assert_eq!(
        Engine::planned_strings(
            &EngineSettings {
                drone: drone::DroneSettings {
                    sa_note: Some(50),
                    ..settings.drone
                },
                ..settings
            },
            &[62, 64]
        )
        .len(),
        3,
        "a set Sa plans the drone's strings on Sa whatever the notes (Pa, Sa, low Sa)"
    );
}

/// A note-on whose string settings were tuned before configures its string at the tension
/// remembered then, without tuning it again: one voice plays A3, is stolen by C4 and then by A3
/// again, and the third note-on tunes nothing and sets the first one's tension bit for bit,
/// which is the tension a fresh voice tunes A3 to (within round-off).
#[test]
fn a_note_on_with_settings_tuned_before_takes_the_remembered_tension() {
    let settings = EngineSettings::default();
    let mut engine = Engine::new(&settings, RATE, 1);
    let tunings = |engine: &Engine| engine.slots[0].voice.tunings();
    let made = tunings(&engine);
    run(&mut engine, &[note_on(0, 57)], 64);
    assert_eq!(tunings(&engine), made + 1, "A3 is tuned");
    let a3_tension = engine.slots[0].voice.tension_n();
    let a3_settings = *engine.slots[0].voice.settings();
    assert_eq!(
        engine.tuning_memory().tension_n(&a3_settings),
        Some(a3_tension)
    );
    run(&mut engine, &[note_on(0, 60)], 64);
    assert_eq!(tunings(&engine), made + 2, "C4 is tuned");
    assert_ne!(engine.slots[0].voice.tension_n(), a3_tension);
    run(&mut engine, &[note_on(0, 57)], 64);
    assert_eq!(tunings(&engine), made + 2, "A3 comes from the memory");
    assert_eq!(
        engine.slots[0].voice.tension_n().to_bits(),
        a3_tension.to_bits()
    );
    let fresh = TanpuraVoice::new(&a3_settings, RATE);
    let relative = (fresh.tension_n() - a3_tension).abs() / a3_tension;
    assert!(relative < 1e-9, "{relative:e}");
}

/// A calibration handed over with the tension that tunes its string
/// ([`Engine::set_calibration_tuned`], as the plugin's tuning worker hands it) leaves the
/// string's next pluck nothing to tune: the calibrated A3 is configured at that tension bit for
/// bit, with the settings the calibration gives, where an engine handed the calibration alone
/// tunes the string on the note-on (to the same tension within round-off). A calibration for
/// another sample rate remembers nothing.
#[test]
fn a_calibration_handed_over_with_its_tension_leaves_the_next_pluck_nothing_to_tune() {
    let settings = EngineSettings::default();
    assert!(settings.tuning.as_played);
    let mut handed = Engine::new(&settings, RATE, 1);
    let mut alone = Engine::new(&settings, RATE, 1);
    let tunings = |engine: &Engine| engine.slots[0].voice.tunings();
    let (handed_made, alone_made) = (tunings(&handed), tunings(&alone));
    run(&mut handed, &[note_on(0, 57)], 64);
    run(&mut alone, &[note_on(0, 57)], 64);
    let request = handed
        .take_wanted_calibration()
        .expect("a calibration is wanted");
    let calibration = Calibration {
        request,
        sample_rate_hz: RATE,
        offset_cents: 3.0,
        thread_offset_m: 0.1e-3,
    };
    let calibrated = calibration
        .calibrated_settings()
        .expect("a finite calibration");
    let tension = calibration
        .calibrated_tension_n()
        .expect("a finite calibration");
    let elsewhere = Calibration {
        sample_rate_hz: 2.0 * RATE,
        ..calibration
    };
    let remembered = handed.tuning_memory().len();
    handed.set_calibration_tuned(&elsewhere, 0.5 * tension);
    assert_eq!(handed.tuning_memory().len(), remembered, "another rate's");
    handed.set_calibration_tuned(&calibration, tension);
    alone.set_calibration(&calibration);
    run(&mut handed, &[note_on(0, 57)], 64);
    run(&mut alone, &[note_on(0, 57)], 64);
    assert_eq!(
        tunings(&handed),
        handed_made + 1,
        "only the first A3 is tuned"
    );
    assert_eq!(
        tunings(&alone),
        alone_made + 2,
        "the calibrated A3 is tuned"
    );
    let voice = &handed.slots[0].voice;
    assert_eq!(*voice.settings(), calibrated);
    assert_eq!(voice.tension_n().to_bits(), tension.to_bits());
    let tuned = alone.slots[0].voice.tension_n();
    let relative = (tuned - tension).abs() / tension;
    assert!(relative < 1e-9, "{relative:e}");
}

/// A note-on that takes a voice from another note stops the old vibration without solving the
/// rest state it leaves ([`TanpuraVoice::stop`]): the retune to the new note is the only solve
/// of a rest state, and the voice plays on as one reset first does, to the bit.
#[test]
fn a_stolen_voice_is_stopped_without_solving_the_rest_state_it_leaves() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Fine;
    let rest_state_solves = |engine: &Engine| match engine.slots[0].voice.string() {
        crate::tanpura::tier_string::TierString::Modal(string) => string.rest_state_solves(),
        crate::tanpura::tier_string::TierString::FiniteDifference(_) => {
            panic!("the fine tier is modal")
        }
    };
    let mut stopped = Engine::new(&settings, RATE, 1);
    let mut reset = Engine::new(&settings, RATE, 1);
    stopped.prepare_tunings();
    reset.prepare_tunings();
    run(&mut stopped, &[note_on(0, 57)], 2048);
    run(&mut reset, &[note_on(0, 57)], 2048);
    let before = rest_state_solves(&stopped);
    let heard = run(&mut stopped, &[note_on(0, 60)], 4096);
    assert_eq!(
        rest_state_solves(&stopped),
        before + 1,
        "the retune's alone"
    );
    reset.slots[0].voice.reset();
    let expected = run(&mut reset, &[note_on(0, 60)], 4096);
    assert!(peak(&expected) > 1e-3);
    assert!(
        heard
            .iter()
            .zip(&expected)
            .all(|(a, b)| a.to_bits() == b.to_bits()),
        "a stopped voice plays as a reset one"
    );
}

/// [`Engine::prepare_tunings`] remembers a tension for every playable note (MIDI 16–95 at
/// A4 = 440 Hz), after which a phrase's note-ons tune no string, and the phrase sounds as it
/// does from an engine that tunes each string on its note-on (to round-off).
#[test]
fn prepared_tunings_leave_note_ons_nothing_to_tune_and_sound_the_same() {
    let settings = EngineSettings::default();
    let mut prepared = Engine::new(&settings, RATE, 4);
    let mut tuning = Engine::new(&settings, RATE, 4);
    prepared.prepare_tunings();
    let playable = (0..=127u8)
        .filter(|&note| settings.tuning.playable_note_hz(note).is_some())
        .count();
    assert_eq!(playable, 80);
    assert_eq!(prepared.tuning_memory().len(), playable);
    assert_remembers_every_tuning(&mut prepared, &mut tuning, [50, 57, 62, 69]);
}

/// Plays four notes 1500 samples apart on `remembering` and on `tuning`: `remembering` tunes
/// no string on their note-ons, `tuning` tunes each, and the two sound the same to 1e-5 of the
/// louder's peak (round-off).
fn assert_remembers_every_tuning(remembering: &mut Engine, tuning: &mut Engine, notes: [u8; 4]) {
    let (remembering_made, tuning_made) = (remembering.string_tunings(), tuning.string_tunings());
    let phrase: Vec<TimedEvent> = notes
        .iter()
        .enumerate()
        .map(|(index, &note)| note_on(1500 * index, note))
        .collect();
    let heard = run(remembering, &phrase, 9000);
    let expected = run(tuning, &phrase, 9000);
    assert_eq!(
        remembering.string_tunings(),
        remembering_made,
        "nothing tuned on a note-on"
    );
    assert_eq!(tuning.string_tunings(), tuning_made + 4);
    let loudest = peak(&expected);
    assert!(loudest > 1e-3, "{loudest}");
    let largest = heard
        .iter()
        .zip(&expected)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(largest <= 1e-5 * loudest, "{largest:e} of {loudest:e}");
}

/// After a change of the bridge's control the engine hands out one tuning plan, once (and none
/// for a change of the losses alone, which the tuning does not see). Its strings tuned off the
/// engine and handed back leave a phrase's note-ons nothing to tune once the control has
/// settled, and the phrase sounds as from an engine that tunes each string on its note-on (to
/// round-off); without them every note-on tunes its string.
#[test]
fn a_changed_bridge_is_tuned_from_its_plan_off_the_audio_thread() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    let mut planned = Engine::new(&settings, RATE, 4);
    planned.prepare_tunings();
    assert_eq!(planned.take_wanted_tuning_plan(), None, "prepared");
    let mut changed = settings;
    changed.voice.bridge_stiffness_n_m2 *= 10.0;
    planned.set_settings(&changed);
    let plan = planned
        .take_wanted_tuning_plan()
        .expect("a plan for the new bridge");
    assert_eq!(planned.take_wanted_tuning_plan(), None, "handed out once");
    let mut damped = changed;
    damped.voice.gamma_per_s *= 2.0;
    damped.voice.eta_s *= 2.0;
    planned.set_settings(&damped);
    assert_eq!(
        planned.take_wanted_tuning_plan(),
        None,
        "the losses need none"
    );
    // Settings that are not numbers are clamped first: one plan, not one per block.
    let mut broken = damped;
    broken.voice.bridge_stiffness_n_m2 = f64::NAN;
    broken.voice.thread_position_m = f64::NAN;
    broken.tuning.a4_hz = f64::NAN;
    planned.set_settings(&broken);
    assert!(planned.take_wanted_tuning_plan().is_some());
    assert_eq!(planned.take_wanted_tuning_plan(), None, "NaN settings");
    planned.set_settings(&damped);
    assert!(planned.take_wanted_tuning_plan().is_some(), "back");

    // The worker's part.
    let mut voice = plan.scratch_voice();
    for string in plan.strings() {
        planned.remember_tuning(&plan.tune(&mut voice, &string));
    }
    let other_rate = PlannedTension {
        sample_rate_hz: 48_000.0,
        ..plan.tune(&mut voice, &plan.strings().next().unwrap())
    };
    let remembered = planned.tuning_memory().len();
    planned.remember_tuning(&other_rate);
    assert_eq!(planned.tuning_memory().len(), remembered, "another rate's");
    assert!(planned.tuning_memory().covers(&plan));
    assert_eq!(planned.tuning_plan(), plan);

    let mut tuning = Engine::new(&settings, RATE, 4);
    tuning.prepare_tunings();
    tuning.set_settings(&damped);
    // The controls settle.
    let settle = (2.0 * SMOOTHING_TIME_S * RATE) as usize;
    run(&mut planned, &[], settle);
    run(&mut tuning, &[], settle);
    assert_remembers_every_tuning(&mut planned, &mut tuning, [45, 52, 64, 71]);
}

/// In drone mode the tuning plan holds the drone's strings on its Sa, each with its own fine
/// tuning and thread, ahead of the notes': the Sa of a held note joins the plan at its first
/// pluck and stays in it after the note is released, and a change of the bridge hands out a plan
/// with them. Tuned off the engine and handed back, they leave the drone's plucks nothing to
/// tune; an engine that gets no tensions back tunes each string at its pluck (but Sa's, whose
/// string is note 50's, prepared with the notes).
#[test]
fn the_drones_strings_are_tuned_from_the_plan_off_the_audio_thread() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    settings.drone.enabled = true;
    settings.drone.strings[0].fine_tune_cents = -13.0;
    settings.drone.strings[0].thread_offset_m = 0.002;
    settings.drone.strings[2].fine_tune_cents = 4.0;
    settings.drone.strings[3].thread_offset_m = -0.001;
    let beat = 22_050; // at 120 beats per minute
    let started = || {
        let mut engine = Engine::new(&settings, RATE, 4);
        engine.set_host_tempo(Some(120.0));
        engine.prepare_tunings();
        engine
    };
    let tune_off_the_engine = |engine: &mut Engine, plan: &TuningPlan| {
        let mut voice = plan.scratch_voice();
        for string in plan.strings() {
            engine.remember_tuning(&plan.tune(&mut voice, &string));
        }
    };
    let (mut planned, mut unplanned) = (started(), started());
    let notes_only = planned.tuning_plan();
    assert_eq!(
        planned.take_wanted_tuning_plan(),
        None,
        "prepared, no Sa yet"
    );

    // The held note's first pluck (the first string, tuned as it is plucked) brings its Sa in.
    let (planned_made, unplanned_made) = (planned.string_tunings(), unplanned.string_tunings());
    let hold = [note_on(0, 50)];
    run(&mut planned, &hold, 64);
    run(&mut unplanned, &hold, 64);
    assert_eq!(planned.string_tunings(), planned_made + 1);
    let plan = planned
        .take_wanted_tuning_plan()
        .expect("a plan with the drone's strings");
    assert_eq!(
        plan.strings().count(),
        notes_only.strings().count() + 3,
        "Sa's own string is note 50's"
    );
    tune_off_the_engine(&mut planned, &plan);
    run(&mut planned, &[], 4 * beat);
    run(&mut unplanned, &[], 4 * beat);
    let played: Vec<VoiceSettings> = (0..4)
        .map(|string| {
            let slot = planned
                .slots
                .iter()
                .find(|slot| slot.key == Some(StringKey::Drone(string)))
                .expect("each string plucked");
            TuningMemory::key(slot.voice.settings())
        })
        .collect();
    let planned_drone: Vec<VoiceSettings> = plan.strings().take(4).collect();
    assert_eq!(
        planned_drone, played,
        "the plan's drone strings are the plucked ones, first"
    );
    assert_eq!(
        planned.string_tunings(),
        planned_made + 1,
        "the other three from the plan"
    );
    assert_eq!(
        unplanned.string_tunings(),
        unplanned_made + 3,
        "Sa's string was prepared as note 50's"
    );

    // Released (and silenced, so that no string follows the bridge's glide as it rings), the Sa
    // stays planned; a changed bridge plans the drone's strings anew.
    let release = [TimedEvent {
        offset: 0,
        event: EngineEvent::AllSoundOff,
    }];
    run(&mut planned, &release, 64);
    run(&mut unplanned, &release, 64);
    assert_eq!(planned.take_wanted_tuning_plan(), None, "released");
    let mut changed = settings;
    changed.voice.bridge_stiffness_n_m2 *= 10.0;
    planned.set_settings(&changed);
    unplanned.set_settings(&changed);
    let plan = planned
        .take_wanted_tuning_plan()
        .expect("a plan for the new bridge");
    tune_off_the_engine(&mut planned, &plan);
    let settle = (2.0 * SMOOTHING_TIME_S * RATE) as usize;
    run(&mut planned, &[], settle);
    run(&mut unplanned, &[], settle);
    let (planned_made, unplanned_made) = (planned.string_tunings(), unplanned.string_tunings());
    run(&mut planned, &hold, 4 * beat);
    run(&mut unplanned, &hold, 4 * beat);
    assert_eq!(
        planned.string_tunings(),
        planned_made,
        "nothing tuned at the drone's plucks"
    );
    assert_eq!(unplanned.string_tunings(), unplanned_made + 4);
}

/// A ringing string's last retune of a glide, once the tuning plan's tensions are back, takes
/// its tension from the memory: after a move of the thread, four ringing strings tune four times
/// fewer than on an engine that gets no tensions back, and end at the same settings.
#[test]
fn a_glides_last_retune_of_a_ringing_string_takes_the_plans_tension() {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    let started = || {
        let mut engine = Engine::new(&settings, RATE, 4);
        engine.prepare_tunings();
        pluck_four_notes(&mut engine);
        engine
    };
    let (mut planned, mut unplanned) = (started(), started());
    let mut moved = settings;
    moved.voice.thread_position_m += 0.002;
    planned.set_settings(&moved);
    unplanned.set_settings(&moved);
    let plan = planned
        .take_wanted_tuning_plan()
        .expect("a plan for the moved thread");
    let mut voice = plan.scratch_voice();
    for string in plan.strings() {
        planned.remember_tuning(&plan.tune(&mut voice, &string));
    }
    let (planned_made, unplanned_made) = (planned.string_tunings(), unplanned.string_tunings());
    let glide_and_round = (2.0 * SMOOTHING_TIME_S * RATE) as usize + 8 * RETUNE_INTERVAL as usize;
    run(&mut planned, &[], glide_and_round);
    run(&mut unplanned, &[], glide_and_round);
    let retuned = |engine: &Engine| -> Vec<VoiceSettings> {
        engine
            .slots
            .iter()
            .map(|slot| *slot.voice.settings())
            .collect()
    };
    assert_eq!(retuned(&planned), retuned(&unplanned));
    assert!(retuned(&planned)
        .iter()
        .all(|string| (string.thread_position_m - moved.voice.thread_position_m).abs() < 1e-12));
    let (planned_tunings, unplanned_tunings) = (
        planned.string_tunings() - planned_made,
        unplanned.string_tunings() - unplanned_made,
    );
    assert!(unplanned_tunings >= 4, "{unplanned_tunings}");
    assert_eq!(planned_tunings + 4, unplanned_tunings);
}

/// A scripted performance rendered block by block ([`scripted_performance`]).
struct Performance {
    /// Both stereo channels and, after every block, each voice's level and whether it is active.
    bits: Vec<u32>,
    /// Voices that fell asleep in a block without an event.
    fell_asleep: usize,
    /// Voices playing drone strings at the end.
    drone_voices: usize,
}

/// A performance rendered in `block_size` blocks, the voices run by `runner` (`None`: one after
/// another, as on the audio thread). On the live tier with γ at its largest, so that soft notes
/// fall asleep within about half a second: soft and firm notes, a glide of the bridge and the
/// thread (whose ticks retune the ringing strings), the thread taken off (no ramp, the same
/// retunes), a quiet stretch in which strings fall asleep, the drone turned on at a fast tempo, and a drone string's level changed. A change of
/// settings lands at the first block that starts at or after its sample.
fn scripted_performance(block_size: usize, runner: Option<VoiceRunner<'_>>) -> Performance {
    const SAMPLES: usize = 70_000;
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    settings.voice.gamma_per_s = 20.0;
    settings.drone.enabled = false;
    let mut engine = Engine::new(&settings, RATE, 4);
    let notes = [
        (0usize, 48u8, 0.05f32),
        (101, 55, 0.05),
        (333, 60, 1.0),
        (30_017, 52, 0.3),
    ];
    let mut glide = settings;
    glide.voice.thread_position_m += 0.5e-3;
    glide.voice.bridge_stiffness_n_m2 *= 3.0;
    // A setting without a ramp: its ticks retune the ringing strings all the same.
    let mut unthreaded = glide;
    unthreaded.voice.thread_enabled = false;
    let mut drone = unthreaded;
    drone.drone.enabled = true;
    drone.drone.sa_note = Some(50);
    drone.drone.free_tempo_bpm = 240.0;
    let mut quieter = drone;
    quieter.drone.strings[1].level_db -= 6.0;
    let changes = [
        (8_000usize, glide),
        (36_000, unthreaded),
        (40_000, drone),
        (55_000, quieter),
    ];
    let mut next_change = 0;
    let (mut left, mut right) = (vec![0.0f32; block_size], vec![0.0f32; block_size]);
    let mut performance = Performance {
        bits: Vec::new(),
        fell_asleep: 0,
        drone_voices: 0,
    };
    let mut start = 0;
    while start < SAMPLES {
        let length = block_size.min(SAMPLES - start);
        while let Some((_, changed)) = changes.get(next_change).filter(|(at, _)| *at <= start) {
            engine.set_settings(changed);
            next_change += 1;
        }
        let events: Vec<TimedEvent> = notes
            .iter()
            .filter(|(at, _, _)| (start..start + length).contains(at))
            .map(|&(at, note, velocity)| TimedEvent {
                offset: at - start,
                event: EngineEvent::NoteOn { note, velocity },
            })
            .collect();
        let active_before: Vec<bool> = engine.slots.iter().map(|s| s.voice.is_active()).collect();
        let (left, right) = (&mut left[..length], &mut right[..length]);
        match runner {
            None => engine.process_stereo(&events, left, right),
            Some(runner) => engine.process_stereo_with(&events, left, right, runner),
        }
        let bits = &mut performance.bits;
        bits.extend(left.iter().chain(&*right).map(|x| x.to_bits()));
        for (slot, &was_active) in engine.slots.iter().zip(&active_before) {
            bits.push(slot.level.to_bits());
            bits.push(u32::from(slot.voice.is_active()));
            let quiet_block = events.is_empty() && !engine.target.drone.enabled;
            performance.fell_asleep +=
                usize::from(quiet_block && was_active && !slot.voice.is_active());
        }
        start += length;
    }
    performance.drone_voices = engine
        .slots
        .iter()
        .filter(|slot| matches!(slot.key, Some(StringKey::Drone(_))))
        .count();
    performance
}

/// Offline, a segment runs through the control ticks that change nothing, and the samples, the
/// levels and the voices' activity stay those of the audio thread's segments, which end at every
/// tick, to the bit: through notes, a glide, a change without a ramp, strings falling asleep
/// between two ticks, drone
/// plucks and a drone level change, at any block size and whatever order the voices run in.
#[test]
fn offline_segments_through_idle_ticks_render_the_audio_threads_bits() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let segments = AtomicUsize::new(0);
    let in_order = |tasks: &mut [VoiceTask<'_>]| {
        segments.fetch_add(1, Ordering::Relaxed);
        tasks.iter_mut().for_each(VoiceTask::run);
    };
    let reversed = |tasks: &mut [VoiceTask<'_>]| tasks.iter_mut().rev().for_each(VoiceTask::run);
    let ticks = 70_000 / CONTROL_INTERVAL as usize;
    for block_size in [64, 333, 512, 4096] {
        let audio_thread = scripted_performance(block_size, None);
        assert!(
            audio_thread.fell_asleep >= 2,
            "{}",
            audio_thread.fell_asleep
        );
        assert!(
            audio_thread.drone_voices >= 2,
            "{}",
            audio_thread.drone_voices
        );
        assert!(audio_thread.bits.iter().any(|&x| f32::from_bits(x) != 0.0));
        segments.store(0, Ordering::Relaxed);
        let offline = scripted_performance(block_size, Some(&in_order));
        assert!(
            audio_thread.bits == offline.bits,
            "block size {block_size}: the bits differ"
        );
        let counted = segments.load(Ordering::Relaxed);
        if block_size >= 512 {
            // The quiet stretches run a block at a time.
            assert!(
                counted < ticks / 2,
                "block size {block_size}: {counted} segments"
            );
        }
        let offline = scripted_performance(block_size, Some(&reversed));
        assert!(
            audio_thread.bits == offline.bits,
            "block size {block_size}: the order matters"
        );
    }
}
