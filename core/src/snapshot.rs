//! A picture of one tanpura string at one moment, for the editor's live view.
//!
//! The audio thread fills a [`TanpuraSnapshot`] and hands it to the editor through a lock-free
//! queue (`plugin/src/editor/channel.rs`), so the snapshot is a plain fixed-size `Copy` value:
//! filling it never allocates, and moving it through a bounded queue is a memcpy.
//!
//! What it holds, all taken from [`FdString`]'s accessors at the moment of the fill (a unit
//! test checks each field against them):
//! - the displacement `y` and the rest shape over the string grid, with the node positions (the
//!   view of the seed's Figure 3);
//! - the bridge and thread barriers near the bridge: point positions and heights of
//!   [`FdString::bridge_grid`] and [`FdString::thread_grid`], and per point whether the
//!   string penetrates it, `a_i = y_barrier(x_i) − (I y)_i > 0` (seed 000, eq. 17–19: the points
//!   where the Hunt–Crossley force acts);
//! - the deepest penetration, the nut and bridge forces (eq. 12–13) and the Newton statistics;
//! - the last [`FORCE_HISTORY_SAMPLES`] output samples converted back to newtons of pickup force
//!   (with the pickup at 100 % nut this is the nut force of eq. 13 minus its rest value, decimated
//!   to the output rate), for the editor's strip and spectrum;
//! - what the audio thread measured about itself (real-time load, Newton cap hits per frame).
//!
//! Grids larger than the snapshot's arrays are shown every `stride`-th point, so the picture
//! stays correct (a subset of the true points) for any grid the quality tiers may use.

use crate::bowed::instrument::BOW_HISTORY_SAMPLES;
use crate::bowed::BowedInstrument;
use crate::newton::NewtonStats;
use crate::tanpura::fd::FdString;
use crate::tanpura::modal::ModalString;
use crate::tanpura::tier_string::TierString;

/// String nodes a snapshot holds (the seed's grid has 201).
pub const MAX_STRING_NODES: usize = 256;
/// Bridge points a snapshot holds (the seed's 0.18 mm grid over 25–60 mm has 195).
pub const MAX_BRIDGE_POINTS: usize = 256;
/// Thread points a snapshot holds (the seed's 0.15 mm grid over the 5.4 mm cap has 36).
pub const MAX_THREAD_POINTS: usize = 64;
/// Output samples of pickup force a snapshot carries: 46 ms at 44.1 kHz, enough for a spectrum
/// with 21.5 Hz bins.
pub const FORCE_HISTORY_SAMPLES: usize = 2048;

/// One barrier (bridge or thread) as seen at the moment of the snapshot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarrierView<const CAPACITY: usize> {
    /// Points held (≤ CAPACITY).
    pub len: usize,
    /// Barrier grid points between two held points (1 when the whole grid fits).
    pub stride: usize,
    /// Position of each point, m from the tuning bead.
    pub positions_m: [f32; CAPACITY],
    /// Height of the barrier surface at each point, m (the bridge crest is at 0).
    pub heights_m: [f32; CAPACITY],
    /// The interpolated string displacement `(I y)_i` at each point, m.
    pub string_m: [f32; CAPACITY],
    /// Whether the string penetrates the barrier there (`a_i > 0`).
    pub in_contact: [bool; CAPACITY],
}

impl<const CAPACITY: usize> BarrierView<CAPACITY> {
    pub const EMPTY: Self = Self {
        len: 0,
        stride: 1,
        positions_m: [0.0; CAPACITY],
        heights_m: [0.0; CAPACITY],
        string_m: [0.0; CAPACITY],
        in_contact: [false; CAPACITY],
    };

    /// Points in contact.
    pub fn contact_count(&self) -> usize {
        self.in_contact[..self.len].iter().filter(|&&c| c).count()
    }

    fn fill(
        &mut self,
        barrier: &crate::tanpura::fd::barrier_grid::BarrierGrid,
        displacement_m: &[f64],
    ) {
        let (len, stride) = fit(barrier.len(), CAPACITY);
        self.len = len;
        self.stride = stride;
        for held in 0..len {
            let i = held * stride;
            let height = barrier.heights_m()[i];
            let string = barrier.interpolate(displacement_m, i);
            self.positions_m[held] = barrier.positions_m()[i] as f32;
            self.heights_m[held] = height as f32;
            self.string_m[held] = string as f32;
            // Only an active barrier (k > 0) exerts force; an inactive one is drawn, not touched.
            self.in_contact[held] = barrier.is_active() && height - string > 0.0;
        }
    }
}

/// Intervals of the evenly spaced points at which a modal string is drawn.
pub const MODAL_VIEW_INTERVALS: usize = 200;
const _: () = assert!(MODAL_VIEW_INTERVALS < MAX_STRING_NODES);

/// A modal string's contact points `range` as a barrier view, with the string's displacement
/// there from its modes.
fn fill_points<const CAPACITY: usize>(
    view: &mut BarrierView<CAPACITY>,
    string: &ModalString<f32>,
    range: std::ops::Range<usize>,
) {
    let points = string.points();
    let (len, stride) = fit(range.len(), CAPACITY);
    view.len = len;
    view.stride = stride;
    for held in 0..len {
        let i = range.start + held * stride;
        let (position, height) = (points.positions_m[i], points.heights_m[i]);
        let displacement = string.displacement_at_m(position);
        view.positions_m[held] = position as f32;
        view.heights_m[held] = height as f32;
        view.string_m[held] = displacement as f32;
        view.in_contact[held] = height - displacement > 0.0;
    }
}

/// How many of `available` points fit in `capacity`: (held, stride).
fn fit(available: usize, capacity: usize) -> (usize, usize) {
    let stride = available.div_ceil(capacity).max(1);
    (available.div_ceil(stride), stride)
}

/// Everything the editor draws, at one moment. Fixed size, `Copy`, allocation-free to fill.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TanpuraSnapshot {
    /// Frames published so far by the audio thread (set by the publisher).
    pub sequence: u64,
    /// Strings ringing when the snapshot was taken.
    pub active_voices: usize,
    /// Pitch of the string shown, Hz.
    pub fundamental_hz: f64,
    /// Output sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Internal steps per output sample (the tier's oversampling).
    pub oversample: u32,
    /// True for a modal string (then `grid_intervals` counts its modes).
    pub modal: bool,
    /// N, the string grid's intervals (FD), or the number of modes (modal).
    pub grid_intervals: usize,
    /// The Newton iteration cap and tolerance (m) of the string shown.
    pub newton_cap: u32,
    pub newton_tolerance_m: f64,
    /// String length L, m.
    pub length_m: f64,
    /// String nodes held (≤ [`MAX_STRING_NODES`]) and grid nodes between two held ones.
    pub node_count: usize,
    pub node_stride: usize,
    /// x of each held node, m from the tuning bead.
    pub node_positions_m: [f32; MAX_STRING_NODES],
    /// y at each held node, m.
    pub displacement_m: [f32; MAX_STRING_NODES],
    /// The static rest shape on bridge and thread at each held node, m.
    pub rest_displacement_m: [f32; MAX_STRING_NODES],
    pub bridge: BarrierView<MAX_BRIDGE_POINTS>,
    pub thread: BarrierView<MAX_THREAD_POINTS>,
    /// Deepest penetration into bridge or thread after the last step, m.
    pub max_penetration_m: f64,
    /// Nut force (eq. 13) and bridge force (eq. 12) after the last step and at rest, N.
    pub nut_force_n: f64,
    pub rest_nut_force_n: f64,
    pub bridge_force_n: f64,
    pub rest_bridge_force_n: f64,
    /// Newton statistics of the string shown, since its last reset.
    pub shown_newton: NewtonStats,
    /// Newton statistics of all strings together, since each string's last reset.
    pub newton: NewtonStats,
    /// Newtons of pickup force per unit of digital output at the moment of the snapshot.
    pub output_to_force_n: f64,
    /// The last `force_len` output samples as pickup force, N, oldest first.
    pub force_n: [f32; FORCE_HISTORY_SAMPLES],
    pub force_len: usize,
    /// Audio thread's own measurements since the previous frame: the largest ratio of process
    /// time to block duration, the Newton cap hits, and the mean Newton updates per step.
    pub realtime_load: f32,
    pub cap_hits_since_last_frame: u64,
    pub mean_iterations_since_last_frame: f32,
    /// The bowed string, when the bowed instrument plays.
    pub bowed: BowedView,
}

/// What the editor shows of the bowed string: the bow on the string, the stick/slip state and
/// the bow-point velocity waveform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BowedView {
    /// True when the bowed instrument plays (the other fields are meaningful).
    pub active: bool,
    /// Bow position β, pitch (Hz), bow force (N) and bow speed (m/s) of the last sample.
    pub bow_position: f64,
    pub pitch_hz: f64,
    pub bow_force_n: f64,
    pub bow_velocity_m_s: f64,
    /// The last samples' bow-point velocity, m/s, and whether the string stuck to the bow,
    /// oldest first.
    pub velocity_m_s: [f32; BOW_HISTORY_SAMPLES],
    pub sticking: [bool; BOW_HISTORY_SAMPLES],
}

impl BowedView {
    pub const EMPTY: Self = Self {
        active: false,
        bow_position: 0.0,
        pitch_hz: 0.0,
        bow_force_n: 0.0,
        bow_velocity_m_s: 0.0,
        velocity_m_s: [0.0; BOW_HISTORY_SAMPLES],
        sticking: [false; BOW_HISTORY_SAMPLES],
    };

    /// Copies the instrument's controls and bow history. Allocation-free.
    pub fn fill(&mut self, instrument: &BowedInstrument) {
        let controls = instrument.controls();
        self.active = true;
        self.bow_position = controls.bow_position;
        self.pitch_hz = controls.pitch_hz;
        self.bow_force_n = controls.bow_force_n;
        self.bow_velocity_m_s = controls.bow_velocity_m_s;
        instrument.bow_history(&mut self.velocity_m_s, &mut self.sticking);
    }

    /// Whether the string stuck to the bow at the last sample.
    pub fn sticking_now(&self) -> bool {
        self.sticking[BOW_HISTORY_SAMPLES - 1]
    }
}

impl Default for TanpuraSnapshot {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl TanpuraSnapshot {
    pub const EMPTY: Self = Self {
        sequence: 0,
        active_voices: 0,
        fundamental_hz: 0.0,
        sample_rate_hz: 0.0,
        oversample: 0,
        modal: false,
        grid_intervals: 0,
        newton_cap: 0,
        newton_tolerance_m: 0.0,
        length_m: 0.0,
        node_count: 0,
        node_stride: 1,
        node_positions_m: [0.0; MAX_STRING_NODES],
        displacement_m: [0.0; MAX_STRING_NODES],
        rest_displacement_m: [0.0; MAX_STRING_NODES],
        bridge: BarrierView::EMPTY,
        thread: BarrierView::EMPTY,
        max_penetration_m: 0.0,
        nut_force_n: 0.0,
        rest_nut_force_n: 0.0,
        bridge_force_n: 0.0,
        rest_bridge_force_n: 0.0,
        shown_newton: NewtonStats::ZERO,
        newton: NewtonStats::ZERO,
        output_to_force_n: 0.0,
        force_n: [0.0; FORCE_HISTORY_SAMPLES],
        force_len: 0,
        realtime_load: 0.0,
        cap_hits_since_last_frame: 0,
        mean_iterations_since_last_frame: 0.0,
        bowed: BowedView::EMPTY,
    };

    /// Copies the state of a tier's string (shape, barriers, contact, forces, its Newton
    /// statistics). Allocation-free.
    pub fn fill_string(&mut self, string: &TierString) {
        match string {
            TierString::FiniteDifference(string) => self.fill_fd_string(string),
            TierString::Modal(string) => self.fill_modal_string(string),
        }
    }

    /// Copies the state of a modal string: the displacement from its modes at
    /// [`MODAL_VIEW_INTERVALS`] + 1 evenly spaced points, and its bridge and thread points as
    /// the barriers. `grid_intervals` is the number of modes. Allocation-free.
    pub fn fill_modal_string(&mut self, string: &ModalString<f32>) {
        let config = string.config();
        let length = config.string.length_m;
        self.modal = true;
        self.grid_intervals = string.modes().count();
        self.length_m = length;
        self.newton_cap = config.newton.max_iterations;
        self.newton_tolerance_m = config.newton.tolerance_m;
        self.node_count = MODAL_VIEW_INTERVALS + 1;
        self.node_stride = 1;
        for node in 0..=MODAL_VIEW_INTERVALS {
            let x = length * node as f64 / MODAL_VIEW_INTERVALS as f64;
            self.node_positions_m[node] = x as f32;
            self.displacement_m[node] = string.displacement_at_m(x) as f32;
            self.rest_displacement_m[node] = string.rest_displacement_at_m(x) as f32;
        }
        let points = string.points();
        let bridge_points = points.bridge_count();
        fill_points(&mut self.bridge, string, 0..bridge_points);
        fill_points(&mut self.thread, string, bridge_points..points.len());
        self.max_penetration_m = string.max_penetration_m();
        self.nut_force_n = string.nut_force_n();
        self.rest_nut_force_n = string.rest_nut_force_n();
        self.bridge_force_n = string.bridge_force_n();
        self.rest_bridge_force_n = string.rest_bridge_force_n();
        self.shown_newton = *string.newton_stats();
    }

    /// Copies the state of an FD string (shape, barriers, contact, forces, its Newton
    /// statistics). Allocation-free.
    pub fn fill_fd_string(&mut self, string: &FdString) {
        let config = string.config();
        let displacement = string.displacement_m();
        let rest = string.rest_displacement_m();
        let spacing_m = string.operator().spacing_m();
        let (count, stride) = fit(displacement.len(), MAX_STRING_NODES);
        self.modal = false;
        self.grid_intervals = config.intervals;
        self.length_m = config.string.length_m;
        self.newton_cap = config.newton.max_iterations;
        self.newton_tolerance_m = config.newton.tolerance_m;
        self.node_count = count;
        self.node_stride = stride;
        for held in 0..count {
            let m = held * stride;
            self.node_positions_m[held] = (m as f64 * spacing_m) as f32;
            self.displacement_m[held] = displacement[m] as f32;
            self.rest_displacement_m[held] = rest[m] as f32;
        }
        self.bridge.fill(string.bridge_grid(), displacement);
        self.thread.fill(string.thread_grid(), displacement);
        self.max_penetration_m = string.max_penetration_m();
        self.nut_force_n = string.nut_force_n();
        self.rest_nut_force_n = string.rest_nut_force_n();
        self.bridge_force_n = string.bridge_force_n();
        self.rest_bridge_force_n = string.rest_bridge_force_n();
        self.shown_newton = *string.newton_stats();
    }

    /// Copies the output history (oldest first) as pickup force, using
    /// [`TanpuraSnapshot::output_to_force_n`] as set by the engine. Allocation-free.
    pub fn fill_force_history(&mut self, history: &OutputHistory) {
        let scale = self.output_to_force_n as f32;
        let (older, newer) = history.chronological();
        self.force_len = older.len() + newer.len();
        for (target, sample) in self.force_n.iter_mut().zip(older.iter().chain(newer)) {
            *target = sample * scale;
        }
    }

    /// The force history, oldest first, N.
    pub fn force_history_n(&self) -> &[f32] {
        &self.force_n[..self.force_len]
    }
}

/// The last [`FORCE_HISTORY_SAMPLES`] output samples, kept by the audio thread: a fixed ring
/// that never allocates.
#[derive(Debug, Clone)]
pub struct OutputHistory {
    samples: [f32; FORCE_HISTORY_SAMPLES],
    /// Where the next sample goes.
    next: usize,
    filled: bool,
}

impl Default for OutputHistory {
    fn default() -> Self {
        Self {
            samples: [0.0; FORCE_HISTORY_SAMPLES],
            next: 0,
            filled: false,
        }
    }
}

impl OutputHistory {
    /// Appends a block of output samples (only the last [`FORCE_HISTORY_SAMPLES`] are kept).
    pub fn push_block(&mut self, block: &[f32]) {
        let block = &block[block.len().saturating_sub(FORCE_HISTORY_SAMPLES)..];
        for &sample in block {
            self.samples[self.next] = sample;
            self.next += 1;
            if self.next == FORCE_HISTORY_SAMPLES {
                self.next = 0;
                self.filled = true;
            }
        }
    }

    /// The held samples as (older, newer) slices; their concatenation is in time order.
    pub fn chronological(&self) -> (&[f32], &[f32]) {
        if self.filled {
            (&self.samples[self.next..], &self.samples[..self.next])
        } else {
            (&self.samples[..self.next], &[])
        }
    }

    pub fn clear(&mut self) {
        self.next = 0;
        self.filled = false;
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::engine::{pitch, Engine, EngineSettings, TimedEvent};
    use crate::tanpura::excitation::Pluck;
    use crate::tanpura::fd::FdStringConfig;
    use crate::tanpura::TanpuraVoice;

    /// Every field of `snapshot` that `fill_string` wrote equals the string's own accessors.
    pub(crate) fn assert_snapshot_is_string(snapshot: &TanpuraSnapshot, string: &TierString) {
        match string {
            TierString::FiniteDifference(string) => assert_snapshot_is_fd_string(snapshot, string),
            TierString::Modal(string) => assert_snapshot_is_modal_string(snapshot, string),
        }
    }

    pub(crate) fn assert_snapshot_is_modal_string(
        snapshot: &TanpuraSnapshot,
        string: &ModalString<f32>,
    ) {
        let config = string.config();
        assert!(snapshot.modal);
        assert_eq!(snapshot.grid_intervals, string.modes().count());
        assert_eq!(snapshot.node_count, MODAL_VIEW_INTERVALS + 1);
        assert_eq!(snapshot.newton_cap, config.newton.max_iterations);
        for node in 0..snapshot.node_count {
            let x = config.string.length_m * node as f64 / MODAL_VIEW_INTERVALS as f64;
            assert_eq!(snapshot.node_positions_m[node], x as f32);
            assert_eq!(
                snapshot.displacement_m[node],
                string.displacement_at_m(x) as f32
            );
            assert_eq!(
                snapshot.rest_displacement_m[node],
                string.rest_displacement_at_m(x) as f32
            );
        }
        let points = string.points();
        let bridge = points.bridge_count();
        assert_eq!(snapshot.bridge.len, bridge);
        assert_eq!(snapshot.thread.len, points.len() - bridge);
        for i in 0..points.len() {
            let (view, held) = if i < bridge {
                (&snapshot.bridge as &dyn PointView, i)
            } else {
                (&snapshot.thread as &dyn PointView, i - bridge)
            };
            let (position, height, string_m, contact) = view.point(held);
            assert_eq!(position, points.positions_m[i] as f32);
            assert_eq!(height, points.heights_m[i] as f32);
            let y = string.displacement_at_m(points.positions_m[i]);
            assert_eq!(string_m, y as f32);
            assert_eq!(contact, points.heights_m[i] - y > 0.0);
        }
        assert_eq!(snapshot.nut_force_n, string.nut_force_n());
        assert_eq!(snapshot.bridge_force_n, string.bridge_force_n());
        assert_eq!(snapshot.shown_newton, *string.newton_stats());
    }

    /// One point of a barrier view, whatever its capacity.
    trait PointView {
        fn point(&self, i: usize) -> (f32, f32, f32, bool);
    }

    impl<const CAPACITY: usize> PointView for BarrierView<CAPACITY> {
        fn point(&self, i: usize) -> (f32, f32, f32, bool) {
            (
                self.positions_m[i],
                self.heights_m[i],
                self.string_m[i],
                self.in_contact[i],
            )
        }
    }

    #[test]
    fn snapshot_of_a_ringing_modal_string_equals_its_state() {
        use crate::tanpura::modal::ModalStringConfig;
        let mut string = ModalString::<f32>::new(ModalStringConfig::REFERENCE);
        string.pluck(&Pluck::default());
        let mut snapshot = TanpuraSnapshot::default();
        let mut contacts_seen = 0;
        for _ in 0..12 {
            for _ in 0..40 {
                string.step();
            }
            snapshot.fill_modal_string(&string);
            assert_snapshot_is_modal_string(&snapshot, &string);
            contacts_seen += snapshot.bridge.contact_count() + snapshot.thread.contact_count();
        }
        assert!(contacts_seen > 0, "the string touches bridge or thread");
        string.settle_to_rest();
        snapshot.fill_modal_string(&string);
        assert!(snapshot.thread.contact_count() > 0, "resting on the thread");
        // The drawn rest shape passes through the resting points' contact.
        let top = snapshot.thread.len / 2;
        assert!((snapshot.thread.heights_m[top] - snapshot.thread.string_m[top]).abs() < 20e-6);
    }

    pub(crate) fn assert_snapshot_is_fd_string(snapshot: &TanpuraSnapshot, string: &FdString) {
        let config = string.config();
        let y = string.displacement_m();
        let rest = string.rest_displacement_m();
        let dx = string.operator().spacing_m();
        assert_eq!(snapshot.node_count, y.len(), "whole grid held");
        assert_eq!(snapshot.node_stride, 1);
        assert_eq!(snapshot.grid_intervals, config.intervals);
        assert_eq!(snapshot.length_m, config.string.length_m);
        assert_eq!(snapshot.newton_cap, config.newton.max_iterations);
        assert_eq!(snapshot.newton_tolerance_m, config.newton.tolerance_m);
        for m in 0..y.len() {
            assert_eq!(snapshot.node_positions_m[m], (m as f64 * dx) as f32);
            assert_eq!(snapshot.displacement_m[m], y[m] as f32, "y at node {m}");
            assert_eq!(snapshot.rest_displacement_m[m], rest[m] as f32);
        }
        for (view_len, view_stride, positions, heights, strings, contact, grid) in [
            (
                snapshot.bridge.len,
                snapshot.bridge.stride,
                &snapshot.bridge.positions_m[..],
                &snapshot.bridge.heights_m[..],
                &snapshot.bridge.string_m[..],
                &snapshot.bridge.in_contact[..],
                string.bridge_grid(),
            ),
            (
                snapshot.thread.len,
                snapshot.thread.stride,
                &snapshot.thread.positions_m[..],
                &snapshot.thread.heights_m[..],
                &snapshot.thread.string_m[..],
                &snapshot.thread.in_contact[..],
                string.thread_grid(),
            ),
        ] {
            assert_eq!(view_stride, 1);
            assert_eq!(view_len, grid.len());
            for i in 0..grid.len() {
                let interpolated = grid.interpolate(y, i);
                assert_eq!(positions[i], grid.positions_m()[i] as f32);
                assert_eq!(heights[i], grid.heights_m()[i] as f32);
                assert_eq!(strings[i], interpolated as f32);
                assert_eq!(contact[i], grid.heights_m()[i] - interpolated > 0.0);
            }
        }
        assert_eq!(snapshot.max_penetration_m, string.max_penetration_m());
        assert_eq!(snapshot.nut_force_n, string.nut_force_n());
        assert_eq!(snapshot.rest_nut_force_n, string.rest_nut_force_n());
        assert_eq!(snapshot.bridge_force_n, string.bridge_force_n());
        assert_eq!(snapshot.rest_bridge_force_n, string.rest_bridge_force_n());
        assert_eq!(snapshot.shown_newton, *string.newton_stats());
    }

    #[test]
    fn snapshot_of_a_ringing_string_equals_its_state_field_by_field() {
        let mut string = FdString::new(FdStringConfig::REFERENCE);
        string.pluck(&Pluck::default());
        let mut snapshot = TanpuraSnapshot::default();
        let mut contacts_seen = 0;
        // Several moments of the first milliseconds: pressing, release, contact, free flight.
        for _ in 0..12 {
            for _ in 0..150 {
                string.step();
            }
            snapshot.fill_fd_string(&string);
            assert_snapshot_is_fd_string(&snapshot, &string);
            contacts_seen += snapshot.bridge.contact_count() + snapshot.thread.contact_count();
        }
        assert!(contacts_seen > 0, "the string touches bridge or thread");
        // A string resting on bridge and thread touches the thread (rest state).
        string.settle_to_rest();
        snapshot.fill_fd_string(&string);
        assert_snapshot_is_fd_string(&snapshot, &string);
        assert!(snapshot.thread.contact_count() > 0);
    }

    #[test]
    fn grids_larger_than_the_snapshot_are_held_every_stride_points() {
        assert_eq!(fit(201, 256), (201, 1));
        assert_eq!(fit(256, 256), (256, 1));
        assert_eq!(fit(257, 256), (129, 2));
        assert_eq!(fit(401, 256), (201, 2));
        assert_eq!(fit(0, 64), (0, 1));
        let mut config = FdStringConfig::REFERENCE;
        config.intervals = 400;
        let string = FdString::new(config);
        let mut snapshot = TanpuraSnapshot::default();
        snapshot.fill_fd_string(&string);
        assert_eq!((snapshot.node_count, snapshot.node_stride), (201, 2));
        let y = string.displacement_m();
        for held in 0..snapshot.node_count {
            assert_eq!(snapshot.displacement_m[held], y[2 * held] as f32);
        }
        assert_eq!(
            snapshot.node_positions_m[snapshot.node_count - 1],
            config.string.length_m as f32
        );
    }

    #[test]
    fn output_history_keeps_the_last_samples_in_time_order() {
        let mut history = OutputHistory::default();
        let ramp: Vec<f32> = (0..3000).map(|i| i as f32).collect();
        history.push_block(&ramp[..100]);
        let (older, newer) = history.chronological();
        assert_eq!(older, &ramp[..100]);
        assert!(newer.is_empty());
        for block in ramp[100..].chunks(64) {
            history.push_block(block);
        }
        let (older, newer) = history.chronological();
        let joined: Vec<f32> = older.iter().chain(newer).copied().collect();
        assert_eq!(joined, &ramp[3000 - FORCE_HISTORY_SAMPLES..]);
        // A block longer than the ring keeps its own tail.
        history.push_block(&ramp);
        let (older, newer) = history.chronological();
        let joined: Vec<f32> = older.iter().chain(newer).copied().collect();
        assert_eq!(joined, &ramp[3000 - FORCE_HISTORY_SAMPLES..]);

        let mut snapshot = TanpuraSnapshot {
            output_to_force_n: 2.0,
            ..TanpuraSnapshot::default()
        };
        snapshot.fill_force_history(&history);
        assert_eq!(snapshot.force_len, FORCE_HISTORY_SAMPLES);
        for (force, sample) in snapshot.force_history_n().iter().zip(&joined) {
            assert_eq!(*force, 2.0 * sample);
        }
    }

    /// The force strip is the pickup force in newtons: with one note played, the engine's
    /// output converted back must match a lone voice given the same settings and pluck. (The
    /// lone voice is tuned along a different path, so its state differs from the engine's string
    /// by round-off: the comparison allows 1e-6 of the peak. The exact field-by-field check of
    /// the engine's own string is `engine::tests::snapshot_equals_the_loudest_string_exactly`.)
    #[test]
    fn engine_snapshot_force_history_is_the_pickup_force_in_newtons() {
        let settings = EngineSettings::default();
        let rate = 44_100.0;
        let mut engine = Engine::new(&settings, rate, 4);
        let note = 50;
        let hz = pitch::note_to_hz(note);
        let mut output = vec![0.0f32; 441];
        engine.process(&[TimedEvent::note_on(0, note, 1.0)], &mut output);
        let mut voice_settings = engine.settings().voice;
        voice_settings.fundamental_hz = hz;
        let mut lone = TanpuraVoice::new(&voice_settings, rate);
        lone.pluck(&settings.pluck);
        let mut lone_output = vec![0.0f32; 441];
        lone.process(&mut lone_output);

        let mut snapshot = TanpuraSnapshot::default();
        engine.fill_snapshot(&mut snapshot);
        assert_eq!(snapshot.fundamental_hz, hz);
        assert_eq!(snapshot.active_voices, 1);
        assert_eq!(snapshot.sample_rate_hz, rate);
        let expected_oversample = (1.0 / (lone.string().time_step_s() * rate)).round();
        assert_eq!(f64::from(snapshot.oversample), expected_oversample);

        let mut history = OutputHistory::default();
        history.push_block(&output);
        snapshot.fill_force_history(&history);
        assert_eq!(snapshot.force_len, output.len());
        let peak = lone_output.iter().fold(0.0f32, |p, x| p.max(x.abs()));
        assert!(peak > 0.05, "the pluck reaches the nut: {peak} N");
        for (force, lone_sample) in snapshot.force_history_n().iter().zip(&lone_output) {
            assert!(
                (force - lone_sample).abs() <= 1e-6 * peak,
                "{force} N vs {lone_sample} N"
            );
        }
    }

    #[test]
    fn engine_snapshot_follows_the_loudest_string() {
        let mut engine = Engine::new(&EngineSettings::default(), 44_100.0, 4);
        let mut output = vec![0.0f32; 256];
        let events = [
            TimedEvent::note_on(0, 48, 0.1),
            TimedEvent::note_on(10, 55, 1.0),
        ];
        engine.process(&events, &mut output);
        for _ in 0..8 {
            engine.process(&[], &mut output);
        }
        let mut snapshot = TanpuraSnapshot::default();
        engine.fill_snapshot(&mut snapshot);
        assert_eq!(snapshot.active_voices, 2);
        assert_eq!(snapshot.fundamental_hz, pitch::note_to_hz(55));
        assert!(snapshot.newton.steps > snapshot.shown_newton.steps);
    }
}
