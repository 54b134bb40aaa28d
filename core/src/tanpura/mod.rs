//! The tanpura: a stiff, lossy string in distributed contact with a curved bridge and a cotton
//! thread (van Walstijn & Chatziioannou, ISMA 2014, seed 000; `shared/notes/tanpura-model.md`).
//!
//! Shared by every discretisation:
//! - `string.rs`: the string's physical constants;
//! - `geometry.rs`: the bridge, thread and finger profiles with their contact constants;
//! - `contact.rs`: the Hunt–Crossley law in the seed's energy-stable mid-point form;
//! - `excitation.rs`: the finger pluck and the first-mode shape;
//! - `quality.rs`: the tiers, each naming its discretisation and resolution.
//!
//! The discretisations, side by side behind the same voice interface:
//! - `fd/`: the seed's finite-difference scheme (studio and reference tiers);
//! - `modal/`: the string in its own eigenmodes with exact partials at the output rate and the
//!   seed's contact force on a few points, Newton on the points that touch (`docs/modal-tanpura.md`).
//!
//! `voice.rs` turns musician-facing settings into a tuned string of the chosen tier;
//! `instrument.rs` is the four-string drone.

pub mod as_played;
pub mod body;
pub mod contact;
pub mod excitation;
pub mod fd;
pub mod geometry;
pub mod instrument;
pub mod modal;
pub mod quality;
pub mod string;
pub mod tier_string;
pub mod voice;

pub use instrument::{FirstString, Tanpura};
pub use voice::{
    reference_fundamental_hz, tension_for_pitch_n, SettingsError, TanpuraVoice, VoiceSettings,
    MAX_OVERSAMPLE, SLEEP_ENERGY_J, TUNING_PASSES,
};
