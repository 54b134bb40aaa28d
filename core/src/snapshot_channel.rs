//! From the audio thread to the editor without ever waiting: snapshots of the string travel
//! through a bounded lock-free queue (crossbeam's `ArrayQueue`).
//!
//! The audio thread ([`SnapshotPublisher`]) keeps the last output samples, measures how long
//! each block took against its deadline, and every [`FRAME_INTERVAL_S`] worth of samples fills
//! a [`TanpuraSnapshot`] from the engine and offers it with `ArrayQueue::push`. When the queue is
//! full (the editor is slow, stalled or closed) `push` fails at once and the frame is dropped
//! and counted: the producer never waits, never locks and never allocates (every buffer is built
//! in `new`). While no editor is open the snapshot is not even filled.
//!
//! The editor ([`SnapshotReceiver`]) pops whatever has arrived and keeps the newest.

use crate::engine::Engine;
use crate::snapshot::{OutputHistory, TanpuraSnapshot};
use crossbeam::queue::ArrayQueue;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Time between two published frames, s (50 frames per second).
pub const FRAME_INTERVAL_S: f64 = 0.02;
/// Frames the queue holds: enough to ride out a late editor frame, few enough that a reopened
/// editor catches up at once.
pub const QUEUE_FRAMES: usize = 4;

/// The shared end of the channel: the queue, whether an editor is reading, and counters.
#[derive(Debug)]
pub struct SnapshotChannel {
    queue: ArrayQueue<TanpuraSnapshot>,
    consumer_open: AtomicBool,
    /// A pluck the editor asks for: MIDI note + 1, or 0 for none.
    audition: AtomicU32,
    published: AtomicU64,
    dropped: AtomicU64,
}

impl SnapshotChannel {
    /// A channel holding `capacity` frames (at least 1). Allocates.
    pub fn new(capacity: usize) -> Arc<Self> {
        Arc::new(Self {
            queue: ArrayQueue::new(capacity.max(1)),
            consumer_open: AtomicBool::new(false),
            audition: AtomicU32::new(0),
            published: AtomicU64::new(0),
            dropped: AtomicU64::new(0),
        })
    }

    /// Set by the editor while its window is open; the audio thread skips the snapshot work
    /// while it is false.
    pub fn set_consumer_open(&self, open: bool) {
        self.consumer_open.store(open, Ordering::Release);
    }

    pub fn consumer_open(&self) -> bool {
        self.consumer_open.load(Ordering::Acquire)
    }

    /// Asks the audio thread to pluck the string of MIDI `note` at full velocity (the editor's
    /// audition button). A second request before the next block replaces the first.
    pub fn request_audition(&self, note: u8) {
        self.audition.store(u32::from(note) + 1, Ordering::Release);
    }

    /// The pending audition note, if any (taken: the next call returns None).
    pub fn take_audition(&self) -> Option<u8> {
        match self.audition.swap(0, Ordering::AcqRel) {
            0 => None,
            note => u8::try_from(note - 1).ok(),
        }
    }

    /// Frames accepted by the queue so far.
    pub fn published(&self) -> u64 {
        self.published.load(Ordering::Relaxed)
    }

    /// Frames dropped because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Frames waiting in the queue.
    pub fn pending(&self) -> usize {
        self.queue.len()
    }

    /// Offers one frame without waiting: true if the queue took it, false if it was full and
    /// the frame is dropped.
    pub fn offer(&self, snapshot: TanpuraSnapshot) -> bool {
        match self.queue.push(snapshot) {
            Ok(()) => {
                self.published.fetch_add(1, Ordering::Relaxed);
                true
            }
            Err(_dropped) => {
                self.dropped.fetch_add(1, Ordering::Relaxed);
                false
            }
        }
    }
}

/// What [`SnapshotPublisher::end_block`] did with this block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Publication {
    /// Not yet [`FRAME_INTERVAL_S`] since the last frame.
    NotDue,
    /// No editor is open: nothing filled, nothing offered.
    NoConsumer,
    Published,
    /// The queue was full: the frame was dropped.
    Dropped,
}

/// The audio thread's end: measurements and the snapshot buffer. Allocation-free after `new`.
#[derive(Debug)]
pub struct SnapshotPublisher {
    channel: Arc<SnapshotChannel>,
    /// Boxed: a snapshot is about 14 kB, too much to move around inside the plugin struct.
    scratch: Box<TanpuraSnapshot>,
    history: Box<OutputHistory>,
    sample_rate_hz: f64,
    frame_interval_samples: u64,
    samples_since_frame: u64,
    sequence: u64,
    /// Largest process-time / block-duration ratio since the last frame.
    max_load_since_frame: f32,
    last_load: f32,
    /// All strings' Newton totals at the last frame, for the per-frame figures.
    last_cap_hits: u64,
    last_steps: u64,
    last_iterations: u64,
}

impl SnapshotPublisher {
    /// The publisher for `channel`. Allocates its buffers.
    pub fn new(channel: Arc<SnapshotChannel>) -> Self {
        let mut publisher = Self {
            channel,
            scratch: Box::default(),
            history: Box::default(),
            sample_rate_hz: 0.0,
            frame_interval_samples: 1,
            samples_since_frame: 0,
            sequence: 0,
            max_load_since_frame: 0.0,
            last_load: 0.0,
            last_cap_hits: 0,
            last_steps: 0,
            last_iterations: 0,
        };
        publisher.prepare(44_100.0);
        publisher
    }

    /// Sets the frame interval for a sample rate and clears the history. Allocation-free.
    pub fn prepare(&mut self, sample_rate_hz: f64) {
        self.sample_rate_hz = sample_rate_hz;
        self.frame_interval_samples = (FRAME_INTERVAL_S * sample_rate_hz).round().max(1.0) as u64;
        self.samples_since_frame = 0;
        self.max_load_since_frame = 0.0;
        self.history.clear();
    }

    pub fn channel(&self) -> &Arc<SnapshotChannel> {
        &self.channel
    }

    /// The real-time load of the last block: process time over the block's duration.
    pub fn last_load(&self) -> f32 {
        self.last_load
    }

    /// Keeps output samples for the editor's force strip (call for every rendered chunk).
    pub fn record_output(&mut self, samples: &[f32]) {
        self.history.push_block(samples);
    }

    /// Called once at the end of every block of `block_samples` samples that took
    /// `process_time`: records the load and, when a frame is due and an editor is open, fills
    /// a snapshot from `engine` and offers it. Never waits, never allocates.
    pub fn end_block(
        &mut self,
        engine: &Engine,
        block_samples: usize,
        process_time: Duration,
    ) -> Publication {
        let block_duration_s = block_samples as f64 / self.sample_rate_hz;
        self.last_load = if block_duration_s > 0.0 {
            (process_time.as_secs_f64() / block_duration_s) as f32
        } else {
            0.0
        };
        self.max_load_since_frame = self.max_load_since_frame.max(self.last_load);
        self.samples_since_frame += block_samples as u64;
        if self.samples_since_frame < self.frame_interval_samples {
            return Publication::NotDue;
        }
        // The remainder carries over, so frames keep a 20 ms rhythm whatever the block size.
        self.samples_since_frame %= self.frame_interval_samples;
        if !self.channel.consumer_open() {
            self.max_load_since_frame = 0.0;
            return Publication::NoConsumer;
        }

        let snapshot = &mut *self.scratch;
        engine.fill_snapshot(snapshot);
        snapshot.fill_force_history(&self.history);
        // Newton totals restart when a string is reset; a smaller total starts a new count.
        let newton = snapshot.newton;
        let since = |now: u64, before: u64| {
            if now >= before {
                now - before
            } else {
                now
            }
        };
        let steps = since(newton.steps, self.last_steps);
        let iterations = since(newton.iterations, self.last_iterations);
        snapshot.cap_hits_since_last_frame = since(newton.cap_hits, self.last_cap_hits);
        snapshot.mean_iterations_since_last_frame = if steps > 0 {
            (iterations as f64 / steps as f64) as f32
        } else {
            0.0
        };
        self.last_steps = newton.steps;
        self.last_iterations = newton.iterations;
        self.last_cap_hits = newton.cap_hits;
        snapshot.realtime_load = self.max_load_since_frame;
        self.max_load_since_frame = 0.0;
        self.sequence += 1;
        snapshot.sequence = self.sequence;

        if self.channel.offer(*snapshot) {
            Publication::Published
        } else {
            Publication::Dropped
        }
    }
}

/// The editor's end: drains the queue and keeps the newest frame.
#[derive(Debug)]
pub struct SnapshotReceiver {
    channel: Arc<SnapshotChannel>,
    latest: Box<TanpuraSnapshot>,
    received: u64,
}

impl SnapshotReceiver {
    pub fn new(channel: Arc<SnapshotChannel>) -> Self {
        Self {
            channel,
            latest: Box::default(),
            received: 0,
        }
    }

    /// Pops every waiting frame; returns true if a new one arrived.
    pub fn poll(&mut self) -> bool {
        self.poll_each(|_| ())
    }

    /// Pops every waiting frame, oldest first, showing each to `visit`; the newest is kept.
    /// Returns true if a new one arrived.
    pub fn poll_each(&mut self, mut visit: impl FnMut(&TanpuraSnapshot)) -> bool {
        let mut fresh = false;
        while let Some(snapshot) = self.channel.queue.pop() {
            *self.latest = snapshot;
            visit(&self.latest);
            self.received += 1;
            fresh = true;
        }
        fresh
    }

    /// The newest frame received (all zeros before the first).
    pub fn latest(&self) -> &TanpuraSnapshot {
        &self.latest
    }

    pub fn received(&self) -> u64 {
        self.received
    }

    pub fn channel(&self) -> &Arc<SnapshotChannel> {
        &self.channel
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{EngineSettings, TimedEvent};

    fn engine() -> Engine {
        Engine::new(&EngineSettings::default(), 44_100.0, 4)
    }

    fn pluck(note: u8) -> [TimedEvent; 1] {
        [TimedEvent::note_on(0, note, 1.0)]
    }

    #[test]
    fn a_stalled_consumer_never_blocks_the_producer_frames_are_dropped() {
        let channel = SnapshotChannel::new(QUEUE_FRAMES);
        channel.set_consumer_open(true);
        let mut publisher = SnapshotPublisher::new(channel.clone());
        let engine = engine();
        // A block of exactly one frame interval: every call is due and offers a frame.
        let block = publisher.frame_interval_samples as usize;
        let attempts = 100_000;
        let mut outcomes = [0usize; 4];
        let mut slowest = Duration::ZERO;
        let all = std::time::Instant::now();
        for _ in 0..attempts {
            let start = std::time::Instant::now();
            let outcome = publisher.end_block(&engine, block, Duration::ZERO);
            slowest = slowest.max(start.elapsed());
            outcomes[outcome as usize] += 1;
        }
        // Printed, not asserted (house rule: no wall-time assertions); the slowest call is
        // bounded by the OS scheduler on a shared machine, the mean is the real cost.
        println!(
            "{attempts} offers to a stalled consumer: {} published, {} dropped, mean {:?} per \
             offer (snapshot fill included), slowest {:?}",
            outcomes[Publication::Published as usize],
            outcomes[Publication::Dropped as usize],
            all.elapsed() / attempts as u32,
            slowest
        );
        assert_eq!(outcomes[Publication::Published as usize], QUEUE_FRAMES);
        assert_eq!(
            outcomes[Publication::Dropped as usize],
            attempts - QUEUE_FRAMES
        );
        assert_eq!(channel.dropped(), (attempts - QUEUE_FRAMES) as u64);
        assert_eq!(channel.published(), QUEUE_FRAMES as u64);
        assert_eq!(channel.pending(), QUEUE_FRAMES);

        // The consumer wakes up: it gets the queued frames, the oldest kept ones, in order.
        let mut receiver = SnapshotReceiver::new(channel.clone());
        assert!(receiver.poll());
        assert_eq!(receiver.received(), QUEUE_FRAMES as u64);
        assert_eq!(receiver.latest().sequence, QUEUE_FRAMES as u64);
        // And the next frame goes through again.
        assert_eq!(
            publisher.end_block(&engine, block, Duration::ZERO),
            Publication::Published
        );
        assert!(receiver.poll());
        assert_eq!(receiver.latest().sequence, attempts as u64 + 1);
    }

    /// The audio is the same whether the editor reads, stalls or is closed: the channel only
    /// observes the engine.
    #[test]
    fn the_channel_does_not_change_the_sound() {
        let render = |mode: u8| {
            let channel = SnapshotChannel::new(QUEUE_FRAMES);
            channel.set_consumer_open(mode != 0);
            let mut publisher = SnapshotPublisher::new(channel.clone());
            let mut receiver = SnapshotReceiver::new(channel);
            let mut engine = engine();
            let mut output = Vec::new();
            let mut block = vec![0.0f32; 256];
            for index in 0..40 {
                let events = if index % 10 == 0 { &pluck(50)[..] } else { &[] };
                engine.process(events, &mut block);
                publisher.record_output(&block);
                publisher.end_block(&engine, block.len(), Duration::from_micros(100));
                if mode == 1 {
                    receiver.poll();
                }
                output.extend_from_slice(&block);
            }
            (output, receiver.received())
        };
        let (closed, closed_frames) = render(0);
        let (reading, reading_frames) = render(1);
        let (stalled, stalled_frames) = render(2);
        assert_eq!(closed, reading);
        assert_eq!(closed, stalled);
        assert_eq!(closed_frames, 0);
        assert_eq!(stalled_frames, 0);
        // 40 blocks of 256 samples = 232 ms: 11 frames at 20 ms (882 samples each).
        assert_eq!(reading_frames, 40 * 256 / 882);
    }

    #[test]
    fn frames_carry_load_newton_figures_and_the_force_strip() {
        let channel = SnapshotChannel::new(QUEUE_FRAMES);
        channel.set_consumer_open(true);
        let mut publisher = SnapshotPublisher::new(channel.clone());
        let mut receiver = SnapshotReceiver::new(channel);
        let mut engine = engine();
        let mut block = vec![0.0f32; 441];
        engine.process(&pluck(50), &mut block);
        publisher.record_output(&block);
        // 441 samples at 44.1 kHz last 10 ms; 2.5 ms of work is a load of 0.25.
        assert_eq!(
            publisher.end_block(&engine, 441, Duration::from_micros(2500)),
            Publication::NotDue
        );
        assert!((publisher.last_load() - 0.25).abs() < 1e-6);
        engine.process(&[], &mut block);
        publisher.record_output(&block);
        assert_eq!(
            publisher.end_block(&engine, 441, Duration::from_micros(5000)),
            Publication::Published
        );
        assert!(receiver.poll());
        let frame = receiver.latest();
        assert_eq!(frame.sequence, 1);
        assert!((frame.realtime_load - 0.5).abs() < 1e-6, "the larger load");
        assert_eq!(frame.force_len, 882);
        assert_eq!(frame.active_voices, 1);
        assert!(frame.newton.steps > 0);
        let expected_mean = frame.newton.iterations as f64 / frame.newton.steps as f64;
        assert!((f64::from(frame.mean_iterations_since_last_frame) - expected_mean).abs() < 1e-6);
        assert_eq!(frame.cap_hits_since_last_frame, frame.newton.cap_hits);
        let scale = frame.output_to_force_n as f32;
        assert_eq!(frame.force_history_n()[882 - 1], block[440] * scale);
    }
}
