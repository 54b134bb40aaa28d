//! The editor's view of the bowed string equals the instrument's state at that moment: the
//! engine's snapshot against a bowed instrument driven identically, sample for sample.

use javari_core::bowed::instrument::BOW_HISTORY_SAMPLES;
use javari_core::bowed::{BowedEvent, BowedInstrument, StringConstants};
use javari_core::engine::{Engine, EngineSettings, Instrument, TimedEvent};
use javari_core::snapshot::TanpuraSnapshot;

#[test]
fn bowed_snapshot_equals_the_instrument_state() {
    let settings = EngineSettings {
        instrument: Instrument::Bowed,
        ..EngineSettings::default()
    };
    let rate = 44_100.0;
    let mut engine = Engine::new(&settings, rate, 2);
    let mut twin =
        BowedInstrument::new(StringConstants::violin_a(), settings.bowed.player, rate).unwrap();
    twin.set_pressure(settings.bowed.pressure);
    twin.set_bow_velocity_m_s(settings.bowed.bow_velocity_m_s);
    twin.set_bow_position(settings.bowed.bow_position);

    let mut block = vec![0.0f32; 4410];
    let events = [TimedEvent::note_on(0, 60, 0.7)];
    engine.process(&events, &mut block);
    twin.handle(BowedEvent::NoteOn {
        note: 60,
        velocity: 0.7,
    });
    for _ in 0..block.len() {
        twin.next_sample();
    }

    let mut snapshot = Box::new(TanpuraSnapshot::EMPTY);
    engine.fill_snapshot(&mut snapshot);
    let view = &snapshot.bowed;
    assert!(view.active);
    let controls = twin.controls();
    assert_eq!(view.pitch_hz, controls.pitch_hz);
    assert_eq!(view.bow_force_n, controls.bow_force_n);
    assert_eq!(view.bow_velocity_m_s, controls.bow_velocity_m_s);
    assert_eq!(view.bow_position, controls.bow_position);
    let mut velocities = [0.0f32; BOW_HISTORY_SAMPLES];
    let mut sticking = [false; BOW_HISTORY_SAMPLES];
    twin.bow_history(&mut velocities, &mut sticking);
    assert_eq!(view.velocity_m_s, velocities);
    assert_eq!(view.sticking, sticking);
    assert!(view.sticking.iter().any(|&s| s) && view.sticking.iter().any(|&s| !s));

    // With the tanpura playing, the bowed view is off.
    engine.set_settings(&EngineSettings::default());
    engine.fill_snapshot(&mut snapshot);
    assert!(!snapshot.bowed.active);
}
