//! Preset text → settings (`javari_core::engine::preset::Preset::parse`).
//! The check is `javari_tests::fuzz::preset_text`, which the stable regression test replays too.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| javari_tests::fuzz::preset_text(data));
