//! The tanpura's audio path allocates nothing: 10 000 output samples of the four-string
//! instrument at every quality tier (modal and FD, with plucks and a retune in between) under a
//! counting global allocator.

use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{FirstString, Tanpura, VoiceSettings};
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
fn ten_thousand_samples_of_the_four_string_tanpura_allocate_nothing() {
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
    for sample in 0..10_000 {
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
