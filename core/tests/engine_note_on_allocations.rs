//! A note-on allocates nothing, whether the engine's tuning memory knows its string's settings
//! (the string configured at the remembered tension) or not (the string tuned, and its tension
//! remembered, the oldest entry making room once the memory is full): 140 note-ons through the
//! engine under a counting global allocator, each at a tuning the memory has not seen, after
//! 80 that it has.

use javari_core::engine::tuning_memory::TUNING_MEMORY_CAPACITY;
use javari_core::engine::{Engine, EngineSettings, TimedEvent};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

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

#[test]
fn note_ons_allocate_nothing_with_or_without_a_remembered_tension() {
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
