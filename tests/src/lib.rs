//! Shared code of Javari's integration tests: the MIDI fixtures (generated here, committed in
//! `tests/fixtures/`), and the measurements the tests assert on (pitch, onsets, peaks).
//!
//! Regenerate the fixtures with `JAVARI_WRITE_FIXTURES=1 cargo test -p javari-tests fixtures`.

pub mod fuzz;

use midly::num::{u15, u24, u28, u4, u7};
use midly::{Format, Header, MetaMessage, MidiMessage, Smf, Timing, TrackEvent, TrackEventKind};
use std::path::PathBuf;

/// Ticks per beat of every fixture; with 120 bpm one tick is 1/960 s.
pub const TICKS_PER_BEAT: u16 = 480;
/// Tempo of every fixture, µs per beat (120 bpm).
pub const MICROSECONDS_PER_BEAT: u32 = 500_000;

/// One note of a fixture: start and length in ticks, key, velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixtureNote {
    pub start_tick: u32,
    pub length_ticks: u32,
    pub key: u8,
    pub velocity: u8,
}

impl FixtureNote {
    pub fn start_s(&self) -> f64 {
        ticks_to_seconds(self.start_tick)
    }
}

pub fn ticks_to_seconds(ticks: u32) -> f64 {
    f64::from(ticks) * f64::from(MICROSECONDS_PER_BEAT) * 1e-6 / f64::from(TICKS_PER_BEAT)
}

/// A control change in a fixture: tick, controller number, value (0–127).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixtureController {
    pub tick: u32,
    pub number: u8,
    pub value: u8,
}

/// A fixture: its file name, its notes, ticks at which CC 120 (all sound off) silences every
/// string, and other control changes.
#[derive(Debug, Clone, PartialEq)]
pub struct Fixture {
    pub file_name: &'static str,
    pub notes: Vec<FixtureNote>,
    pub silence_ticks: Vec<u32>,
    pub controllers: Vec<FixtureController>,
}

/// Velocity of the scale fixture's notes: 48/127 of the 2 mm default pluck, 0.76 mm, where the
/// string's pitch is its small-amplitude (linearised) pitch. Harder plucks start flat or sharp
/// by several cents and glide in as they decay (`full_velocity_pitch_glides_in` in
/// tests/tests/render_fixtures.rs measures it).
pub const SCALE_VELOCITY: u8 = 48;

/// The fixtures:
/// - `scale.mid`: five notes from A2 to A4, each alone (silenced 0.6 s after its start, the
///   next one 0.1 s later) so that pitch and onset can be measured one note at a time; the
///   onsets fall on odd tick times that are not multiples of any block size;
/// - `polyphony.mid`: overlapping notes at several velocities, more notes than voices, a
///   re-plucked string and note-offs that leave strings ringing;
/// - `bowed.mid`: a bowed phrase ([`BOWED_PHRASE`]) with a slur, a detached note and control
///   changes for bow pressure and bow position.
pub fn fixtures() -> Vec<Fixture> {
    let scale_keys = [45u8, 52, 57, 64, 69];
    let step = 672; // 0.7 s
    let scale = Fixture {
        file_name: "scale.mid",
        notes: scale_keys
            .iter()
            .enumerate()
            .map(|(index, &key)| FixtureNote {
                start_tick: 13 + step * index as u32,
                length_ticks: 240,
                key,
                velocity: SCALE_VELOCITY,
            })
            .collect(),
        silence_ticks: (0..scale_keys.len() as u32)
            .map(|index| 13 + step * index + 576)
            .collect(),
        controllers: Vec::new(),
    };
    let polyphony_notes = [
        (0u32, 48u8, 100u8),
        (120, 55, 80),
        (240, 60, 127),
        (300, 64, 40),
        (420, 67, 90),
        (480, 48, 100),
        (500, 72, 70),
        (620, 43, 127),
        (700, 76, 60),
        (830, 79, 100),
        (900, 50, 1),
    ];
    let polyphony = Fixture {
        file_name: "polyphony.mid",
        notes: polyphony_notes
            .iter()
            .map(|&(start_tick, key, velocity)| FixtureNote {
                start_tick,
                length_ticks: 100,
                key,
                velocity,
            })
            .collect(),
        silence_ticks: Vec::new(),
        controllers: Vec::new(),
    };
    let bowed = Fixture {
        file_name: "bowed.mid",
        notes: BOWED_PHRASE
            .iter()
            .map(|&(start_tick, length_ticks, key)| FixtureNote {
                start_tick,
                length_ticks,
                key,
                velocity: 80,
            })
            .collect(),
        silence_ticks: Vec::new(),
        controllers: vec![
            // More bow pressure (CC 2) during the second note, the bow nearer the fingerboard
            // (CC 74) during the third.
            FixtureController {
                tick: 1400,
                number: 2,
                value: 75,
            },
            FixtureController {
                tick: 2400,
                number: 74,
                value: 60,
            },
        ],
    };
    vec![scale, polyphony, bowed]
}

/// The bowed phrase (start tick, length in ticks, key; 960 ticks per second): A3, then C4 slurred
/// to it (the notes overlap by 50 ms, so the bow glides without a new attack), then a detached E4.
pub const BOWED_PHRASE: [(u32, u32, u8); 3] = [(96, 960, 57), (1008, 960, 60), (2112, 864, 64)];

/// The standard MIDI file (format 0) of a fixture.
pub fn fixture_bytes(fixture: &Fixture) -> Vec<u8> {
    // (tick, order within a tick, message): offs before ons at the same tick.
    let mut timed: Vec<(u32, u8, TrackEventKind<'static>)> = Vec::new();
    let channel = u4::new(0);
    for note in &fixture.notes {
        timed.push((
            note.start_tick,
            1,
            TrackEventKind::Midi {
                channel,
                message: MidiMessage::NoteOn {
                    key: u7::new(note.key),
                    vel: u7::new(note.velocity),
                },
            },
        ));
        timed.push((
            note.start_tick + note.length_ticks,
            0,
            TrackEventKind::Midi {
                channel,
                message: MidiMessage::NoteOff {
                    key: u7::new(note.key),
                    vel: u7::new(0),
                },
            },
        ));
    }
    for controller in &fixture.controllers {
        timed.push((
            controller.tick,
            0,
            TrackEventKind::Midi {
                channel,
                message: MidiMessage::Controller {
                    controller: u7::new(controller.number),
                    value: u7::new(controller.value),
                },
            },
        ));
    }
    for &tick in &fixture.silence_ticks {
        timed.push((
            tick,
            0,
            TrackEventKind::Midi {
                channel,
                message: MidiMessage::Controller {
                    controller: u7::new(120),
                    value: u7::new(0),
                },
            },
        ));
    }
    timed.sort_by_key(|(tick, order, _)| (*tick, *order));
    let mut track = vec![TrackEvent {
        delta: u28::new(0),
        kind: TrackEventKind::Meta(MetaMessage::Tempo(u24::new(MICROSECONDS_PER_BEAT))),
    }];
    let mut last = 0;
    for (tick, _, kind) in timed {
        track.push(TrackEvent {
            delta: u28::new(tick - last),
            kind,
        });
        last = tick;
    }
    track.push(TrackEvent {
        delta: u28::new(0),
        kind: TrackEventKind::Meta(MetaMessage::EndOfTrack),
    });
    let smf = Smf {
        header: Header::new(
            Format::SingleTrack,
            Timing::Metrical(u15::new(TICKS_PER_BEAT)),
        ),
        tracks: vec![track],
    };
    let mut bytes = Vec::new();
    smf.write_std(&mut bytes)
        .expect("writing to a Vec cannot fail");
    bytes
}

/// `tests/fixtures/` in the repository.
pub fn fixtures_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

/// The repository's root directory.
pub fn repository_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits in the repository")
        .to_path_buf()
}

/// The plugin's shared library as `cargo test` builds it (the `javari` cdylib with
/// `assert_process_allocs`): in `target/<profile>/deps/` beside the test executable, or one
/// directory up.
pub fn plugin_library() -> PathBuf {
    let file = format!(
        "{}javari{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    );
    let executable = std::env::current_exe().expect("the test executable's path");
    let deps = executable.parent().expect("the deps directory");
    [deps.join(&file), deps.join("..").join(&file)]
        .into_iter()
        .find(|path| path.exists())
        .unwrap_or_else(|| panic!("{file} not found near {}", deps.display()))
}

/// Magnitude of the Hann-windowed signal's spectrum at `frequency_hz` (one DTFT bin).
pub fn windowed_magnitude(signal: &[f32], sample_rate_hz: f64, frequency_hz: f64) -> f64 {
    javari_core::analysis::windowed_dft_power(signal, sample_rate_hz, frequency_hz).sqrt()
}

/// The frequency of the strongest spectral peak within ±`search_cents` of `expected_hz`:
/// a 0.5-cent grid search, then golden-section refinement to 0.01 cent.
pub fn peak_frequency_near(
    signal: &[f32],
    sample_rate_hz: f64,
    expected_hz: f64,
    search_cents: f64,
) -> f64 {
    let at_cents = |cents: f64| expected_hz * (cents / 1200.0).exp2();
    let magnitude = |cents: f64| windowed_magnitude(signal, sample_rate_hz, at_cents(cents));
    let steps = (2.0 * search_cents / 0.5).round() as i32;
    let mut best = (-search_cents, f64::MIN);
    for step in 0..=steps {
        let cents = -search_cents + 0.5 * f64::from(step);
        let value = magnitude(cents);
        if value > best.1 {
            best = (cents, value);
        }
    }
    let (mut low, mut high) = (best.0 - 0.5, best.0 + 0.5);
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    while high - low > 0.01 {
        let a = high - ratio * (high - low);
        let b = low + ratio * (high - low);
        if magnitude(a) > magnitude(b) {
            high = b;
        } else {
            low = a;
        }
    }
    at_cents(0.5 * (low + high))
}

/// First sample at or after `from` whose magnitude exceeds `threshold`.
pub fn first_above(signal: &[f32], from: usize, threshold: f32) -> Option<usize> {
    signal[from.min(signal.len())..]
        .iter()
        .position(|x| x.abs() > threshold)
        .map(|index| index + from)
}

pub fn peak(signal: &[f32]) -> f32 {
    signal.iter().fold(0.0, |peak, x| peak.max(x.abs()))
}

/// What a host hears of the plugin's two channels, checked finite: the mid signal
/// `(left + right) / 2`, which is the engine's mono output (`Engine::process_stereo`).
pub fn finite_mid(left: &[f32], right: &[f32]) -> Vec<f32> {
    assert!(
        left.iter().chain(right).all(|x| x.is_finite()),
        "non-finite sample"
    );
    left.iter().zip(right).map(|(l, r)| 0.5 * (l + r)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_frequency_of_a_sine_is_found_to_a_hundredth_of_a_cent() {
        let rate = 44_100.0;
        let frequency = 223.7;
        let signal: Vec<f32> = (0..22_050)
            .map(|n| (2.0 * std::f64::consts::PI * frequency * n as f64 / rate).sin() as f32)
            .collect();
        let found = peak_frequency_near(&signal, rate, 220.0, 50.0);
        let cents = 1200.0 * (found / frequency).log2();
        assert!(cents.abs() < 0.05, "{found} Hz, {cents} cents");
    }

    #[test]
    fn fixture_files_match_the_generator() {
        for fixture in fixtures() {
            let bytes = fixture_bytes(&fixture);
            let path = fixtures_dir().join(fixture.file_name);
            if std::env::var_os("JAVARI_WRITE_FIXTURES").is_some() {
                std::fs::create_dir_all(fixtures_dir()).unwrap();
                std::fs::write(&path, &bytes).unwrap();
            }
            let committed =
                std::fs::read(&path).unwrap_or_else(|error| panic!("{}: {error}", path.display()));
            assert_eq!(committed, bytes, "{} is stale", path.display());
        }
    }
}
