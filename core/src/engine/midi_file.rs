//! Standard MIDI files to a [`Score`]: note and channel-mode events at times in seconds, with
//! the warnings a listener needs about what the file could not give.
//!
//! All tracks are merged (format 0, 1 and 2 alike) and every channel plays the instrument.
//! Metrical timing follows the file's tempo map (set-tempo meta events, 120 bpm until the first
//! one); SMPTE timing uses frames per second × ticks per frame. Note-on with velocity 0 is a
//! note-off; CC 120 (all sound off) and CC 123 (all notes off) are honoured; everything else is
//! ignored. midly reads the chunks and events; this module walks them itself (midly's lazy
//! iterators) so that it knows where each event lies in the file.
//!
//! Refused, with an error naming the file and the place ([`MidiFileError`]):
//! - bytes that are not a standard MIDI file (midly's reason);
//! - a header whose division is 0 ticks per beat or 0 ticks per frame, and a set-tempo of
//!   0 µs per beat: time means nothing in such a file;
//! - a file with no track, or whose tracks hold no note-on with a velocity above 0: it would
//!   render silence.
//!
//! Read, with a warning in [`MidiScore::warnings`]:
//! - a track chunk cut short (the file ends before the length its chunk declares) or an event
//!   that cannot be read: the events before it are kept, and the warning says which track, at
//!   which byte, how many bytes are lost and from what time;
//! - fewer tracks than the header announces;
//! - notes that never end: they are released at the time of the file's last event (as a host
//!   stops every note when playback ends), with an all-notes-off event there.
//!
//! How long a score may be is the renderer's business (`cargo xtask render --max-seconds`);
//! [`MidiScore::describe_length`] says where a long file spends its time. Memory grows with the
//! bytes actually present, never with a count or length the file claims.

use super::render::{Score, ScoreAction, ScoreEvent};
use super::EngineEvent;
use midly::{EventIter, MetaMessage, MidiMessage, Timing, TrackEventKind};
use std::fmt;
use std::path::Path;

/// Tempo before the first set-tempo event (the MIDI standard's default), µs per beat.
const DEFAULT_MICROSECONDS_PER_BEAT: u32 = 500_000;
/// Bytes of a chunk's header: a four-letter ID and a 32-bit length.
const CHUNK_HEADER_BYTES: usize = 8;

/// A MIDI file that could not be read, parsed, or that has nothing to play.
#[derive(Debug, Clone, PartialEq)]
pub struct MidiFileError {
    pub file: String,
    /// What is wrong, and where (header, track, byte offset).
    pub reason: String,
}

impl fmt::Display for MidiFileError {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(formatter, "{}: {}", self.file, self.reason)
    }
}

impl std::error::Error for MidiFileError {}

/// A place in a MIDI file: the track (1-based, in file order) and the event's byte offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventPlace {
    pub track: usize,
    pub byte: usize,
}

impl fmt::Display for EventPlace {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(formatter, "track {}, byte {}", self.track, self.byte)
    }
}

/// The longest stretch of a score without any event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Silence {
    pub from_s: f64,
    pub to_s: f64,
    /// The event that ends it.
    pub until: EventPlace,
}

/// A MIDI file read into a score.
#[derive(Debug, Clone, PartialEq)]
pub struct MidiScore {
    pub score: Score,
    /// What the file could not give (cut-short tracks, unreadable events, notes that never end),
    /// one sentence each, naming the place.
    pub warnings: Vec<String>,
    /// Note-ons with a velocity above 0.
    pub note_count: usize,
    /// Where the score's last event is.
    pub last_event: Option<EventPlace>,
    /// The longest time between two consecutive events (from 0 s for the first one).
    pub longest_silence: Option<Silence>,
}

impl MidiScore {
    /// Where the score's length comes from: its last event and its longest silence.
    pub fn describe_length(&self) -> String {
        let mut text = format!("its last event is at {}", format_time(self.score.end_s));
        if let Some(place) = self.last_event {
            text += &format!(", at {place}");
        }
        if let Some(silence) = self.longest_silence {
            text += &format!(
                "; nothing happens for {} from {} to the event at {}",
                format_time(silence.to_s - silence.from_s),
                format_time(silence.from_s),
                silence.until
            );
        }
        text
    }
}

/// A time in seconds, with hours or minutes when it is long.
pub fn format_time(seconds: f64) -> String {
    if seconds >= 3600.0 {
        format!("{seconds:.1} s ({:.1} h)", seconds / 3600.0)
    } else if seconds >= 60.0 {
        format!("{seconds:.1} s ({:.1} min)", seconds / 60.0)
    } else {
        format!("{seconds:.2} s")
    }
}

/// Reads a MIDI file into a score.
pub fn load(path: &Path) -> Result<MidiScore, MidiFileError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|error| MidiFileError {
        file: file.clone(),
        reason: format!("cannot read the file: {error}"),
    })?;
    parse(&bytes, &file)
}

/// Byte offset of `part` inside `whole` (both slices of the same file).
fn offset_in(whole: &[u8], part: &[u8]) -> usize {
    (part.as_ptr() as usize).wrapping_sub(whole.as_ptr() as usize)
}

/// One event of one track on the file's absolute tick axis.
struct PlacedEvent<'a> {
    tick: u64,
    kind: TrackEventKind<'a>,
    place: EventPlace,
}

/// What [`read_track`] found past the last event it could read.
struct TrackLoss {
    /// Byte at which reading stopped.
    byte: usize,
    /// Bytes of the track not read (including those missing from the file).
    lost_bytes: usize,
    /// Bytes the chunk declares beyond the end of the file (0 when an unreadable event inside a
    /// whole chunk stopped the reading).
    missing_bytes: usize,
    /// Tick of the last event read.
    last_tick: u64,
}

/// Reads one track's events onto `events`; returns what was lost, if anything.
fn read_track<'a>(
    bytes: &'a [u8],
    track: usize,
    mut iter: EventIter<'a>,
    events: &mut Vec<PlacedEvent<'a>>,
) -> Option<TrackLoss> {
    let data = iter.unread();
    let start = offset_in(bytes, data);
    let end = start + data.len();
    // The chunk's declared length sits just before its data (midly hands out the data only).
    let declared = start
        .checked_sub(CHUNK_HEADER_BYTES / 2)
        .and_then(|at| bytes.get(at..start))
        .map_or(data.len(), |field| {
            u32::from_be_bytes([field[0], field[1], field[2], field[3]]) as usize
        });
    let missing = declared.saturating_sub(data.len());
    let mut tick = 0u64;
    loop {
        let byte = offset_in(bytes, iter.unread());
        match iter.next() {
            Some(Ok(event)) => {
                tick += u64::from(u32::from(event.delta));
                events.push(PlacedEvent {
                    tick,
                    kind: event.kind,
                    place: EventPlace { track, byte },
                });
            }
            // midly (without its `strict` feature) ends a track silently at an unreadable
            // event: reading stopped before the chunk's end.
            Some(Err(_)) | None => {
                let lost_bytes = end.saturating_sub(byte) + missing;
                return (lost_bytes > 0).then_some(TrackLoss {
                    byte,
                    lost_bytes,
                    missing_bytes: missing,
                    last_tick: tick,
                });
            }
        }
    }
}

/// Seconds per tick of the file's timing at a tempo of `microseconds_per_beat`.
fn seconds_per_tick(timing: Timing, microseconds_per_beat: u32) -> f64 {
    match timing {
        Timing::Metrical(ticks_per_beat) => {
            f64::from(microseconds_per_beat) * 1e-6 / f64::from(u16::from(ticks_per_beat))
        }
        Timing::Timecode(fps, ticks_per_frame) => {
            1.0 / (f64::from(fps.as_f32()) * f64::from(ticks_per_frame))
        }
    }
}

/// Parses the bytes of a MIDI file; `file` names it in errors and warnings.
pub fn parse(bytes: &[u8], file: &str) -> Result<MidiScore, MidiFileError> {
    let fail = |reason: String| MidiFileError {
        file: file.to_string(),
        reason,
    };
    // midly reads an SMPTE division's frame rate by negating its high byte as an i8, which
    // overflows (a panic where overflow is checked) for 0x80, and it parses every header chunk
    // it meets (a RIFF wrapper's, a duplicate one). No frame rate is −128, so a file with such a
    // header chunk anywhere is refused here first (the division is 12 bytes into the chunk).
    if let Some(at) = bytes
        .windows(13)
        .position(|window| window.starts_with(b"MThd") && window[12] == 0x80)
    {
        return Err(fail(format!(
            "the header's SMPTE division (byte {}) gives −128 frames per second; only 24, 25, \
             29.97 and 30 exist",
            at + 12
        )));
    }
    let (header, tracks) = midly::parse(bytes)
        .map_err(|error| fail(format!("not a valid standard MIDI file: {error}")))?;
    let timing = header.timing;
    match timing {
        Timing::Metrical(ticks_per_beat) if u16::from(ticks_per_beat) == 0 => {
            return Err(fail(
                "the header's division is 0 ticks per beat, which makes every time in the file \
                 meaningless"
                    .to_string(),
            ))
        }
        Timing::Timecode(_, 0) => {
            return Err(fail(
                "the header's SMPTE division is 0 ticks per frame, which makes every time in the \
                 file meaningless"
                    .to_string(),
            ))
        }
        _ => {}
    }
    let announced_tracks = tracks.size_hint().0;

    let mut placed: Vec<PlacedEvent> = Vec::new();
    let mut losses: Vec<(usize, TrackLoss)> = Vec::new();
    let mut track_count = 0;
    for track in tracks {
        // Without midly's `strict` feature a chunk that cannot be read is skipped, never an
        // error; keep the arm for completeness.
        let Ok(iter) = track else { continue };
        track_count += 1;
        if let Some(loss) = read_track(bytes, track_count, iter, &mut placed) {
            losses.push((track_count, loss));
        }
    }
    if track_count == 0 {
        return Err(fail("the file holds no track chunk (MTrk)".to_string()));
    }
    // Merge every track's events on the absolute tick axis; the sort is stable so that events
    // at the same tick keep their order within a track (and tracks keep theirs).
    placed.sort_by_key(|event| event.tick);

    let mut score = Score::default();
    let mut warnings = Vec::new();
    let mut microseconds_per_beat = DEFAULT_MICROSECONDS_PER_BEAT;
    let mut last_tick = 0u64;
    let mut time_s = 0.0f64;
    // The times of the ticks at which a track's reading stopped, for the warnings.
    let mut loss_ticks: Vec<u64> = losses.iter().map(|(_, loss)| loss.last_tick).collect();
    loss_ticks.sort_unstable();
    loss_ticks.dedup();
    let mut tick_times: Vec<(u64, f64)> = Vec::new();
    if let Timing::Metrical(_) = timing {
        score.events.push(ScoreEvent {
            time_s: 0.0,
            action: ScoreAction::Tempo(60e6 / f64::from(microseconds_per_beat)),
        });
    }
    let mut note_count = 0;
    let mut last_event = None;
    let mut longest_silence: Option<Silence> = None;
    // Notes sounding, per channel and key, and the first note-on of each (for the warning).
    let mut held = [[None::<(f64, EventPlace)>; 128]; 16];
    for event in &placed {
        let from_s = time_s;
        time_s += (event.tick - last_tick) as f64 * seconds_per_tick(timing, microseconds_per_beat);
        last_tick = event.tick;
        if longest_silence.is_none_or(|silence| time_s - from_s > silence.to_s - silence.from_s) {
            longest_silence = Some(Silence {
                from_s,
                to_s: time_s,
                until: event.place,
            });
        }
        last_event = Some(event.place);
        if loss_ticks.binary_search(&event.tick).is_ok()
            && tick_times
                .last()
                .is_none_or(|(tick, _)| *tick != event.tick)
        {
            tick_times.push((event.tick, time_s));
        }
        let action = match event.kind {
            TrackEventKind::Meta(MetaMessage::Tempo(tempo)) => {
                if u32::from(tempo) == 0 {
                    return Err(fail(format!(
                        "{}: a set-tempo of 0 µs per beat makes the time of every later event \
                         meaningless",
                        event.place
                    )));
                }
                microseconds_per_beat = u32::from(tempo);
                if !matches!(timing, Timing::Metrical(_)) {
                    continue;
                }
                ScoreAction::Tempo(60e6 / f64::from(microseconds_per_beat))
            }
            TrackEventKind::Midi { channel, message } => {
                let channel = usize::from(u8::from(channel));
                match message {
                    MidiMessage::NoteOn { key, vel } if u8::from(vel) > 0 => {
                        note_count += 1;
                        let slot = &mut held[channel][usize::from(u8::from(key))];
                        if slot.is_none() {
                            *slot = Some((time_s, event.place));
                        }
                        ScoreAction::Engine(EngineEvent::NoteOn {
                            note: u8::from(key),
                            velocity: f32::from(u8::from(vel)) / 127.0,
                        })
                    }
                    MidiMessage::NoteOn { key, .. } | MidiMessage::NoteOff { key, .. } => {
                        held[channel][usize::from(u8::from(key))] = None;
                        ScoreAction::Engine(EngineEvent::NoteOff {
                            note: u8::from(key),
                        })
                    }
                    MidiMessage::Controller { controller, value } => match u8::from(controller) {
                        120 | 123 => {
                            held[channel] = [None; 128];
                            ScoreAction::Engine(if u8::from(controller) == 120 {
                                EngineEvent::AllSoundOff
                            } else {
                                EngineEvent::AllNotesOff
                            })
                        }
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
                }
            }
            _ => continue,
        };
        score.events.push(ScoreEvent { time_s, action });
    }
    score.end_s = time_s;

    // The time of a tick already passed (the last event read of a track), for the warnings.
    let time_of = |tick: u64| -> f64 {
        tick_times
            .binary_search_by_key(&tick, |(at, _)| *at)
            .map_or(0.0, |index| tick_times[index].1)
    };
    for (track, loss) in &losses {
        let what = if loss.missing_bytes > 0 {
            format!(
                "track {track} is cut short: the file ends {} bytes before the track's declared \
                 end, and reading stops at byte {} ({} bytes of the track lost)",
                loss.missing_bytes, loss.byte, loss.lost_bytes
            )
        } else {
            format!(
                "track {track}: the event at byte {} cannot be read, and the {} bytes from there \
                 to the track's end are skipped",
                loss.byte, loss.lost_bytes
            )
        };
        warnings.push(format!(
            "{what}; whatever the track held after {} is lost",
            format_time(time_of(loss.last_tick))
        ));
    }
    if track_count < announced_tracks {
        warnings.push(format!(
            "the header announces {announced_tracks} tracks but the file holds {track_count}: \
             the other {} are lost",
            announced_tracks - track_count
        ));
    }
    let mut never_ending = held
        .iter()
        .enumerate()
        .flat_map(|(channel, keys)| {
            keys.iter().enumerate().filter_map(move |(key, start)| {
                start.map(|(time_s, place)| (time_s, place, channel, key))
            })
        })
        .collect::<Vec<_>>();
    never_ending.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(&(first_s, place, channel, key)) = never_ending.first() {
        warnings.push(format!(
            "{} note{} never end{} (the first, note {key} on channel {}, starts at {} at \
             {place}); released at the file's last event, {}",
            never_ending.len(),
            if never_ending.len() == 1 { "" } else { "s" },
            if never_ending.len() == 1 { "s" } else { "" },
            channel + 1,
            format_time(first_s),
            format_time(score.end_s)
        ));
        score.events.push(ScoreEvent {
            time_s: score.end_s,
            action: ScoreAction::Engine(EngineEvent::AllNotesOff),
        });
    }

    if note_count == 0 {
        let mut reason = format!(
            "no notes: the file's {} event{} in {track_count} track{} hold no note-on with a \
             velocity above 0, so there is nothing to play",
            placed.len(),
            if placed.len() == 1 { "" } else { "s" },
            if track_count == 1 { "" } else { "s" },
        );
        for warning in &warnings {
            reason += &format!("; {warning}");
        }
        return Err(fail(reason));
    }
    Ok(MidiScore {
        score,
        warnings,
        note_count,
        last_event,
        longest_silence,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use midly::num::{u15, u28, u4, u7};
    use midly::{Format, Header, Smf, TrackEvent};

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
        let score = parse(&write(&smf), "t.mid").unwrap().score;
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

    /// A format-1 file with the given division bytes and raw track data (each given its chunk
    /// header with its true length).
    fn file_with(division: [u8; 2], tracks: &[&[u8]]) -> Vec<u8> {
        let mut bytes = b"MThd\0\0\0\x06\0\x01".to_vec();
        bytes.extend_from_slice(&(tracks.len() as u16).to_be_bytes());
        bytes.extend_from_slice(&division);
        for track in tracks {
            bytes.extend_from_slice(b"MTrk");
            bytes.extend_from_slice(&(track.len() as u32).to_be_bytes());
            bytes.extend_from_slice(track);
        }
        bytes
    }

    /// Delta 0, note-on C4; one beat (480 ticks) later its note-off; end of track.
    const ONE_NOTE: &[u8] = b"\x00\x90\x3c\x64\x83\x60\x80\x3c\x00\x00\xff\x2f\x00";
    const DIVISION_480: [u8; 2] = [0x01, 0xe0];

    #[test]
    fn a_plain_file_reads_without_warnings() {
        let read = parse(&file_with(DIVISION_480, &[ONE_NOTE]), "ok.mid").unwrap();
        assert!(read.warnings.is_empty(), "{:?}", read.warnings);
        assert_eq!(read.note_count, 1);
        assert_eq!(read.score.end_s, 0.5);
        assert_eq!(
            read.last_event,
            Some(EventPlace {
                track: 1,
                byte: 14 + 8 + 9
            })
        );
    }

    #[test]
    fn divisions_and_tempos_that_make_time_meaningless_are_refused() {
        let zero_division = parse(&file_with([0, 0], &[ONE_NOTE]), "z.mid").unwrap_err();
        assert!(
            zero_division
                .to_string()
                .starts_with("z.mid: the header's division is 0 ticks"),
            "{zero_division}"
        );
        // SMPTE: −25 frames per second, 0 ticks per frame.
        let smpte = parse(&file_with([0xe7, 0], &[ONE_NOTE]), "s.mid").unwrap_err();
        assert!(smpte.reason.contains("0 ticks per frame"), "{smpte}");
        // Note-on, then a set-tempo of 0 µs per beat (at byte 14 + 8 + 4).
        let track = b"\x00\x90\x3c\x64\x00\xff\x51\x03\x00\x00\x00\x00\xff\x2f\x00";
        let tempo = parse(&file_with(DIVISION_480, &[track]), "t.mid").unwrap_err();
        assert_eq!(
            tempo.to_string(),
            "t.mid: track 1, byte 26: a set-tempo of 0 µs per beat makes the time of every \
             later event meaningless"
        );
    }

    #[test]
    fn an_smpte_division_of_minus_128_frames_is_refused() {
        // Found by the midi_file fuzz target: midly's negation of 0x80 overflows.
        let error = parse(&file_with([0x80, 0x3c], &[ONE_NOTE]), "f.mid").unwrap_err();
        assert!(
            error.reason.contains("byte 12) gives −128 frames"),
            "{error}"
        );
    }

    #[test]
    fn smpte_division_counts_frames() {
        // 25 frames per second, 40 ticks per frame: 1000 ticks per second; the note-off comes
        // 480 ticks after the note-on.
        let read = parse(&file_with([0xe7, 40], &[ONE_NOTE]), "s.mid").unwrap();
        assert!((read.score.end_s - 0.48).abs() < 1e-12);
    }

    #[test]
    fn a_track_cut_short_keeps_what_was_read_and_says_what_is_lost() {
        // Two notes, the second at 1 s; the file ends inside the second note-off.
        let track = b"\x00\x90\x3c\x64\x83\x60\x80\x3c\x00\x83\x60\x90\x3e\x64\x83\x60\x80\x3e\x00\x00\xff\x2f\x00";
        let whole = file_with(DIVISION_480, &[track]);
        let cut = &whole[..whole.len() - 6];
        let read = parse(cut, "cut.mid").unwrap();
        assert_eq!(read.note_count, 2);
        assert_eq!(read.score.end_s, 1.0);
        assert_eq!(
            read.warnings[0],
            "track 1 is cut short: the file ends 6 bytes before the track's declared end, and \
             reading stops at byte 36 (9 bytes of the track lost); whatever the track held \
             after 1.00 s is lost"
        );
        // The second note never ends (its note-off was lost): it is released at the end.
        assert!(read.warnings[1].starts_with("1 note never ends (the first, note 62 on channel 1, starts at 1.00 s at track 1, byte 31)"), "{}", read.warnings[1]);
        assert_eq!(
            read.score.events.last().unwrap().action,
            ScoreAction::Engine(EngineEvent::AllNotesOff)
        );
    }

    #[test]
    fn an_unreadable_event_and_missing_tracks_are_warned_about() {
        // A second track that starts with a data byte (there is no running status to reuse).
        let track = b"\x00\x3c\x40\x00\xff\x2f\x00";
        let mut bytes = file_with(DIVISION_480, &[ONE_NOTE, track]);
        bytes[11] = 4; // the header announces four tracks
        let read = parse(&bytes, "bad.mid").unwrap();
        assert!(
            read.warnings[0].starts_with(
                "track 2: the event at byte 43 cannot be read, and the 7 bytes from there to the \
                 track's end are skipped; whatever the track held after 0.00 s is lost"
            ),
            "{:?}",
            read.warnings
        );
        assert!(
            read.warnings[1].contains("announces 4 tracks but the file holds 2"),
            "{:?}",
            read.warnings
        );
    }

    #[test]
    fn a_file_without_notes_is_refused() {
        let track = b"\x00\xb0\x07\x64\x00\x90\x3c\x00\x00\xff\x2f\x00";
        let error = parse(&file_with(DIVISION_480, &[track]), "quiet.mid").unwrap_err();
        assert!(
            error
                .to_string()
                .starts_with("quiet.mid: no notes: the file's 3 events in 1 track hold no note-on"),
            "{error}"
        );
        // Cut at its start: the lost bytes are named as well.
        let whole = file_with(DIVISION_480, &[ONE_NOTE]);
        let error = parse(&whole[..24], "cut.mid").unwrap_err();
        assert!(error.reason.contains("no notes"), "{error}");
        assert!(error.reason.contains("reading stops at byte 22"), "{error}");
        let error = parse(b"MThd\0\0\0\x06\0\x01\0\x01\x01\xe0", "empty.mid").unwrap_err();
        assert!(error.reason.contains("no track chunk"), "{error}");
    }

    #[test]
    fn a_file_whose_events_lie_hours_apart_says_where_the_time_goes() {
        // Division 1 tick per beat, the slowest tempo (16.8 s per beat), a delta of 2^28 − 1
        // ticks before the note-off: 4.5e9 s.
        let track = b"\x00\xff\x51\x03\xff\xff\xff\x00\x90\x3c\x64\xff\xff\xff\x7f\x80\x3c\x00";
        let read = parse(&file_with([0, 1], &[track]), "far.mid").unwrap();
        let expected_s = 16.777_215 * f64::from((1u32 << 28) - 1);
        assert!((read.score.end_s / expected_s - 1.0).abs() < 1e-12);
        let text = read.describe_length();
        assert!(
            text.contains("at 4503599342.2 s (1250999.8 h), at track 1, byte 33"),
            "{text}"
        );
        assert!(text.contains("nothing happens for"), "{text}");
    }

    #[test]
    fn a_chunk_claiming_four_gigabytes_costs_only_what_is_there() {
        let mut bytes = file_with(DIVISION_480, &[ONE_NOTE]);
        bytes[18..22].copy_from_slice(&u32::MAX.to_be_bytes());
        let read = parse(&bytes, "huge.mid").unwrap();
        assert_eq!(read.note_count, 1);
        assert!(
            read.warnings[0].contains("cut short"),
            "{:?}",
            read.warnings
        );
    }
}
