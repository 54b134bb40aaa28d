//! Standard MIDI files to a [`Score`]: note and channel-mode events at times in seconds.
//!
//! All tracks are merged (format 0, 1 and 2 alike) and every channel plays the instrument.
//! Metrical timing follows the file's tempo map (set-tempo meta events, 120 bpm until the first
//! one); SMPTE timing uses frames per second × ticks per frame. Note-on with velocity 0 is a
//! note-off; CC 120 (all sound off) and CC 123 (all notes off) are honoured; everything else is
//! ignored. A file that midly cannot parse fails with the parser's reason and the file name.

use super::render::{Score, ScoreAction, ScoreEvent};
use super::EngineEvent;
use midly::{MetaMessage, MidiMessage, Smf, Timing, TrackEventKind};
use std::fmt;
use std::path::Path;

/// Tempo before the first set-tempo event (the MIDI standard's default), µs per beat.
const DEFAULT_MICROSECONDS_PER_BEAT: u32 = 500_000;

/// A MIDI file that could not be read or parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct MidiFileError {
    pub file: String,
    pub reason: String,
}

impl fmt::Display for MidiFileError {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            formatter,
            "{}: not a valid standard MIDI file: {}",
            self.file, self.reason
        )
    }
}

impl std::error::Error for MidiFileError {}

/// Reads a MIDI file into a score.
pub fn load(path: &Path) -> Result<Score, MidiFileError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|error| MidiFileError {
        file: file.clone(),
        reason: error.to_string(),
    })?;
    parse(&bytes, &file)
}

/// Parses the bytes of a MIDI file; `file` names it in errors.
pub fn parse(bytes: &[u8], file: &str) -> Result<Score, MidiFileError> {
    let smf = Smf::parse(bytes).map_err(|error| MidiFileError {
        file: file.to_string(),
        reason: error.to_string(),
    })?;

    // Merge every track's events on an absolute tick axis; the sort is stable so that events at
    // the same tick keep their order within a track (and tracks keep theirs).
    let mut merged: Vec<(u64, TrackEventKind)> = Vec::new();
    for track in &smf.tracks {
        let mut tick = 0u64;
        for event in track {
            tick += u64::from(u32::from(event.delta));
            merged.push((tick, event.kind));
        }
    }
    merged.sort_by_key(|(tick, _)| *tick);

    let mut events = Vec::new();
    let mut microseconds_per_beat = DEFAULT_MICROSECONDS_PER_BEAT;
    let mut last_tick = 0u64;
    let mut time_s = 0.0f64;
    let seconds_per_tick = |microseconds_per_beat: u32| -> f64 {
        match smf.header.timing {
            Timing::Metrical(ticks_per_beat) => {
                f64::from(microseconds_per_beat) * 1e-6
                    / f64::from(u16::from(ticks_per_beat).max(1))
            }
            Timing::Timecode(fps, ticks_per_frame) => {
                1.0 / (f64::from(fps.as_f32()) * f64::from(ticks_per_frame.max(1)))
            }
        }
    };
    if let Timing::Metrical(_) = smf.header.timing {
        events.push(ScoreEvent {
            time_s: 0.0,
            action: ScoreAction::Tempo(60e6 / f64::from(microseconds_per_beat)),
        });
    }
    for (tick, kind) in merged {
        time_s += (tick - last_tick) as f64 * seconds_per_tick(microseconds_per_beat);
        last_tick = tick;
        let action = match kind {
            TrackEventKind::Meta(MetaMessage::Tempo(tempo)) => {
                microseconds_per_beat = u32::from(tempo).max(1);
                if !matches!(smf.header.timing, Timing::Metrical(_)) {
                    continue;
                }
                ScoreAction::Tempo(60e6 / f64::from(microseconds_per_beat))
            }
            TrackEventKind::Midi { message, .. } => match message {
                MidiMessage::NoteOn { key, vel } => ScoreAction::Engine(EngineEvent::NoteOn {
                    note: u8::from(key),
                    velocity: f32::from(u8::from(vel)) / 127.0,
                }),
                MidiMessage::NoteOff { key, .. } => ScoreAction::Engine(EngineEvent::NoteOff {
                    note: u8::from(key),
                }),
                MidiMessage::Controller { controller, value } => match u8::from(controller) {
                    120 => ScoreAction::Engine(EngineEvent::AllSoundOff),
                    123 => ScoreAction::Engine(EngineEvent::AllNotesOff),
                    number => ScoreAction::Engine(EngineEvent::Controller {
                        number,
                        value: f32::from(u8::from(value)) / 127.0,
                    }),
                },
                MidiMessage::ChannelAftertouch { vel } => ScoreAction::Engine(
                    EngineEvent::ChannelPressure(f32::from(u8::from(vel)) / 127.0),
                ),
                MidiMessage::Aftertouch { key, vel } => {
                    ScoreAction::Engine(EngineEvent::PolyPressure {
                        note: u8::from(key),
                        value: f32::from(u8::from(vel)) / 127.0,
                    })
                }
                MidiMessage::PitchBend { bend } => {
                    ScoreAction::Engine(EngineEvent::PitchBend(bend.as_f32()))
                }
                MidiMessage::ProgramChange { .. } => continue,
            },
            _ => continue,
        };
        events.push(ScoreEvent { time_s, action });
    }
    Ok(Score {
        events,
        end_s: time_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use midly::num::{u15, u28, u4, u7};
    use midly::{Format, Header, TrackEvent};

    fn write(smf: &Smf) -> Vec<u8> {
        let mut bytes = Vec::new();
        smf.write_std(&mut bytes).unwrap();
        bytes
    }

    #[test]
    fn tempo_map_converts_ticks_to_seconds() {
        let note = |delta: u32, on: bool| TrackEvent {
            delta: u28::new(delta),
            kind: TrackEventKind::Midi {
                channel: u4::new(0),
                message: if on {
                    MidiMessage::NoteOn {
                        key: u7::new(60),
                        vel: u7::new(127),
                    }
                } else {
                    MidiMessage::NoteOff {
                        key: u7::new(60),
                        vel: u7::new(0),
                    }
                },
            },
        };
        let track = vec![
            note(480, true), // 1 beat at 120 bpm: 0.5 s
            TrackEvent {
                delta: u28::new(0),
                kind: TrackEventKind::Meta(MetaMessage::Tempo(midly::num::u24::new(1_000_000))),
            },
            note(480, false), // 1 beat at 60 bpm: 1.0 s later
            TrackEvent {
                delta: u28::new(0),
                kind: TrackEventKind::Meta(MetaMessage::EndOfTrack),
            },
        ];
        let smf = Smf {
            header: Header::new(Format::SingleTrack, Timing::Metrical(u15::new(480))),
            tracks: vec![track],
        };
        let score = parse(&write(&smf), "t.mid").unwrap();
        let times: Vec<f64> = score.events.iter().map(|event| event.time_s).collect();
        assert_eq!(times, vec![0.0, 0.5, 0.5, 1.5]);
        assert_eq!(score.events[2].action, ScoreAction::Tempo(60.0));
        assert_eq!(
            score.events[1].action,
            ScoreAction::Engine(EngineEvent::NoteOn {
                note: 60,
                velocity: 1.0
            })
        );
        assert_eq!(score.end_s, 1.5);
    }

    #[test]
    fn garbage_is_a_clear_error_naming_the_file() {
        let error = parse(b"RIFF not midi at all", "song.mid").unwrap_err();
        let message = error.to_string();
        assert!(
            message.starts_with("song.mid: not a valid standard MIDI file"),
            "{message}"
        );
        let truncated = parse(b"MThd\x00\x00\x00\x06\x00", "cut.mid").unwrap_err();
        assert!(truncated.to_string().contains("cut.mid"));
    }
}
