//! The tanpura's audio path allocates nothing, under a counting global allocator:
//!
//! - 10 000 output samples of the four-string instrument at every quality tier (modal and FD,
//!   with plucks, humanised plucks and a retune in between);
//! - a note-on through the engine, whether the engine's tuning memory knows its string's
//!   settings (the string configured at the remembered tension) or not (the string tuned, and
//!   its tension remembered, the oldest entry making room once the memory is full): 140
//!   note-ons, each at a tuning the memory has not seen, after 80 that it has.
//!
//! The tests take turns (`SERIAL`): the allocator's count is one for the whole binary.

use javari_core::engine::tuning_memory::TUNING_MEMORY_CAPACITY;
use javari_core::engine::{Engine, EngineSettings, TimedEvent};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{FirstString, Tanpura, VoiceSettings};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

struct CountingAllocator;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Held by each test while it counts, so that no other test allocates meanwhile.
static SERIAL: Mutex<()> = Mutex::new(());

#[test]
fn ten_thousand_samples_of_the_four_string_tanpura_allocate_nothing() {
    let _turn = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    for quality in Quality::ALL {
        four_strings_allocate_nothing(quality);
    }
}

fn four_strings_allocate_nothing(quality: Quality) {
    let settings = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let mut tanpura = Tanpura::new(&settings, 146.8, 44_100.0);
    let mut retuned = settings;
    retuned.thread_position_m = 0.041;
    retuned.bridge_stiffness_n_m2 = 3e8;
    let mut sum = 0.0f64;

    COUNTING.store(true, Ordering::SeqCst);
    for index in 0..4 {
        tanpura.pluck(index, &Pluck::default());
    }
    // Humanised plucks: softer at the same place (the modal strings on the nodes shift their
    // last press), and a hard one (solved again on the press's problem).
    let softer = Pluck {
        amplitude_m: 0.93 * Pluck::default().amplitude_m,
        ..Pluck::default()
    };
    let hard = Pluck {
        amplitude_m: 3e-3,
        ..Pluck::default()
    };
    for sample in 0..10_000 {
        if sample == 2_500 {
            tanpura.pluck(0, &softer);
            tanpura.pluck(2, &hard);
        }
        if sample == 5_000 {
            tanpura.set_tuning(&retuned, 155.6, FirstString::Ma);
            tanpura.pluck(1, &Pluck::default());
        }
        sum += tanpura.next_sample() as f64;
    }
    COUNTING.store(false, Ordering::SeqCst);

    assert!(sum.is_finite());
    let steps = 4 * quality.oversample() as u64 * 10_000;
    assert_eq!(tanpura.newton_stats().steps, steps, "{quality:?}");
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst), 0, "{quality:?}");
}

#[test]
fn note_ons_allocate_nothing_with_or_without_a_remembered_tension() {
    let _turn = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut settings = EngineSettings::default();
    let mut engine = Engine::new(&settings, 44_100.0, 2);
    engine.prepare_tunings();
    let prepared = engine.tuning_memory().len();
    let mut block = [0.0f32; 64];
    let mut sum = 0.0f64;

    COUNTING.store(true, Ordering::SeqCst);
    // Remembered: every playable note from MIDI 16 up.
    for note in 16..96u8 {
        engine.process(&[TimedEvent::note_on(0, note, 0.8)], &mut block);
        sum += block.iter().map(|&x| f64::from(x)).sum::<f64>();
    }
    // Not remembered: A3 at 140 fine tunings, more than the memory holds beside them.
    for step in 0..140 {
        settings.tuning.fine_tune_cents = 0.5 + f64::from(step) * 0.25;
        engine.set_settings(&settings);
        engine.process(&[TimedEvent::note_on(0, 57, 0.8)], &mut block);
        sum += block.iter().map(|&x| f64::from(x)).sum::<f64>();
    }
    COUNTING.store(false, Ordering::SeqCst);

    assert!(sum.is_finite());
    assert_eq!(prepared, 80);
    assert_eq!(engine.tuning_memory().len(), TUNING_MEMORY_CAPACITY);
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst), 0);
}
