//! Offline rendering: a [`Score`] (events at times in seconds) through the [`Engine`] in blocks,
//! exactly as a host would drive the plugin. `cargo xtask render` and the tests/ crate both call
//! [`render`], so what they check is what users hear.

use super::{Engine, EngineEvent, EngineSettings, Instrument, TimedEvent, VoiceRunner};
use crate::tanpura::as_played::{Calibration, CalibrationRequest};

/// Voices the plugin and the renderer allocate: the four drone strings plus four more for
/// melody notes or overlapping cycles.
pub const DEFAULT_VOICE_COUNT: usize = 8;
/// Most events the renderer hands to one `process` call (a block is split when it has more).
const MAX_EVENTS_PER_CALL: usize = 256;

/// What happens at a score time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScoreAction {
    Engine(EngineEvent),
    /// The host's tempo from here on, beats per minute.
    Tempo(f64),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScoreEvent {
    pub time_s: f64,
    pub action: ScoreAction,
}

/// Events sorted by time, and the time of the last one.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Score {
    pub events: Vec<ScoreEvent>,
    pub end_s: f64,
}

impl Score {
    /// The built-in demo: two cycles of a tanpura's four strings played as notes (G2 for Pa,
    /// C3, C3, C2 for low Sa; one beat at 60 bpm, a rest of two after the low Sa), then a C3–E3–G3
    /// arpeggio, so that it sounds the same with any preset.
    pub fn demo() -> Self {
        let mut score = Score::default();
        let cycle = [(43u8, 0.0), (48, 1.0), (48, 2.0), (36, 3.0)];
        for start in [0.0, 5.0] {
            for (note, offset) in cycle {
                score.note(start + offset, 0.8, note, 0.9);
            }
        }
        for (index, note) in [48u8, 52, 55].into_iter().enumerate() {
            score.note(10.0 + 0.25 * index as f64, 1.0, note, 0.7);
        }
        score
    }

    /// The notes the score plays (note-ons with a velocity), in score order.
    pub fn played_notes(&self) -> Vec<u8> {
        self.events
            .iter()
            .filter_map(|event| match event.action {
                ScoreAction::Engine(EngineEvent::NoteOn { note, velocity }) if velocity > 0.0 => {
                    Some(note)
                }
                _ => None,
            })
            .collect()
    }

    /// Appends a note-on at `time_s` and its note-off `duration_s` later, keeping the order.
    pub fn note(&mut self, time_s: f64, duration_s: f64, note: u8, velocity: f32) {
        self.push(
            time_s,
            ScoreAction::Engine(EngineEvent::NoteOn { note, velocity }),
        );
        self.push(
            time_s + duration_s,
            ScoreAction::Engine(EngineEvent::NoteOff { note }),
        );
    }

    /// Inserts an event after every event at the same or an earlier time.
    pub fn push(&mut self, time_s: f64, action: ScoreAction) {
        let index = self.events.partition_point(|event| event.time_s <= time_s);
        self.events.insert(index, ScoreEvent { time_s, action });
        self.end_s = self.end_s.max(time_s);
    }
}

/// How to render.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    pub sample_rate_hz: f64,
    /// Samples per `process` call, as a host's buffer size.
    pub block_size: usize,
    /// Time rendered after the score's last event, s.
    pub tail_s: f64,
    pub voice_count: usize,
    /// 1: the mono output; 2: the stereo image ([`Engine::process_stereo`]), the blocks
    /// handed out interleaved (left, right).
    pub channels: usize,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            sample_rate_hz: 44_100.0,
            block_size: 512,
            tail_s: 3.0,
            voice_count: DEFAULT_VOICE_COUNT,
            channels: 1,
        }
    }
}

/// The sample index of a score time (rounded to the nearest sample).
pub fn time_to_sample(time_s: f64, sample_rate_hz: f64) -> usize {
    (time_s.max(0.0) * sample_rate_hz).round() as usize
}

/// Number of samples [`render`] produces (saturating: a score that would last longer than
/// memory could hold gives `usize::MAX`, which callers refuse long before rendering).
pub fn rendered_length(score: &Score, options: &RenderOptions) -> usize {
    time_to_sample(
        score.end_s + options.tail_s.max(0.0),
        options.sample_rate_hz,
    )
    .saturating_add(1)
}

/// Renders `score` with `settings` to a mono signal at full scale ±1. `progress(done, total)`
/// is called after every block.
pub fn render(
    settings: &EngineSettings,
    score: &Score,
    options: &RenderOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Vec<f32> {
    collect(settings, score, options, None, progress)
}

/// [`render`] with the voices run by `runner` ([`Engine::process_with`]), e.g. on a thread pool;
/// the signal is bit-identical to [`render`]'s.
pub fn render_with(
    settings: &EngineSettings,
    score: &Score,
    options: &RenderOptions,
    runner: VoiceRunner<'_>,
    progress: &mut dyn FnMut(usize, usize),
) -> Vec<f32> {
    collect(settings, score, options, Some(runner), progress)
}

/// The whole signal of [`render_blocks`] in memory.
fn collect(
    settings: &EngineSettings,
    score: &Score,
    options: &RenderOptions,
    runner: Option<VoiceRunner<'_>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Vec<f32> {
    let total = rendered_length(score, options);
    let channels = options.channels.max(1);
    let mut output = Vec::with_capacity(total * channels);
    let streamed: Result<(), std::convert::Infallible> =
        render_blocks(settings, score, options, runner, &mut |block| {
            output.extend_from_slice(block);
            progress(output.len() / channels, total);
            Ok(())
        });
    let Ok(()) = streamed;
    output
}

/// Renders `score` block by block, handing each block's samples to `emit` as soon as they are
/// computed (the renderer streams them to disk, so memory does not grow with the score's
/// length). The blocks are those [`render`] computes, so the samples are bit-identical to its
/// signal; `runner` runs the voices as in [`render_with`]. An error from `emit` stops the render
/// and is returned.
pub fn render_blocks<E>(
    settings: &EngineSettings,
    score: &Score,
    options: &RenderOptions,
    runner: Option<VoiceRunner<'_>>,
    emit: &mut dyn FnMut(&[f32]) -> Result<(), E>,
) -> Result<(), E> {
    render_blocks_calibrated(settings, &[], score, options, runner, emit)
}

/// What a score's strings need to be tuned as played (`tanpura/as_played.rs`): every string it
/// plucks, none when the as-played tuning is off or the instrument is bowed. The renderer
/// measures them ([`Calibration::measure`], off the audio thread and in parallel) and passes
/// them to [`render_blocks_calibrated`].
pub fn calibration_requests(settings: &EngineSettings, score: &Score) -> Vec<CalibrationRequest> {
    if !settings.tuning.as_played || settings.instrument != Instrument::Tanpura {
        return Vec::new();
    }
    Engine::planned_strings(settings, &score.played_notes())
}

/// The sample from which each of `requests` (a score's [`calibration_requests`]) is needed: that
/// of the first note-on whose strings ([`Engine::planned_strings`] of its note) include it; 0
/// for every string of a drone on a fixed Sa, which plays from the start, and for a request no
/// note-on plucks. A renderer may hand a calibration to [`render_blocks_scheduled`] as late as
/// this and render the same samples as with every calibration given before the first block.
pub fn calibration_need_samples(
    settings: &EngineSettings,
    score: &Score,
    sample_rate_hz: f64,
    requests: &[CalibrationRequest],
) -> Vec<usize> {
    let clamped = settings.clamped();
    let fixed_sa = clamped.drone.enabled && clamped.drone.sa_note.is_some();
    let mut needed_at: Vec<Option<usize>> = vec![fixed_sa.then_some(0); requests.len()];
    // A note's strings are needed from its first note-on; its later ones change nothing.
    let mut played = [false; 128];
    for event in &score.events {
        let ScoreAction::Engine(EngineEvent::NoteOn { note, velocity }) = event.action else {
            continue;
        };
        let Some(first) = played.get_mut(usize::from(note)) else {
            continue;
        };
        if velocity <= 0.0 || *first {
            continue;
        }
        *first = true;
        let at = time_to_sample(event.time_s, sample_rate_hz);
        for string in Engine::planned_strings(settings, &[note]) {
            for (request, needed) in requests.iter().zip(needed_at.iter_mut()) {
                if *request == string && needed.is_none() {
                    *needed = Some(at);
                }
            }
        }
    }
    needed_at
        .into_iter()
        .map(|needed| needed.unwrap_or(0))
        .collect()
}

/// [`render_blocks`] with the strings tuned as played by `calibrations` (see
/// [`calibration_requests`]); strings without one keep their linearised tuning.
pub fn render_blocks_calibrated<E>(
    settings: &EngineSettings,
    calibrations: &[Calibration],
    score: &Score,
    options: &RenderOptions,
    runner: Option<VoiceRunner<'_>>,
    emit: &mut dyn FnMut(&[f32]) -> Result<(), E>,
) -> Result<(), E> {
    let up_front = vec![0; calibrations.len()];
    render_blocks_scheduled(
        settings,
        &up_front,
        &mut |index| calibrations[index],
        score,
        options,
        runner,
        emit,
    )
}

/// [`render_blocks_calibrated`] with calibration `i` taken from `calibration(i)` just before
/// sample `needed_at[i]` ([`calibration_need_samples`]; a block is cut there), in the order of those
/// samples (ties by index), so that a renderer can measure the strings a score plucks later
/// while it renders the first. `calibration` may wait for its calibration to be measured; it is
/// called once for each index, and not at all for one needed after the render's end. The
/// samples depend on the schedule only through the engine's table of calibrations: they are
/// those of every calibration given up front whenever the table holds them all
/// ([`crate::tanpura::as_played::AS_PLAYED_CAPACITY`] strings).
pub fn render_blocks_scheduled<E>(
    settings: &EngineSettings,
    needed_at: &[usize],
    calibration: &mut dyn FnMut(usize) -> Calibration,
    score: &Score,
    options: &RenderOptions,
    runner: Option<VoiceRunner<'_>>,
    emit: &mut dyn FnMut(&[f32]) -> Result<(), E>,
) -> Result<(), E> {
    let mut engine = Engine::new(settings, options.sample_rate_hz, options.voice_count);
    let mut schedule: Vec<usize> = (0..needed_at.len()).collect();
    schedule.sort_by_key(|&index| (needed_at[index], index));
    let mut next_calibration = 0;
    let total = rendered_length(score, options);
    let block_size = options.block_size.max(1);
    let mut output = vec![0.0f32; block_size];
    let stereo = options.channels == 2;
    let mut right = vec![0.0f32; if stereo { block_size } else { 0 }];
    let mut interleaved = vec![0.0f32; if stereo { 2 * block_size } else { 0 }];
    let mut block_events: Vec<TimedEvent> = Vec::with_capacity(MAX_EVENTS_PER_CALL);
    let mut next_event = 0;
    let mut start = 0;
    while start < total {
        let block_end = start + block_size.min(total - start);
        // A block is cut short at a tempo change (the host reports tempo per block) or when it
        // holds more events than one call takes.
        let mut end = block_end;
        let mut engine_events = 0;
        for event in &score.events[next_event..] {
            let at = time_to_sample(event.time_s, options.sample_rate_hz);
            if at >= end {
                break;
            }
            let is_tempo = matches!(event.action, ScoreAction::Tempo(_));
            if at > start && (is_tempo || engine_events == MAX_EVENTS_PER_CALL) {
                end = at;
                break;
            }
            engine_events += usize::from(!is_tempo);
        }
        // And at the first pluck of a string whose calibration is still to come, so that it is
        // taken just before that pluck whatever the block size.
        let later = schedule[next_calibration..]
            .iter()
            .map(|&index| needed_at[index])
            .find(|&needed| needed > start);
        if let Some(needed) = later.filter(|&needed| needed < end) {
            end = needed;
        }
        while let Some(&index) = schedule.get(next_calibration) {
            if needed_at[index] >= end {
                break;
            }
            engine.set_calibration(&calibration(index));
            next_calibration += 1;
        }
        block_events.clear();
        while let Some(event) = score.events.get(next_event) {
            let at = time_to_sample(event.time_s, options.sample_rate_hz);
            if at >= end || block_events.len() == MAX_EVENTS_PER_CALL {
                break;
            }
            match event.action {
                ScoreAction::Tempo(tempo) => engine.set_host_tempo(Some(tempo)),
                ScoreAction::Engine(engine_event) => block_events.push(TimedEvent {
                    offset: at.saturating_sub(start),
                    event: engine_event,
                }),
            }
            next_event += 1;
        }
        let block = &mut output[..end - start];
        if stereo {
            let right = &mut right[..end - start];
            match runner {
                None => engine.process_stereo(&block_events, block, right),
                Some(runner) => engine.process_stereo_with(&block_events, block, right, runner),
            }
            let interleaved = &mut interleaved[..2 * (end - start)];
            for ((pair, left), right) in interleaved.chunks_exact_mut(2).zip(&*block).zip(&*right) {
                pair[0] = *left;
                pair[1] = *right;
            }
            emit(interleaved)?;
        } else {
            match runner {
                None => engine.process(&block_events, block),
                Some(runner) => engine.process_with(&block_events, block, runner),
            }
            emit(block)?;
        }
        start = end;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::VoiceTask;

    #[test]
    fn score_keeps_events_sorted_and_stable() {
        let mut score = Score::default();
        score.note(1.0, 1.0, 60, 1.0);
        score.note(0.5, 0.5, 62, 1.0);
        let times: Vec<f64> = score.events.iter().map(|event| event.time_s).collect();
        assert_eq!(times, vec![0.5, 1.0, 1.0, 2.0]);
        // At 1.0 s the earlier-inserted note-on stays before the later note-off.
        assert_eq!(
            score.events[1].action,
            ScoreAction::Engine(EngineEvent::NoteOn {
                note: 60,
                velocity: 1.0
            })
        );
        assert_eq!(score.end_s, 2.0);
    }

    #[test]
    fn a_stereo_render_is_interleaved_and_its_mid_is_the_mono_render() {
        let mut score = Score::default();
        for (index, note) in [43u8, 55, 67].into_iter().enumerate() {
            score.note(0.01 * index as f64, 0.1, note, 0.9);
        }
        let mut settings = EngineSettings::default();
        settings.voice.quality = crate::tanpura::quality::Quality::Live;
        settings.stereo_width = 1.0;
        let mono_options = RenderOptions {
            tail_s: 0.2,
            block_size: 100,
            ..RenderOptions::default()
        };
        let stereo_options = RenderOptions {
            channels: 2,
            ..mono_options
        };
        let mono = render(&settings, &score, &mono_options, &mut |_, _| {});
        let stereo = render(&settings, &score, &stereo_options, &mut |_, _| {});
        assert_eq!(stereo.len(), 2 * mono.len());
        let mut differ = false;
        for (pair, mono) in stereo.chunks_exact(2).zip(&mono) {
            let (left, right) = (pair[0], pair[1]);
            assert!((0.5 * (left + right) - mono).abs() <= 1e-6 * (left.abs() + right.abs()));
            differ |= left != right;
        }
        assert!(differ, "notes by pitch spread over the image");
    }

    #[test]
    fn voices_run_in_any_order_sum_to_the_same_bits() {
        // Overlapping notes on several strings, drone-free, at the cheapest tier.
        let mut score = Score::default();
        for (index, note) in [43u8, 48, 52, 55, 36].into_iter().enumerate() {
            score.note(0.01 * index as f64, 0.1, note, 0.9);
        }
        let mut settings = EngineSettings::default();
        settings.voice.quality = crate::tanpura::quality::Quality::Live;
        let options = RenderOptions {
            tail_s: 0.05,
            block_size: 100,
            ..RenderOptions::default()
        };
        let in_turn = render(&settings, &score, &options, &mut |_, _| {});
        let backwards: VoiceRunner<'_> = &|tasks| tasks.iter_mut().rev().for_each(VoiceTask::run);
        let reversed = render_with(&settings, &score, &options, backwards, &mut |_, _| {});
        assert!(in_turn.iter().any(|&sample| sample != 0.0));
        let bits = |signal: &[f32]| signal.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&in_turn), bits(&reversed));
    }

    #[test]
    fn blocks_stream_the_same_bits_as_the_whole_signal() {
        let mut settings = EngineSettings::default();
        settings.voice.quality = crate::tanpura::quality::Quality::Live;
        let mut score = Score::default();
        score.note(0.0, 0.02, 48, 0.9);
        score.push(0.013, ScoreAction::Tempo(90.0));
        let options = RenderOptions {
            tail_s: 0.03,
            block_size: 300,
            ..RenderOptions::default()
        };
        let whole = render(&settings, &score, &options, &mut |_, _| {});
        let mut streamed = Vec::new();
        let mut longest_block = 0;
        let result: Result<(), ()> =
            render_blocks(&settings, &score, &options, None, &mut |block| {
                longest_block = longest_block.max(block.len());
                streamed.extend_from_slice(block);
                Ok(())
            });
        result.unwrap();
        assert_eq!(longest_block, 300);
        let bits = |signal: &[f32]| signal.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&whole), bits(&streamed));
        // An error from the sink stops the render at once.
        let mut calls = 0;
        let stopped = render_blocks(&settings, &score, &options, None, &mut |_| {
            calls += 1;
            Err("disk full")
        });
        assert_eq!((stopped, calls), (Err("disk full"), 1));
    }

    #[test]
    fn the_length_of_an_absurdly_long_score_saturates() {
        let score = Score {
            events: Vec::new(),
            end_s: 1e300,
        };
        assert_eq!(
            rendered_length(&score, &RenderOptions::default()),
            usize::MAX
        );
    }

    #[test]
    fn demo_ends_after_the_arpeggio() {
        let demo = Score::demo();
        assert_eq!(demo.end_s, 11.5);
        assert_eq!(demo.events.len(), 22);
    }

    /// Each string of the demo is needed from its first note-on (the arpeggio's E3 and G3 only
    /// from 10.25 and 10.5 s, so a renderer measures them while it renders the drone), and every
    /// string of a drone on a fixed Sa from the start.
    /// A calibration is taken when the render has reached its string's first pluck, not at the
    /// start of a long block that holds it: a block is cut there (so that a renderer measuring
    /// later strings alongside has until the pluck itself).
    #[test]
    fn a_calibration_is_taken_at_its_strings_first_pluck_whatever_the_block() {
        let mut settings = EngineSettings::default();
        settings.voice.quality = crate::tanpura::quality::Quality::Live;
        let mut score = Score::default();
        for (index, note) in [43u8, 48, 52].into_iter().enumerate() {
            score.note(0.013 * index as f64, 0.01, note, 0.9);
        }
        let options = RenderOptions {
            tail_s: 0.01,
            block_size: 4096,
            ..RenderOptions::default()
        };
        let requests = calibration_requests(&settings, &score);
        let needed_at = calibration_need_samples(&settings, &score, 44_100.0, &requests);
        assert_eq!(needed_at, [0, 573, 1147]);
        let rendered = std::cell::Cell::new(0);
        let taken_at = std::cell::RefCell::new(Vec::new());
        let result: Result<(), ()> = render_blocks_scheduled(
            &settings,
            &needed_at,
            &mut |index| {
                taken_at.borrow_mut().push(rendered.get());
                Calibration {
                    request: requests[index],
                    sample_rate_hz: 44_100.0,
                    offset_cents: 0.0,
                    thread_offset_m: 0.0,
                }
            },
            &score,
            &options,
            None,
            &mut |block| {
                rendered.set(rendered.get() + block.len());
                Ok(())
            },
        );
        result.unwrap();
        assert_eq!(taken_at.into_inner(), needed_at);
    }

    #[test]
    fn a_string_is_needed_from_the_first_note_on_that_plucks_it() {
        let settings = EngineSettings::default();
        let demo = Score::demo();
        let requests = calibration_requests(&settings, &demo);
        let notes: Vec<f64> = requests
            .iter()
            .map(|request| request.settings.fundamental_hz)
            .collect();
        let expected_hz = [43u8, 48, 36, 52, 55].map(|note| settings.tuning.note_hz(note));
        assert_eq!(notes, expected_hz);
        let needed_at = calibration_need_samples(&settings, &demo, 44_100.0, &requests);
        assert_eq!(needed_at, [0, 44_100, 132_300, 452_025, 463_050]);
        let mut drone = settings;
        drone.drone.enabled = true;
        drone.drone.sa_note = Some(50);
        let requests = calibration_requests(&drone, &demo);
        // Pa, the two Sa strings (one pitch) and low Sa.
        assert_eq!(requests.len(), 3);
        let needed_at = calibration_need_samples(&drone, &demo, 44_100.0, &requests);
        assert!(needed_at.iter().all(|&sample| sample == 0));
    }
}
