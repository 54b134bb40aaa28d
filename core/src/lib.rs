//! javari-core: every equation and solver of the Javari instrument, free of any plugin framework.
//!
//! Tanpura voice (van Walstijn & Chatziioannou, ISMA 2014; `shared/notes/tanpura-model.md`) and
//! bowed voice (McIntyre–Schumacher–Woodhouse, Woodhouse 1993; `shared/notes/bowed-model.md`).
//! SI units throughout.

// Grid equations index nodes m − 1, m, m + 1 of several vectors at once; explicit index loops
// read like the finite-difference formulas they implement (house style: per-sample code reads
// like the physics).
#![allow(clippy::needless_range_loop)]

pub mod bowed;
pub mod stability;

pub mod tanpura;

pub mod analysis;
pub mod banded;
pub mod denormals;
pub mod dense;
pub mod engine;
pub mod newton;
pub mod simd;
pub mod snapshot;
pub mod snapshot_channel;
pub mod step_timers;
mod unroll;
