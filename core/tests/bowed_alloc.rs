//! The per-sample path of both bowed tiers never allocates (house style 3; issue 4): a counting
//! global allocator wraps the system one, and the count must not move while voices run and their
//! controls change every sample. `new()` and `prepare()` may allocate; nothing after them does.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use javari_core::bowed::{
    BowTableString, BowedCapacity, BowedString, BowedVoice, StringConstants, VIOLIN_BODY,
};

struct CountingAllocator;

thread_local! {
    // Per thread, so tests running in parallel (and the harness) do not count each other's
    // allocations. A const-initialised Cell needs no allocation itself.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count_one() {
    // try_with: during thread teardown the slot may be gone; such allocations are not ours.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_one();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { System.alloc_zeroed(layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Run `voice` for `samples`, changing every control each sample (a glide, a bow-force swell,
/// a bow-position sweep, bow lifts), and return the sum of the outputs so nothing is optimised
/// away.
fn play<V: BowedVoice>(voice: &mut V, samples: usize) -> f64 {
    let mut sum = 0.0;
    for n in 0..samples {
        let t = n as f64 / samples as f64;
        voice.set_pitch_hz(196.0 * (1.0 + t));
        voice.set_bow_force_n(if n % 5000 < 4000 { 0.1 + 0.6 * t } else { 0.0 });
        voice.set_bow_velocity_m_s(0.05 + 0.2 * t);
        voice.set_bow_position(0.05 + 0.2 * t);
        voice.set_body_enabled(n % 3000 < 2000);
        let o = voice.next_sample();
        sum += o.radiated + o.bridge_force_n + o.bow_point_velocity_m_s;
    }
    sum
}

#[test]
fn per_sample_and_block_paths_do_not_allocate() {
    let capacity = BowedCapacity::default();
    let mut rounded = BowedString::new(capacity, StringConstants::violin_a());
    let mut table = BowTableString::new(capacity, StringConstants::cello_d());
    rounded.prepare(48_000.0).unwrap();
    table.prepare(48_000.0).unwrap();

    let before = allocations();
    let mut sum = play(&mut rounded, 48_000);
    sum += play(&mut table, 48_000);
    // Control changes outside the per-sample path that must not allocate either.
    rounded.set_constants(StringConstants::cello_d());
    rounded.set_body_resonances(&VIOLIN_BODY[..2]);
    rounded.reset();
    table.reset();
    sum += play(&mut rounded, 10_000);
    // The block path, body on and off.
    let mut block = [0.0f32; 64];
    for body in [true, false, true] {
        rounded.set_body_enabled(body);
        table.set_body_enabled(body);
        for _ in 0..100 {
            rounded.process(&mut block);
            sum += f64::from(block[0]);
            table.process(&mut block);
            sum += f64::from(block[0]);
        }
    }
    let after = allocations();

    assert!(sum.is_finite());
    assert_eq!(
        after - before,
        0,
        "{} allocations on the audio path",
        after - before
    );
}

#[test]
fn the_counter_sees_allocations() {
    // Guard against a counter that never counts: constructing a voice allocates.
    let before = allocations();
    let voice = BowedString::new(BowedCapacity::default(), StringConstants::violin_a());
    let after = allocations();
    assert!(after > before);
    drop(voice);
}
