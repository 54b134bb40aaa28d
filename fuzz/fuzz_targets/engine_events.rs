//! A stream of engine events and parameter changes → `Engine::process`: finite, bounded output,
//! no panic, no allocation.
//! The check is `javari_tests::fuzz::engine_events`, which the stable regression test replays too.

#![no_main]

use javari_tests::allocations::CountingAllocator;
use libfuzzer_sys::fuzz_target;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

fuzz_target!(|data: &[u8]| javari_tests::fuzz::engine_events(data));
