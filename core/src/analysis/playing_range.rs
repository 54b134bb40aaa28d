//! The tanpura's playing range as a grid of single plucks: keys, velocities and pluck positions,
//! each rendered as a MIDI note through the engine at a chosen tier. The bench compares every
//! tier with the reference over the whole grid ([`full_grid`]); the tests over a few points of it.
//! Each pluck is one voice of a fresh engine, the pickup output, 64-sample blocks; tuned by its
//! linearisation ([`render`]) or, as `cargo xtask render` and the plugin tune it, by its
//! sustained pitch as played ([`calibrate`], [`render_as_played`]).

use crate::engine::{Engine, EngineSettings, TimedEvent};
use crate::tanpura::as_played::{Calibration, CalibrationRequest};
use crate::tanpura::excitation::Pluck;
use crate::tanpura::quality::Quality;
use crate::tanpura::VoiceSettings;

/// Keys from C2 to E4: every third semitone and the top key, and every crest key
/// ([`CREST_KEYS`]), where the string at rest lies at the edge of the bridge's crest and a hard
/// pluck may or may not lift it off: at key 53, between two keys of every third semitone, the
/// fine tier's hardest pluck sounded 10 cents from the reference's (stop 57,
/// `core/tests/tanpura_as_played.rs`), where the keys beside it agreed within a cent.
pub const KEYS: [u8; 15] = [36, 39, 42, 45, 48, 49, 50, 51, 52, 53, 54, 57, 60, 63, 64];
/// MIDI velocities, from the softest to the hardest: denser at the hard end (steps of 20, 15
/// and 12 above 80), where the contact's nonlinearity grows with the amplitude and a string at
/// the crest may be bistable. With 1, 40, 80 and 127 alone (stops 51–57) the grid missed what a
/// sweep of key 53 over velocities 88–127 showed (stop 58): the studio tier 2.52 cents from the
/// reference at velocity 115 and the fine tier 13.25 cents at 124, where both lay within 0.24
/// and 10.21 cents of it at 127.
pub const VELOCITIES: [u8; 6] = [1, 40, 80, 100, 115, 127];
/// Pluck positions, m from the tuning bead: the instrument's default and one nearer the bridge.
pub const PLUCK_POSITIONS_M: [f64; 2] = [0.35, 0.20];
/// Length of each render, s: the sustained pitch is measured up to 1.5 s.
pub const NOTE_SECONDS: f64 = 1.6;
/// The crest keys: where the string at rest lies at the edge of the bridge's crest, and where
/// the reference's grid is the least resolved scheme (README, *Where the targets are missed*;
/// `docs/modal-tanpura.md` §9; `core/tests/tanpura_crest_threshold.rs`). The bench and
/// `examples/grid_against_refined.rs` also report their worst plucks without these keys.
pub const CREST_KEYS: std::ops::RangeInclusive<u8> = 48..=54;

/// One pluck of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridPoint {
    pub key: u8,
    pub velocity: u8,
    pub pluck_position_m: f64,
}

impl GridPoint {
    /// The key's nominal pitch at the default tuning (A4 = 440 Hz), Hz.
    pub fn nominal_hz(&self) -> f64 {
        crate::engine::pitch::note_to_hz(self.key)
    }

    /// A short label: "key 48, velocity 80, pluck at 0.35 m".
    pub fn label(&self) -> String {
        format!(
            "key {}, velocity {}, pluck at {:.2} m",
            self.key, self.velocity, self.pluck_position_m
        )
    }
}

/// Every key × velocity × position of the bench's grid.
pub fn full_grid() -> Vec<GridPoint> {
    let mut points = Vec::new();
    for &key in &KEYS {
        for &velocity in &VELOCITIES {
            for &pluck_position_m in &PLUCK_POSITIONS_M {
                points.push(GridPoint {
                    key,
                    velocity,
                    pluck_position_m,
                });
            }
        }
    }
    points
}

/// The engine settings of a grid render: defaults except the tier and the pluck position.
pub fn settings_for(quality: Quality, point: &GridPoint) -> EngineSettings {
    EngineSettings {
        voice: VoiceSettings {
            quality,
            ..VoiceSettings::default()
        },
        pluck: Pluck {
            position_m: point.pluck_position_m,
            ..Pluck::default()
        },
        ..EngineSettings::default()
    }
}

/// Renders one pluck of the grid for `seconds` at `sample_rate_hz`: a note-on at the first
/// sample, the string left ringing.
pub fn render(quality: Quality, point: &GridPoint, seconds: f64, sample_rate_hz: f64) -> Vec<f64> {
    render_tuned(quality, point, seconds, sample_rate_hz, None)
}

/// The as-played calibration of the grid's string at `key` plucked at `pluck_position_m` on
/// `quality` (the same for every velocity: it centres velocities 40 and 110). Renders.
pub fn calibrate(
    quality: Quality,
    key: u8,
    pluck_position_m: f64,
    sample_rate_hz: f64,
) -> Calibration {
    Calibration::measure(
        &calibration_request(quality, key, pluck_position_m),
        sample_rate_hz,
    )
}

/// What [`calibrate`] measures: the grid's string at `key` plucked at `pluck_position_m` on
/// `quality`, as the engine plans it.
pub fn calibration_request(quality: Quality, key: u8, pluck_position_m: f64) -> CalibrationRequest {
    let point = GridPoint {
        key,
        velocity: 127,
        pluck_position_m,
    };
    Engine::planned_strings(&settings_for(quality, &point), &[key])
        .into_iter()
        .next()
        .expect("every key of the grid is playable")
}

/// [`render`] with the string tuned as played by `calibration` (from [`calibrate`]).
pub fn render_as_played(
    quality: Quality,
    point: &GridPoint,
    seconds: f64,
    sample_rate_hz: f64,
    calibration: &Calibration,
) -> Vec<f64> {
    render_tuned(quality, point, seconds, sample_rate_hz, Some(calibration))
}

fn render_tuned(
    quality: Quality,
    point: &GridPoint,
    seconds: f64,
    sample_rate_hz: f64,
    calibration: Option<&Calibration>,
) -> Vec<f64> {
    const BLOCK: usize = 64;
    let mut engine = Engine::new(&settings_for(quality, point), sample_rate_hz, 1);
    if let Some(calibration) = calibration {
        engine.set_calibration(calibration);
    }
    let samples = (seconds * sample_rate_hz).round() as usize;
    let mut output = Vec::with_capacity(samples);
    let mut block = [0.0f32; BLOCK];
    let note_on = [TimedEvent::note_on(
        0,
        point.key,
        point.velocity as f32 / 127.0,
    )];
    while output.len() < samples {
        let length = BLOCK.min(samples - output.len());
        let events: &[TimedEvent] = if output.is_empty() { &note_on } else { &[] };
        engine.process(events, &mut block[..length]);
        output.extend(block[..length].iter().map(|&x| x as f64));
    }
    output
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_spans_the_range_the_issue_names() {
        let grid = full_grid();
        assert_eq!(
            grid.len(),
            KEYS.len() * VELOCITIES.len() * PLUCK_POSITIONS_M.len()
        );
        assert_eq!(KEYS[0], 36);
        assert_eq!(*KEYS.last().unwrap(), 64);
        assert!(KEYS.windows(2).all(|pair| pair[1] - pair[0] <= 3));
        assert!(CREST_KEYS.into_iter().all(|key| KEYS.contains(&key)));
    }

    #[test]
    fn a_render_is_the_length_asked_and_sounds() {
        let point = GridPoint {
            key: 48,
            velocity: 80,
            pluck_position_m: 0.35,
        };
        let output = render(Quality::Live, &point, 0.2, 44_100.0);
        assert_eq!(output.len(), 8820);
        assert!(output.iter().all(|x| x.is_finite()));
        assert!(output.iter().any(|x| x.abs() > 1e-4));
    }
}
