//! The audio thread's side of the editor channel never allocates, with the editor open (a
//! consumer thread draining the queue), stalled (open but never reading) or closed: the
//! engine's `process` plus the publisher's `record_output` and `end_block`, exactly as
//! `Javari::process` calls them, run under a counting global allocator that counts only the
//! audio thread's allocations.

use javari_core::engine::{Engine, EngineSettings, TimedEvent};
use javari_core::snapshot_channel::{
    Publication, SnapshotChannel, SnapshotPublisher, QUEUE_FRAMES,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

struct CountingAllocator;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn note_allocation() {
    // `try_with`: thread-locals may already be gone while a thread shuts down.
    let _ = COUNTING.try_with(|counting| {
        if counting.get() {
            let _ = ALLOCATIONS.try_with(|count| count.set(count.get() + 1));
        }
    });
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note_allocation();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        note_allocation();
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[derive(Clone, Copy, PartialEq, Debug)]
enum EditorState {
    Open,
    Stalled,
    Closed,
}

/// Runs 1 s of audio in 128-sample blocks with a pluck every 0.25 s; returns (allocations on
/// the audio thread, publications by kind, frames the consumer received).
fn run(state: EditorState) -> (u64, [usize; 4], u64) {
    const RATE: f64 = 44_100.0;
    const BLOCK: usize = 128;
    let channel = SnapshotChannel::new(QUEUE_FRAMES);
    channel.set_consumer_open(state != EditorState::Closed);
    let mut publisher = SnapshotPublisher::new(channel.clone());
    publisher.prepare(RATE);
    let mut engine = Engine::new(&EngineSettings::default(), RATE, 4);
    let mut block = vec![0.0f32; BLOCK];

    let stop = Arc::new(AtomicBool::new(false));
    let consumer = (state == EditorState::Open).then(|| {
        let channel = channel.clone();
        let stop = stop.clone();
        std::thread::spawn(move || {
            let mut receiver = javari_core::snapshot_channel::SnapshotReceiver::new(channel);
            while !stop.load(Ordering::Acquire) {
                receiver.poll();
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            receiver.poll();
            receiver.received()
        })
    });

    let mut outcomes = [0usize; 4];
    let blocks = RATE as usize / BLOCK;
    let pluck_every = (0.25 * RATE) as usize / BLOCK;
    COUNTING.with(|counting| counting.set(true));
    for index in 0..blocks {
        let started = Instant::now();
        let pluck = [TimedEvent::note_on(
            17,
            48 + (index / pluck_every % 5) as u8,
            0.9,
        )];
        let events: &[TimedEvent] = if index % pluck_every == 0 {
            &pluck
        } else {
            &[]
        };
        engine.process(events, &mut block);
        publisher.record_output(&block);
        let outcome = publisher.end_block(&engine, BLOCK, started.elapsed());
        outcomes[outcome as usize] += 1;
    }
    COUNTING.with(|counting| counting.set(false));
    let allocations = ALLOCATIONS.with(|count| count.replace(0));
    stop.store(true, Ordering::Release);
    let received = consumer.map_or(0, |thread| thread.join().unwrap());
    (allocations, outcomes, received)
}

#[test]
fn the_audio_thread_never_allocates_with_the_editor_open_stalled_or_closed() {
    for state in [EditorState::Open, EditorState::Stalled, EditorState::Closed] {
        let (allocations, outcomes, received) = run(state);
        println!(
            "{state:?}: {allocations} allocations; published {}, dropped {}, no consumer {}, received {received}",
            outcomes[Publication::Published as usize],
            outcomes[Publication::Dropped as usize],
            outcomes[Publication::NoConsumer as usize],
        );
        assert_eq!(allocations, 0, "{state:?}");
        // 1 s at 50 frames per second: 50 frames are due (49 when the last block ends short).
        let due = outcomes[1] + outcomes[2] + outcomes[3];
        assert!((49..=50).contains(&due), "{due} frames due");
        match state {
            EditorState::Open => {
                assert!(outcomes[Publication::Published as usize] >= QUEUE_FRAMES);
                assert_eq!(received, outcomes[Publication::Published as usize] as u64);
            }
            EditorState::Stalled => {
                assert_eq!(outcomes[Publication::Published as usize], QUEUE_FRAMES);
                assert_eq!(outcomes[Publication::Dropped as usize], due - QUEUE_FRAMES);
            }
            EditorState::Closed => {
                assert_eq!(outcomes[Publication::NoConsumer as usize], due);
            }
        }
    }
}

/// The allocator really counts: a deliberate allocation on the counting thread is seen.
#[test]
fn the_counting_allocator_sees_allocations() {
    COUNTING.with(|counting| counting.set(true));
    let boxed = std::hint::black_box(Box::new([0u8; 64]));
    COUNTING.with(|counting| counting.set(false));
    drop(boxed);
    let allocations = ALLOCATIONS.with(|count| count.replace(0));
    assert!(allocations >= 1);
}
