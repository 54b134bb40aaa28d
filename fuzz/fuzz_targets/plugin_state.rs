//! The plugin's saved state → parameters (`javari::state::restore`, the wrapper's load path).
//! The check is `javari_tests::fuzz::plugin_state`, which the stable regression test replays too.

#![no_main]

use javari_tests::allocations::CountingAllocator;
use libfuzzer_sys::fuzz_target;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

fuzz_target!(|data: &[u8]| javari_tests::fuzz::plugin_state(data));
