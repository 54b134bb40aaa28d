//! MIDI file bytes → the engine's event list (`javari_core::engine::midi_file::parse`).
//! The check is `javari_tests::fuzz::midi_file`, which the stable regression test replays too.

#![no_main]

use javari_tests::allocations::CountingAllocator;
use libfuzzer_sys::fuzz_target;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

fuzz_target!(|data: &[u8]| javari_tests::fuzz::midi_file(data));
