//! Where a modal step's time goes, part by part: time-stamp-counter totals for a profiling build.
//!
//! The fine tier's whole step is one function compiled for the vector unit (`modal/mod.rs`,
//! `WholeStep`), so `perf` sees one symbol, and about two fifths of its instructions carry the
//! line of an inlined std helper (integer methods, slice indexing, iterators) rather than one of
//! the step's own (cachegrind, `docs/performance.md`, stop 63). With the `step-timers` feature
//! each part of the step reads the processor's time-stamp counter where it starts and ends and
//! adds the difference to its total; `cargo run --release -p javari-core --features step-timers
//! --example step_parts` prints the totals per step. Without the feature every function here is
//! an empty inline one: the shipped build carries no counter and no atomic.
//!
//! The totals are relaxed atomic adds (no lock, no allocation), so a profiling build stays
//! real-time safe; they are shared by every string of the process.

/// A part of the modal step on the grid's nodes (`modal/nodal.rs`, `NodalContact::step`, and
/// `modal/mod.rs`, `step_on_nodes`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepPart {
    /// The node rows' dot products with the modes' free step.
    NodeDots,
    /// Forming S and inverting its compliance when the node set changed.
    FormSet,
    /// The tracked points' evaluations (step, law, case, nodal force).
    Evaluate,
    /// The segments' stiffness sums before an update.
    Stiffnesses,
    /// An update's matrix and right side.
    UpdateSetup,
    /// An update's LDLᵀ factorisation.
    Factorise,
    /// An update's substitution.
    Substitute,
    /// The exact finish of a step with crossing points.
    FinishCrossings,
    /// Every node's step from the forces on S.
    NodeSteps,
    /// The pass forming every point's gap from the nodes.
    PointPass,
    /// The tracked points' gaps, the nodal loads and the next guess.
    Outcome,
    /// The tracking's joins and releases.
    Tracking,
    /// The modes advanced with the nodal forces, and the outputs.
    Advance,
}

/// Every part, in the order the step takes them.
pub const STEP_PARTS: [StepPart; 13] = [
    StepPart::NodeDots,
    StepPart::FormSet,
    StepPart::Evaluate,
    StepPart::Stiffnesses,
    StepPart::UpdateSetup,
    StepPart::Factorise,
    StepPart::Substitute,
    StepPart::FinishCrossings,
    StepPart::NodeSteps,
    StepPart::PointPass,
    StepPart::Outcome,
    StepPart::Tracking,
    StepPart::Advance,
];

#[cfg(feature = "step-timers")]
mod counting {
    use super::{StepPart, STEP_PARTS};
    use std::sync::atomic::{AtomicU64, Ordering};

    static TOTALS: [AtomicU64; STEP_PARTS.len()] = [const { AtomicU64::new(0) }; STEP_PARTS.len()];

    /// The time-stamp counter (another clock elsewhere: nanoseconds since the first call).
    #[inline(always)]
    pub fn now() -> u64 {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: `rdtsc` has no preconditions on x86-64.
            #[allow(unused_unsafe)]
            unsafe {
                core::arch::x86_64::_rdtsc()
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            use std::sync::OnceLock;
            use std::time::Instant;
            static START: OnceLock<Instant> = OnceLock::new();
            START.get_or_init(Instant::now).elapsed().as_nanos() as u64
        }
    }

    #[inline(always)]
    pub fn add(part: StepPart, since: u64) -> u64 {
        let time = now();
        TOTALS[part as usize].fetch_add(time.wrapping_sub(since), Ordering::Relaxed);
        time
    }

    pub fn totals() -> [u64; STEP_PARTS.len()] {
        TOTALS.each_ref().map(|total| total.load(Ordering::Relaxed))
    }

    pub fn reset() {
        for total in &TOTALS {
            total.store(0, Ordering::Relaxed);
        }
    }
}

#[cfg(not(feature = "step-timers"))]
mod counting {
    use super::{StepPart, STEP_PARTS};

    #[inline(always)]
    pub fn now() -> u64 {
        0
    }

    #[inline(always)]
    pub fn add(_part: StepPart, _since: u64) -> u64 {
        0
    }

    pub fn totals() -> [u64; STEP_PARTS.len()] {
        [0; STEP_PARTS.len()]
    }

    pub fn reset() {}
}

/// Where a part starts: the counter now (0 without the feature).
#[inline(always)]
pub fn start() -> u64 {
    counting::now()
}

/// Adds the counter's advance since `since` to `part`'s total and returns the counter now, where
/// the next part starts.
#[inline(always)]
pub fn add(part: StepPart, since: u64) -> u64 {
    counting::add(part, since)
}

/// Each part's total so far, in [`STEP_PARTS`]' order (all zero without the feature).
pub fn totals() -> [u64; STEP_PARTS.len()] {
    counting::totals()
}

/// Sets every total to zero.
pub fn reset() {
    counting::reset()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parts index the totals in their own order.
    #[test]
    fn every_part_has_its_own_total() {
        for (index, part) in STEP_PARTS.iter().enumerate() {
            assert_eq!(*part as usize, index);
        }
    }

    /// With the feature a part's total grows by the time spent in it; without it nothing is
    /// counted.
    #[test]
    fn a_part_adds_the_time_since_its_start() {
        let since = start();
        let mut sum = 0.0f64;
        for i in 0..10_000 {
            sum += f64::from(i).sqrt();
        }
        assert!(sum > 0.0);
        add(StepPart::Advance, since);
        let total = totals()[StepPart::Advance as usize];
        if cfg!(feature = "step-timers") {
            assert!(total > 0, "no time counted");
        } else {
            assert_eq!(total, 0);
        }
    }
}
