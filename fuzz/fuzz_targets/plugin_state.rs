//! The plugin's saved state → parameters (`javari::state::restore`, the wrapper's load path).
//! The check is `javari_tests::fuzz::plugin_state`, which the stable regression test replays too.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| javari_tests::fuzz::plugin_state(data));
