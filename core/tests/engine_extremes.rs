//! The engine at the extremes a host can throw at it: block sizes from 1 to 8192, output rates
//! from 22.05 kHz to 384 kHz, both instruments. The output must not depend on the block size
//! (events sit at absolute sample times) and must stay finite and below full scale. Non-finite
//! and out-of-range settings and events, as broken automation or a foreign state would send, are
//! clamped at the engine's boundary. The reported latency follows the tier.

use javari_core::engine::render::{render, RenderOptions, Score};
use javari_core::engine::{preset, Engine};
use javari_core::engine::{
    EngineEvent, EngineSettings, Instrument, TimedEvent, OUTPUT_GAIN_RANGE_DB,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::VoiceSettings;

fn score() -> Score {
    let mut score = Score::default();
    for (index, note) in [45u8, 57, 64, 52].into_iter().enumerate() {
        score.note(0.013 + 0.11 * index as f64, 0.2, note, 0.8);
    }
    score
}

fn settings(instrument: Instrument) -> EngineSettings {
    let mut settings = EngineSettings {
        instrument,
        ..EngineSettings::default()
    };
    settings.voice.quality = Quality::Live;
    settings
}

fn render_with(instrument: Instrument, sample_rate_hz: f64, block_size: usize) -> Vec<f32> {
    let options = RenderOptions {
        sample_rate_hz,
        block_size,
        tail_s: 0.1,
        ..RenderOptions::default()
    };
    render(&settings(instrument), &score(), &options, &mut |_, _| {})
}

#[test]
fn block_sizes_from_1_to_8192_give_the_same_output() {
    for instrument in [Instrument::Tanpura, Instrument::Bowed] {
        let reference = render_with(instrument, 44_100.0, 8192);
        assert!(reference.iter().any(|&x| x != 0.0));
        for block_size in [1, 3, 64, 1000] {
            let other = render_with(instrument, 44_100.0, block_size);
            assert!(
                other
                    .iter()
                    .map(|x| x.to_bits())
                    .eq(reference.iter().map(|x| x.to_bits())),
                "{instrument:?}: block size {block_size} differs from 8192"
            );
        }
    }
}

#[test]
fn output_rates_from_22050_to_384000_stay_finite_and_below_full_scale() {
    for instrument in [Instrument::Tanpura, Instrument::Bowed] {
        for rate in [22_050.0, 48_000.0, 96_000.0, 192_000.0, 384_000.0] {
            let output = render_with(instrument, rate, 512);
            assert!(
                output.iter().all(|x| x.is_finite()),
                "{instrument:?} at {rate}"
            );
            let peak = output.iter().fold(0.0f32, |a, x| a.max(x.abs()));
            assert!(
                peak > 1e-4 && peak < 1.0,
                "{instrument:?} at {rate}: peak {peak}"
            );
        }
    }
}

/// Every number of the settings set to `value` (switches and choices as given).
fn every_number_set_to(value: f64, instrument: Instrument) -> EngineSettings {
    let mut settings = EngineSettings {
        instrument,
        ..EngineSettings::default()
    };
    settings.voice.quality = Quality::Live;
    settings.drone.enabled = instrument == Instrument::Tanpura;
    settings.drone.tempo_sync = false;
    let voice = &mut settings.voice;
    voice.fundamental_hz = value;
    voice.bridge_stiffness_n_m2 = value;
    voice.thread_position_m = value;
    voice.gamma_per_s = value;
    voice.eta_s = value;
    voice.nut_pickup_weight = value;
    settings.pluck = Pluck {
        position_m: value,
        width_m: value,
        amplitude_m: value,
    };
    settings.output_gain_db = value;
    settings.drone.free_tempo_bpm = value;
    settings.drone.pluck_spacing_beats = value;
    settings.drone.cycle_pause_beats = value;
    settings.drone.humanize_timing_s = value;
    settings.drone.humanize_strength = value;
    settings.tuning.a4_hz = value;
    settings.tuning.fine_tune_cents = value;
    let bowed = &mut settings.bowed;
    bowed.pressure = value;
    bowed.bow_velocity_m_s = value;
    bowed.bow_position = value;
    bowed.player.glide_time_s = value;
    bowed.player.vibrato_rate_hz = value;
    bowed.player.max_vibrato_cents = value;
    bowed.player.pitch_bend_range_semitones = value;
    bowed.player.bow_lift_time_s = value;
    settings
}

fn assert_within(name: &str, value: f64, (min, max): (f64, f64)) {
    assert!(
        (min..=max).contains(&value),
        "{name} = {value} outside {min}..{max}"
    );
}

fn assert_valid(settings: &EngineSettings) {
    assert!(settings.voice.validate().is_ok(), "{:?}", settings.voice);
    let pluck = settings.pluck;
    assert_within(
        "pluck position",
        pluck.position_m,
        preset::PLUCK_POSITION_RANGE_M,
    );
    assert_within("pluck width", pluck.width_m, Pluck::WIDTH_RANGE_M);
    assert_within(
        "pluck amplitude",
        pluck.amplitude_m,
        Pluck::AMPLITUDE_RANGE_M,
    );
    assert_within("gain", settings.output_gain_db, OUTPUT_GAIN_RANGE_DB);
    let tempo = javari_core::engine::drone::TEMPO_RANGE_BPM;
    assert_within("drone tempo", settings.drone.free_tempo_bpm, tempo);
    use javari_core::engine::{drone, pitch};
    let d = settings.drone;
    assert_within(
        "spacing",
        d.pluck_spacing_beats,
        drone::PLUCK_SPACING_RANGE_BEATS,
    );
    assert_within("pause", d.cycle_pause_beats, drone::CYCLE_PAUSE_RANGE_BEATS);
    assert_within(
        "humanize",
        d.humanize_timing_s,
        drone::HUMANIZE_TIMING_RANGE_S,
    );
    assert_within(
        "softening",
        d.humanize_strength,
        drone::HUMANIZE_STRENGTH_RANGE,
    );
    assert_within("A4", settings.tuning.a4_hz, pitch::A4_RANGE_HZ);
    let fine = settings.tuning.fine_tune_cents;
    assert_within("fine tuning", fine, pitch::FINE_TUNE_RANGE_CENTS);
    let bowed = settings.bowed;
    assert_within("bow pressure", bowed.pressure, (0.0, 1.0));
    assert_within(
        "bow speed",
        bowed.bow_velocity_m_s,
        preset::BOW_VELOCITY_RANGE_M_S,
    );
    assert_within(
        "bow position",
        bowed.bow_position,
        preset::BOW_POSITION_RANGE,
    );
    assert_within(
        "glide",
        bowed.player.glide_time_s,
        preset::BOW_GLIDE_RANGE_S,
    );
    let player = bowed.player;
    assert!(player.vibrato_rate_hz.is_finite() && player.max_vibrato_cents.is_finite());
    assert!(player.pitch_bend_range_semitones.is_finite() && player.bow_lift_time_s > 0.0);
}

/// NaN, ±∞ and values far outside every range, as settings (at construction and as automation
/// while strings ring) and as event values: the applied settings are valid, NaN takes the
/// default, and the output stays finite and bounded.
#[test]
fn non_finite_and_out_of_range_values_are_clamped() {
    let nan = every_number_set_to(f64::NAN, Instrument::Tanpura).clamped();
    assert_valid(&nan);
    let default = EngineSettings::default();
    assert_eq!(nan.voice.gamma_per_s, default.voice.gamma_per_s);
    assert_eq!(nan.pluck, default.pluck);
    assert_eq!(nan.output_gain_db, default.output_gain_db);
    assert_eq!(nan.drone.free_tempo_bpm, default.drone.free_tempo_bpm);
    assert_eq!(nan.bowed.pressure, default.bowed.pressure);
    let huge = every_number_set_to(1e300, Instrument::Tanpura).clamped();
    assert_eq!(huge.output_gain_db, OUTPUT_GAIN_RANGE_DB.1);
    assert_eq!(huge.voice.gamma_per_s, VoiceSettings::GAMMA_RANGE.1);

    let hostile_events = [
        EngineEvent::NoteOn {
            note: 57,
            velocity: f32::NAN,
        },
        EngineEvent::NoteOn {
            note: 200,
            velocity: f32::INFINITY,
        },
        EngineEvent::Controller {
            number: 2,
            value: f32::NAN,
        },
        EngineEvent::Controller {
            number: 11,
            value: 1e30,
        },
        EngineEvent::ChannelPressure(f32::NEG_INFINITY),
        EngineEvent::PolyPressure {
            note: 57,
            value: -1e30,
        },
        EngineEvent::PitchBend(f32::NAN),
        EngineEvent::PitchBend(1e30),
    ];
    assert_eq!(hostile_events[0].sanitised(), None);
    assert_eq!(
        hostile_events[3].sanitised(),
        Some(EngineEvent::Controller {
            number: 11,
            value: 1.0
        })
    );
    assert_eq!(
        hostile_events[7].sanitised(),
        Some(EngineEvent::PitchBend(1.0))
    );

    let values = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e300,
        -1e300,
        0.0,
    ];
    for instrument in [Instrument::Tanpura, Instrument::Bowed] {
        for (index, &value) in values.iter().enumerate() {
            let hostile = every_number_set_to(value, instrument);
            let mut engine = Engine::new(&hostile, 44_100.0, 4);
            assert_valid(engine.settings());
            let mut calm = settings(instrument);
            calm.drone.enabled = false;
            engine.set_settings(&calm);
            let mut block = [0.0f32; 256];
            let note = [TimedEvent::note_on(0, 57, 0.8)];
            engine.process(&note, &mut block);
            let mut peak = 0.0f32;
            for block_index in 0..80 {
                // Automation every block while the string rings, alternating hostile and
                // ordinary values, and every hostile event once.
                let automated = if block_index % 2 == 0 {
                    every_number_set_to(values[(index + block_index) % values.len()], instrument)
                } else {
                    calm
                };
                engine.set_settings(&automated);
                assert_valid(engine.settings());
                let events: Vec<TimedEvent> = hostile_events
                    .iter()
                    .enumerate()
                    .map(|(offset, &event)| TimedEvent { offset, event })
                    .collect();
                let events = if block_index == 3 { &events[..] } else { &[] };
                engine.process(events, &mut block);
                for &sample in &block {
                    assert!(
                        sample.is_finite(),
                        "{instrument:?}, {value}: non-finite output"
                    );
                    peak = peak.max(sample.abs());
                }
            }
            // The hostile values include the largest gain, +24 dB (×15.8): bounded by that.
            assert!(peak < 16.0, "{instrument:?}, {value}: peak {peak}");
        }
    }
}

/// The latency a host is told follows the tier: the decimator's delay (whole samples) at the
/// oversampled tiers, studio and reference, none at the tiers at the output rate and for the
/// bowed string. An engine reports the latency it was built with until it adopts the tier's (the
/// plugin does at activation), and a voice with less latency of its own is delayed to it: a
/// string at the output rate plucked while an oversampled tier's latency is reported is exactly
/// silent for that many samples and sounds from the next, and sounds from its first sample once
/// the engine has adopted its own tier's latency.
#[test]
fn latency_follows_the_tier_and_lower_latency_voices_are_delayed_to_it() {
    let tanpura = settings(Instrument::Tanpura);
    let at = |quality: Quality, instrument: Instrument| {
        let mut settings = tanpura;
        settings.voice.quality = quality;
        settings.instrument = instrument;
        settings
    };
    let oversampled_latency =
        Engine::new(&at(Quality::Reference, Instrument::Tanpura), 44_100.0, 1).latency_samples();
    println!(
        "latency: {oversampled_latency} samples at the oversampled tiers (studio and reference, 4x)"
    );
    assert!(
        oversampled_latency > 1.0 && oversampled_latency < 64.0,
        "{oversampled_latency}"
    );
    assert_eq!(oversampled_latency.fract(), 0.0);
    for quality in Quality::ALL {
        let expected = if quality.oversample() > 1 {
            oversampled_latency
        } else {
            0.0
        };
        let engine = Engine::new(&at(quality, Instrument::Tanpura), 44_100.0, 1);
        assert_eq!(engine.latency_samples(), expected, "{quality:?}");
        assert_eq!(engine.tier_latency_samples(), expected, "{quality:?}");
        let bowed = Engine::new(&at(quality, Instrument::Bowed), 44_100.0, 1);
        assert_eq!(bowed.latency_samples(), 0.0, "{quality:?}, bowed");
    }
    // A change of tier is reported only once adopted.
    let mut engine = Engine::new(&at(Quality::Reference, Instrument::Tanpura), 44_100.0, 1);
    engine.set_settings(&at(Quality::Live, Instrument::Tanpura));
    assert_eq!(engine.latency_samples(), oversampled_latency);
    assert_eq!(engine.tier_latency_samples(), 0.0);
    let delay = oversampled_latency as usize;
    let pluck = [TimedEvent::note_on(0, 57, 1.0)];
    let mut output = vec![0.0f32; 256];
    engine.process(&pluck, &mut output);
    assert!(
        output[..delay].iter().all(|&x| x == 0.0),
        "delayed to the oversampled tiers' latency"
    );
    assert!(output[delay] != 0.0, "silent after the delay");
    engine.adopt_tier_latency();
    assert_eq!(engine.latency_samples(), 0.0);
    engine.reset();
    engine.process(&pluck, &mut output);
    assert!(
        output[0] != 0.0,
        "a modal string at the modal latency sounds at once"
    );
    engine.set_settings(&at(Quality::Studio, Instrument::Tanpura));
    assert_eq!(engine.tier_latency_samples(), oversampled_latency);
    engine.adopt_tier_latency();
    assert_eq!(engine.latency_samples(), oversampled_latency);
}
