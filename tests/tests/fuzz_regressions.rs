//! The fuzz targets' inputs replayed on stable: the kept corpus (`fuzz/corpus/TARGET/`) and every
//! input that once crashed, hung or ran out of memory (`tests/fixtures/fuzz-regressions/TARGET/`),
//! each through the same check the target runs (`javari_tests::fuzz`), which asserts the
//! promised behaviour: an error, or a bounded, finite result without allocation on the audio
//! path (this binary's global allocator is nice-plug's allocation guard, see
//! `the_allocation_guard_aborts_on_an_allocation`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// Set in the child process of `the_allocation_guard_aborts_on_an_allocation`.
const ALLOCATE_UNDER_GUARD: &str = "JAVARI_ALLOCATE_UNDER_GUARD";

/// Slowest a single input may be (libFuzzer's runs used `-timeout=10`; the parsers promise well
/// under a second).
const MAX_TIME_PER_INPUT: Duration = Duration::from_secs(10);

fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The files of the corpus and of the regressions of `target`, sorted.
fn inputs(target: &str) -> Vec<PathBuf> {
    let root = repository_root();
    let mut files = Vec::new();
    for directory in [
        root.join("fuzz/corpus").join(target),
        root.join("tests/fixtures/fuzz-regressions").join(target),
    ] {
        let Ok(entries) = std::fs::read_dir(&directory) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            if path.is_file() {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

fn replay(target: &str, check: fn(&[u8]), at_least: usize) {
    let files = inputs(target);
    assert!(
        files.len() >= at_least,
        "{target}: {} inputs, expected at least {at_least}",
        files.len()
    );
    for file in files {
        let bytes = std::fs::read(&file).unwrap();
        let started = Instant::now();
        let outcome = std::panic::catch_unwind(|| check(&bytes));
        assert!(
            outcome.is_ok(),
            "{target}: {} fails its check",
            file.display()
        );
        let elapsed = started.elapsed();
        assert!(
            elapsed < MAX_TIME_PER_INPUT,
            "{target}: {} took {elapsed:?}",
            file.display()
        );
    }
}

#[test]
fn midi_file_inputs_are_parsed_or_refused() {
    replay("midi_file", javari_tests::fuzz::midi_file, 20);
}

#[test]
fn preset_text_inputs_are_read_or_refused() {
    replay("preset_text", javari_tests::fuzz::preset_text, 10);
}

#[test]
fn plugin_state_inputs_leave_every_parameter_in_range() {
    replay("plugin_state", javari_tests::fuzz::plugin_state, 4);
}

#[test]
fn engine_event_streams_give_finite_bounded_output_without_allocating() {
    replay("engine_events", javari_tests::fuzz::engine_events, 2);
}

#[test]
fn the_allocation_guard_aborts_on_an_allocation() {
    // In the child: allocate where the engine check forbids it; the guard must abort.
    if std::env::var_os(ALLOCATE_UNDER_GUARD).is_some() {
        nice_assert_no_alloc::assert_no_alloc(|| drop(std::hint::black_box(vec![1u8; 64])));
        return;
    }
    let output = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "the_allocation_guard_aborts_on_an_allocation",
            "--nocapture",
        ])
        .env(ALLOCATE_UNDER_GUARD, "1")
        .output()
        .unwrap();
    assert!(
        !output.status.success(),
        "an allocation under the guard did not abort: the engine check would miss allocations"
    );
    // The child did run the test (rather than fail to start).
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("running 1 test"), "{stdout}");
}
