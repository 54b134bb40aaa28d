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
//! Between calibrations the worker tunes the strings of the engine's latest tuning plan: after
//! a change of what the tuning sees (the bridge, the thread, the tier, the tuning), the engine
//! hands out the new plan (`Engine::take_wanted_tuning_plan`), and the worker tunes every
//! string in it (in drone mode the drone's strings on its Sa first, then every playable note's)
//! and hands the tensions back one by one (`Engine::remember_tuning`), so that the strings
//! plucked after the change configure their strings instead of tuning them on the audio thread.
//! A newer plan replaces one in progress.
//!
//! Every direction is a lock-free fixed-size queue (`crossbeam::queue::ArrayQueue`): the audio
//! thread only pushes and pops, never waits, locks or allocates (a full request queue drops the
//! request, and the engine asks again at the string's next pluck; a newer plan displaces an
//! older one still queued). The worker polls every `POLL_INTERVAL` when idle, and stops when the
//! plugin is dropped.

use crossbeam::queue::ArrayQueue;
use javari_core::engine::tuning_memory::{PlannedTension, TuningPlan};
use javari_core::engine::Engine;
use javari_core::tanpura::as_played::{Calibration, CalibrationRequest};
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
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
    /// The latest tuning plan not yet taken up (one at most).
    plans: ArrayQueue<TuningPlan>,
    /// Tensions of the plan's strings.
    tensions: ArrayQueue<PlannedTension>,
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
            plans: ArrayQueue::new(1),
            tensions: ArrayQueue::new(QUEUE_CAPACITY),
            stop: AtomicBool::new(false),
        });
        let worker = shared.clone();
        // A plugin that cannot start a thread still plays, with its linearised tuning.
        let _ = std::thread::Builder::new()
            .name("javari-tuning".to_string())
            .spawn(move || run(&worker));
        Self { shared }
    }

    /// On the audio thread: hands the finished calibrations and tensions to `engine` and passes
    /// on the strings it wants measured and the tuning plan it wants tuned. Lock-free,
    /// allocation-free.
    pub fn exchange(&self, engine: &mut Engine) {
        while let Some((calibration, tension_n)) = self.shared.results.pop() {
            match tension_n {
                Some(tension_n) => engine.set_calibration_tuned(&calibration, tension_n),
                None => engine.set_calibration(&calibration),
            }
        }
        while let Some(tuned) = self.shared.tensions.pop() {
            engine.remember_tuning(&tuned);
        }
        let rate = engine.sample_rate_hz();
        while let Some(request) = engine.take_wanted_calibration() {
            // A full queue drops it; the string asks again at its next pluck.
            let _ = self.shared.requests.push((request, rate));
        }
        if let Some(plan) = engine.take_wanted_tuning_plan() {
            // Displaces a plan the worker has not taken up yet.
            let _ = self.shared.plans.force_push(plan);
        }
    }
}

impl Drop for TuningWorker {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
    }
}

/// A tuning plan being tuned: the strings left, the next last.
struct PlanInProgress {
    plan: TuningPlan,
    strings_left: Vec<VoiceSettings>,
}

impl PlanInProgress {
    fn new(plan: TuningPlan) -> Self {
        let mut strings_left: Vec<_> = plan.strings().collect();
        strings_left.reverse();
        Self { plan, strings_left }
    }
}

fn run(shared: &Shared) {
    let mut remembered: Vec<Calibration> = Vec::with_capacity(REMEMBERED);
    let mut in_progress: Option<PlanInProgress> = None;
    // Kept from plan to plan at one output rate (a knob turned for a while sends a plan every
    // block): a string is tuned on it whatever its last settings were.
    let mut scratch: Option<(f64, TanpuraVoice)> = None;
    while !shared.stop.load(Ordering::Relaxed) {
        // Calibrations first: they are for strings being played.
        if let Some((request, rate)) = shared.requests.pop() {
            let calibration = recall_or_measure(&mut remembered, &request, rate);
            let result = (calibration, calibration.calibrated_tension_n());
            if !push_when_room(shared, &shared.results, result) {
                return;
            }
            continue;
        }
        if let Some(plan) = shared.plans.pop() {
            in_progress = Some(PlanInProgress::new(plan));
        }
        let Some(progress) = &mut in_progress else {
            std::thread::sleep(POLL_INTERVAL);
            continue;
        };
        let Some(string) = progress.strings_left.pop() else {
            in_progress = None;
            continue;
        };
        let rate = progress.plan.sample_rate_hz();
        if scratch
            .as_ref()
            .is_none_or(|(built_for, _)| *built_for != rate)
        {
            scratch = Some((rate, progress.plan.scratch_voice()));
        }
        let Some((_, voice)) = &mut scratch else {
            continue;
        };
        let tuned = progress.plan.tune(voice, &string);
        if !push_when_room(shared, &shared.tensions, tuned) {
            return;
        }
    }
}

/// Pushes `item`, waiting while `queue` is full (the audio thread empties it every block).
/// Returns false if the plugin stopped the worker meanwhile.
fn push_when_room<T>(shared: &Shared, queue: &ArrayQueue<T>, mut item: T) -> bool {
    loop {
        match queue.push(item) {
            Ok(()) => return true,
            Err(back) => item = back,
        }
        if shared.stop.load(Ordering::Relaxed) {
            return false;
        }
        std::thread::sleep(POLL_INTERVAL);
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
        settings.voice.quality = Quality::Live;
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

    /// A change of the bridge's control is tuned by the worker: the engine's memory comes to
    /// cover the new plan, and the notes played then tune no string on the audio thread.
    #[test]
    fn a_changed_bridge_comes_back_tuned() {
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Live;
        settings.tuning.as_played = false;
        let mut engine = Engine::new(&settings, 44_100.0, 4);
        engine.prepare_tunings();
        let worker = TuningWorker::start();
        settings.voice.bridge_stiffness_n_m2 *= 10.0;
        engine.set_settings(&settings);
        let plan = engine.tuning_plan();
        assert!(!engine.tuning_memory().covers(&plan));
        let mut output = [0.0f32; 64];
        let deadline = std::time::Instant::now() + Duration::from_secs(120);
        while !engine.tuning_memory().covers(&plan) {
            assert!(
                std::time::Instant::now() < deadline,
                "the plan was not tuned"
            );
            engine.process(&[], &mut output);
            worker.exchange(&mut engine);
            std::thread::sleep(Duration::from_millis(1));
        }
        // The bridge's control settles.
        for _ in 0..40 {
            engine.process(&[], &mut output);
        }
        let made = engine.string_tunings();
        for note in [45, 52, 64, 71] {
            engine.process(&[TimedEvent::note_on(0, note, 1.0)], &mut output);
        }
        assert_eq!(engine.string_tunings(), made, "nothing tuned on a note-on");
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
