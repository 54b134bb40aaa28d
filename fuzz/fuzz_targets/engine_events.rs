//! A stream of engine events and parameter changes → `Engine::process`: finite, bounded output,
//! no panic, no allocation.
//! The check is `javari_tests::fuzz::engine_events`, which the stable regression test replays too.

#![no_main]

use libfuzzer_sys::fuzz_target;

/// Aborts on an allocation inside `assert_no_alloc` (the fuzz build has debug assertions, `-a`),
/// which libFuzzer reports as a crash.
#[global_allocator]
static ALLOCATOR: nice_assert_no_alloc::AllocDisabler = nice_assert_no_alloc::AllocDisabler;

fuzz_target!(|data: &[u8]| javari_tests::fuzz::engine_events(data));
