//! The thread that tunes strings by their sustained pitch as played
//! (`javari_core::tanpura::as_played`): a calibration renders a few seconds of a string, which
//! the audio thread cannot afford, so the audio thread hands the strings it plucks without a
//! current calibration to this thread and takes the measured calibrations back at the start of a
//! later block. A string plays with its linearised tuning (or the last calibration of its note)
//! until then: about a second after the first pluck of a new note at the live tier, several at
//! the studio tier, whose calibration takes the reference's jawari and so measures the
//! reference's calibration first (`as_played::jawari_set_on`). With each calibration the worker
//! tunes the string it calibrates (`Calibration::calibrated_tension_n`) and hands the tension
//! back with it, so that the string's next pluck configures it once at that tension instead of
//! tuning it on the audio thread (`Engine::set_calibration_tuned`).
//!
//! Both directions are lock-free fixed-size queues (`crossbeam::queue::ArrayQueue`): the audio
//! thread only pushes and pops, never waits, locks or allocates (a full queue drops the request;
//! the engine asks again at the string's next pluck). The worker polls every
//! `POLL_INTERVAL` when idle, and stops when the plugin is dropped.

use crossbeam::queue::ArrayQueue;
use javari_core::engine::Engine;
use javari_core::tanpura::as_played::{Calibration, CalibrationRequest};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Requests and results in flight at once.
const QUEUE_CAPACITY: usize = 16;
/// How long the idle worker sleeps between looks at its queue.
const POLL_INTERVAL: Duration = Duration::from_millis(20);
/// Calibrations the worker remembers, so that a string asked for again is not measured again.
const REMEMBERED: usize = 64;

struct Shared {
    requests: ArrayQueue<(CalibrationRequest, f64)>,
    /// Each calibration with the tension that tunes its string, if one was found.
    results: ArrayQueue<(Calibration, Option<f64>)>,
    stop: AtomicBool,
}

/// The audio thread's end of the tuning worker.
pub struct TuningWorker {
    shared: Arc<Shared>,
}

impl TuningWorker {
    /// Starts the worker thread.
    pub fn start() -> Self {
        let shared = Arc::new(Shared {
            requests: ArrayQueue::new(QUEUE_CAPACITY),
            results: ArrayQueue::new(QUEUE_CAPACITY),
            stop: AtomicBool::new(false),
        });
        let worker = shared.clone();
        // A plugin that cannot start a thread still plays, with its linearised tuning.
        let _ = std::thread::Builder::new()
            .name("javari-tuning".to_string())
            .spawn(move || run(&worker));
        Self { shared }
    }

    /// On the audio thread: hands the finished calibrations to `engine` and passes on the
    /// strings it wants measured. Lock-free, allocation-free.
    pub fn exchange(&self, engine: &mut Engine) {
        while let Some((calibration, tension_n)) = self.shared.results.pop() {
            match tension_n {
                Some(tension_n) => engine.set_calibration_tuned(&calibration, tension_n),
                None => engine.set_calibration(&calibration),
            }
        }
        let rate = engine.sample_rate_hz();
        while let Some(request) = engine.take_wanted_calibration() {
            // A full queue drops it; the string asks again at its next pluck.
            let _ = self.shared.requests.push((request, rate));
        }
    }
}

impl Drop for TuningWorker {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
    }
}

fn run(shared: &Shared) {
    let mut remembered: Vec<Calibration> = Vec::with_capacity(REMEMBERED);
    while !shared.stop.load(Ordering::Relaxed) {
        let Some((request, rate)) = shared.requests.pop() else {
            std::thread::sleep(POLL_INTERVAL);
            continue;
        };
        let calibration = recall_or_measure(&mut remembered, &request, rate);
        let result = (calibration, calibration.calibrated_tension_n());
        // The audio thread empties the queue every block; if it is full, wait for it.
        while shared.results.push(result).is_err() {
            if shared.stop.load(Ordering::Relaxed) {
                return;
            }
            std::thread::sleep(POLL_INTERVAL);
        }
    }
}

/// The calibration of `request` from `remembered`, else measured and remembered (the oldest
/// forgotten beyond [`REMEMBERED`]); the calibration whose jawari it takes (a studio string's:
/// the reference's) the same way, so that a note switched between those tiers is measured once.
fn recall_or_measure(
    remembered: &mut Vec<Calibration>,
    request: &CalibrationRequest,
    rate: f64,
) -> Calibration {
    if let Some(known) = remembered.iter().find(|known| known.is_for(request, rate)) {
        return *known;
    }
    let measured = Calibration::measure_with(request, rate, |jawari, rate| {
        recall_or_measure(remembered, jawari, rate)
    });
    if remembered.len() == REMEMBERED {
        remembered.remove(0);
    }
    remembered.push(measured);
    measured
}

#[cfg(test)]
mod tests {
    use super::*;
    use javari_core::engine::{EngineSettings, TimedEvent};
    use javari_core::tanpura::quality::Quality;

    #[test]
    fn a_plucked_note_comes_back_calibrated() {
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Draft;
        let mut engine = Engine::new(&settings, 44_100.0, 2);
        let worker = TuningWorker::start();
        let mut output = [0.0f32; 64];
        let pluck = [TimedEvent::note_on(0, 57, 1.0)];
        engine.process(&pluck, &mut output);
        worker.exchange(&mut engine);
        let deadline = std::time::Instant::now() + Duration::from_secs(120);
        while engine.as_played_tuning().calibrations().count() == 0 {
            assert!(std::time::Instant::now() < deadline, "no calibration came");
            std::thread::sleep(Duration::from_millis(10));
            worker.exchange(&mut engine);
        }
        let calibration = engine.as_played_tuning().calibrations().next().unwrap();
        assert!((calibration.request.settings.fundamental_hz - 220.0).abs() < 1e-9);
        assert!(calibration.offset_cents.is_finite());
        // A3 at the live tier settles without the jawari set.
        assert_eq!(calibration.thread_offset_m, 0.0);
        // The tension came with it: the calibrated string's next pluck has nothing to tune.
        let calibrated = calibration
            .calibrated_settings()
            .expect("a finite calibration");
        assert_eq!(
            engine.tuning_memory().tension_n(&calibrated),
            calibration.calibrated_tension_n()
        );
    }

    #[test]
    fn a_studio_calibration_remembers_the_reference_it_takes_the_jawari_from() {
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Studio;
        let request = Engine::planned_strings(&settings, &[57])[0];
        let reference = request
            .jawari_request()
            .expect("a studio string takes the reference's jawari");
        let rate = 44_100.0;
        let mut remembered = Vec::new();
        let studio = recall_or_measure(&mut remembered, &request, rate);
        assert_eq!(remembered.len(), 2, "the studio's and the reference's");
        assert!(remembered
            .iter()
            .any(|known| known.is_for(&reference, rate)));
        assert!(studio.is_for(&request, rate));
        // Switched to the reference tier, the note is not measured again.
        let recalled = recall_or_measure(&mut remembered, &reference, rate);
        assert_eq!(remembered.len(), 2);
        assert_eq!(recalled.thread_offset_m, studio.thread_offset_m);
    }
}
