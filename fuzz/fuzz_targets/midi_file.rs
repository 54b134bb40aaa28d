//! MIDI file bytes → the engine's event list (`javari_core::engine::midi_file::parse`).
//! The check is `javari_tests::fuzz::midi_file`, which the stable regression test replays too.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| javari_tests::fuzz::midi_file(data));
