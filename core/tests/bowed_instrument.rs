//! The bowed instrument as a player meets it: a held note sounds at its pitch, a phrase with
//! every gesture allocates nothing, and a released note falls silent.

use javari_core::analysis::{cents, peak_frequency_hz};
use javari_core::bowed::{
    BowTier, BowedEvent, BowedInstrument, BowedPlayerSettings, StringConstants,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Counts allocations made by the thread that switched counting on (tests run in parallel).
struct CountingAllocator;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

const RATE: f64 = 44_100.0;

fn player(tier: BowTier) -> BowedInstrument {
    let settings = BowedPlayerSettings {
        tier,
        ..BowedPlayerSettings::default()
    };
    BowedInstrument::new(StringConstants::violin_a(), settings, RATE).unwrap()
}

#[test]
fn a_held_note_sounds_at_its_pitch_on_both_tiers() {
    for tier in [BowTier::RoundedCorner, BowTier::BowTable] {
        for note in [55u8, 62, 69, 76] {
            let mut instrument = player(tier);
            instrument.handle(BowedEvent::NoteOn {
                note,
                velocity: 0.6,
            });
            let output: Vec<f64> = (0..(RATE as usize))
                .map(|_| instrument.next_sample())
                .collect();
            let expected = 440.0 * 2f64.powf((note as f64 - 69.0) / 12.0);
            let found = peak_frequency_hz(
                &output[(0.3 * RATE) as usize..],
                RATE,
                expected * 0.97,
                expected * 1.03,
            );
            let error = cents(found, expected);
            assert!(error.abs() < 5.0, "{tier:?} note {note}: {error} cents");
            assert!(output.iter().all(|x| x.is_finite()));
        }
    }
}

#[test]
fn a_phrase_with_every_gesture_allocates_nothing_and_ends_in_silence() {
    let mut instrument = player(BowTier::RoundedCorner);
    let gestures = [
        BowedEvent::NoteOn {
            note: 64,
            velocity: 0.7,
        },
        BowedEvent::Pressure(0.8),
        BowedEvent::Modulation(0.5),
        BowedEvent::NoteOn {
            note: 67,
            velocity: 0.4,
        },
        BowedEvent::Timbre(0.9),
        BowedEvent::Expression(0.3),
        BowedEvent::PitchBend(-0.5),
        BowedEvent::NoteOff { note: 67 },
        BowedEvent::NoteOff { note: 64 },
    ];
    COUNTING.with(|counting| counting.set(true));
    let mut loudest_while_bowing = 0.0f64;
    for gesture in gestures {
        instrument.handle(gesture);
        for _ in 0..4410 {
            let sample = instrument.next_sample();
            assert!(sample.is_finite());
            if instrument.is_bowing() {
                loudest_while_bowing = loudest_while_bowing.max(sample.abs());
            }
        }
    }
    let mut tail = 0.0f64;
    for k in 0..(2.0 * RATE) as usize {
        let sample = instrument.next_sample().abs();
        if k >= (1.9 * RATE) as usize {
            tail = tail.max(sample);
        }
    }
    COUNTING.with(|counting| counting.set(false));
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst), 0);
    assert!(loudest_while_bowing > 0.0);
    // Two seconds after the bow lifts, the string has rung down by more than 40 dB.
    assert!(
        tail < 0.01 * loudest_while_bowing,
        "{tail} vs {loudest_while_bowing}"
    );
}
