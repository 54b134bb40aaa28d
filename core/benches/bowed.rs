//! Cost of one bowed voice, both tiers: real-time factor = simulated seconds per wall-clock
//! second of a single thread.
//!
//! `cargo bench -p javari-core --bench bowed`
//!
//! Three sections:
//!
//! 1. The `cargo xtask bench` scene (`BowedNote`): A3 = 220 Hz on the violin A constants,
//!    β = 0.1, v_b = 0.1 m/s, F_b = 0.4 N, 44.1 kHz, rendered from rest (attack included) in
//!    64-sample blocks into an `f32` buffer, body filter on and off; each block rendered by
//!    `BowedVoice::process` (as xtask renders it) and, for comparison, by a `next_sample` call
//!    per sample. Each figure is the median (and best) of [`SCENE_RUNS`] runs of [`SCENE_S`]
//!    simulated seconds, each run from a reset voice; the median is the honest figure on a
//!    shared machine, the best the least disturbed.
//! 2. The same note played through [`BowedInstrument`] (MIDI note-on, every control smoothed and
//!    set on the voice every sample, as the plugin plays it), both tiers, body on.
//! 3. The steady-state table across sample rates (440 Hz, F_b = 0.3 N), best of [`RUNS`].
//!
//! Nothing here asserts: speed is measured, never tested (house style 13).

use std::hint::black_box;
use std::time::Instant;

use javari_core::bowed::{
    BowTableString, BowTier, BowedCapacity, BowedEvent, BowedInstrument, BowedPlayerSettings,
    BowedString, BowedVoice, StringConstants,
};

/// Simulated seconds per run of the scene.
const SCENE_S: f64 = 3.0;

/// Runs per scene figure; the median and the best are reported.
const SCENE_RUNS: usize = 9;

/// Simulated seconds per run of the rate table.
const SIMULATED_S: f64 = 4.0;

/// Runs per rate-table figure; the fastest is reported.
const RUNS: usize = 5;

/// The `cargo xtask bench` block size.
const BLOCK: usize = 64;

const SCENE_RATE_HZ: f64 = 44_100.0;

/// Median and best of `runs` timings of `run` (each returns its elapsed seconds).
fn median_and_best(runs: usize, mut run: impl FnMut() -> f64) -> (f64, f64) {
    let mut times: Vec<f64> = (0..runs).map(|_| run()).collect();
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], times[0])
}

/// The xtask `BowedNote` scene from rest, in 64-sample blocks rendered by
/// [`BowedVoice::process`] (`per_sample` false, as xtask renders it) or by a
/// [`BowedVoice::next_sample`] call per sample; elapsed seconds.
fn scene_run<V: BowedVoice>(voice: &mut V, body: bool, per_sample: bool) -> f64 {
    voice.prepare(SCENE_RATE_HZ).unwrap();
    voice.set_pitch_hz(220.0);
    voice.set_bow_position(0.1);
    voice.set_bow_velocity_m_s(0.1);
    voice.set_bow_force_n(0.4);
    voice.set_body_enabled(body);
    let samples = (SCENE_S * SCENE_RATE_HZ) as usize;
    let mut block = [0.0f32; BLOCK];
    let mut sum = 0.0f32;
    let start = Instant::now();
    let mut done = 0;
    while done < samples {
        let length = BLOCK.min(samples - done);
        if per_sample {
            for sample in block[..length].iter_mut() {
                *sample = voice.next_sample().radiated as f32;
            }
        } else {
            voice.process(&mut block[..length]);
        }
        sum += black_box(&block)[0];
        done += length;
    }
    let elapsed = start.elapsed().as_secs_f64();
    black_box(sum);
    elapsed
}

/// The same note through the MIDI instrument (setters every sample); elapsed seconds.
fn instrument_run(tier: BowTier) -> f64 {
    let settings = BowedPlayerSettings {
        tier,
        ..BowedPlayerSettings::default()
    };
    let mut player =
        BowedInstrument::new(StringConstants::violin_a(), settings, SCENE_RATE_HZ).unwrap();
    player.handle(BowedEvent::NoteOn {
        note: 57,
        velocity: 0.5,
    });
    let samples = (SCENE_S * SCENE_RATE_HZ) as usize;
    let mut block = [0.0f32; BLOCK];
    let mut sum = 0.0f32;
    let start = Instant::now();
    let mut done = 0;
    while done < samples {
        let length = BLOCK.min(samples - done);
        for sample in block[..length].iter_mut() {
            *sample = player.next_sample() as f32;
        }
        sum += black_box(&block)[0];
        done += length;
    }
    let elapsed = start.elapsed().as_secs_f64();
    black_box(sum);
    elapsed
}

fn steady<V: BowedVoice>(voice: &mut V, sample_rate_hz: f64, body: bool) -> (f64, f64) {
    voice.prepare(sample_rate_hz).unwrap();
    voice.set_pitch_hz(440.0);
    voice.set_bow_position(0.1);
    voice.set_bow_velocity_m_s(0.1);
    voice.set_bow_force_n(0.3);
    voice.set_body_enabled(body);
    // Warm up past the attack so the steady Helmholtz motion is what is timed.
    for _ in 0..(0.5 * sample_rate_hz) as usize {
        black_box(voice.next_sample());
    }
    let samples = (SIMULATED_S * sample_rate_hz) as usize;
    let mut best = f64::INFINITY;
    for _ in 0..RUNS {
        let start = Instant::now();
        let mut sum = 0.0;
        for _ in 0..samples {
            sum += black_box(voice.next_sample()).radiated;
        }
        best = best.min(start.elapsed().as_secs_f64());
        black_box(sum);
    }
    (SIMULATED_S / best, 1e9 * best / samples as f64)
}

/// `cargo bench -p javari-core --bench bowed -- profile TIER BODY SECONDS [per-sample]` runs
/// only the xtask scene for one voice (TIER `rounded` | `table` | `instrument-rounded` |
/// `instrument-table`, BODY `on` | `off`), for `perf record` or `valgrind --tool=callgrind`,
/// and prints its real-time factor.
fn profile(args: &[String]) {
    let tier = args.first().map(String::as_str).unwrap_or("rounded");
    let body = args.get(1).map(String::as_str) != Some("off");
    let seconds: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(30.0);
    let per_sample = args.get(3).map(String::as_str) == Some("per-sample");
    let runs = (seconds / SCENE_S).ceil().max(1.0) as usize;
    let capacity = BowedCapacity::default();
    let mut rounded = BowedString::new(capacity, StringConstants::violin_a());
    let mut table = BowTableString::new(capacity, StringConstants::violin_a());
    let mut total = 0.0;
    for _ in 0..runs {
        total += match tier {
            "table" => scene_run(&mut table, body, per_sample),
            "instrument-rounded" => instrument_run(BowTier::RoundedCorner),
            "instrument-table" => instrument_run(BowTier::BowTable),
            _ => scene_run(&mut rounded, body, per_sample),
        };
    }
    println!(
        "profile {tier}, body {}: {runs} runs, real-time factor {:.0}",
        on_off(body),
        runs as f64 * SCENE_S / total
    );
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args.first().map(String::as_str) == Some("profile") {
        profile(&args[1..]);
        return;
    }
    let capacity = BowedCapacity::default();
    let scene_samples = SCENE_S * SCENE_RATE_HZ;

    println!(
        "1. xtask scene: A3 220 Hz, violin A constants, β = 0.1, v_b = 0.1 m/s, F_b = 0.4 N, \
         44.1 kHz, from rest, 64-sample blocks; median (best) of {SCENE_RUNS} runs of {SCENE_S} s"
    );
    println!(
        "{:<28} {:>6} {:>24} {:>20}",
        "tier", "body", "real-time factor", "ns/sample"
    );
    for (per_sample, mode) in [(false, "process"), (true, "next_sample")] {
        for body in [true, false] {
            let mut rounded = BowedString::new(capacity, StringConstants::violin_a());
            let (median, best) =
                median_and_best(SCENE_RUNS, || scene_run(&mut rounded, body, per_sample));
            let name = format!("rounded corner, {mode}");
            print_scene_row(&name, body, median, best, scene_samples);
            let mut table = BowTableString::new(capacity, StringConstants::violin_a());
            let (median, best) =
                median_and_best(SCENE_RUNS, || scene_run(&mut table, body, per_sample));
            let name = format!("bow table, {mode}");
            print_scene_row(&name, body, median, best, scene_samples);
        }
    }

    println!();
    println!(
        "2. the same note through BowedInstrument (MIDI note 57, velocity 0.5, controls smoothed \
         and set every sample), body on; median (best) of {SCENE_RUNS} runs"
    );
    for (name, tier) in [
        ("rounded corner", BowTier::RoundedCorner),
        ("bow table", BowTier::BowTable),
    ] {
        let (median, best) = median_and_best(SCENE_RUNS, || instrument_run(tier));
        print_scene_row(name, true, median, best, scene_samples);
    }

    println!();
    println!(
        "3. steady state, violin A constants, 440 Hz, β = 0.1, F_b = 0.3 N, v_b = 0.1 m/s; \
         best of {RUNS} runs of {SIMULATED_S} s"
    );
    println!(
        "{:<28} {:>10} {:>6} {:>16} {:>12}",
        "tier", "rate (Hz)", "body", "real-time factor", "ns/sample"
    );
    for &rate in &[44_100.0, 48_000.0, 96_000.0, 192_000.0] {
        for body in [false, true] {
            let mut rounded = BowedString::new(capacity, StringConstants::violin_a());
            let (rtf, ns) = steady(&mut rounded, rate, body);
            print_rate_row("rounded corner", rate, body, rtf, ns);
            let mut table = BowTableString::new(capacity, StringConstants::violin_a());
            let (rtf, ns) = steady(&mut table, rate, body);
            print_rate_row("bow table", rate, body, rtf, ns);
        }
    }
}

fn on_off(body: bool) -> &'static str {
    if body {
        "on"
    } else {
        "off"
    }
}

fn print_scene_row(tier: &str, body: bool, median_s: f64, best_s: f64, samples: f64) {
    let rtf = format!("{:.0} ({:.0})", SCENE_S / median_s, SCENE_S / best_s);
    let ns = format!(
        "{:.1} ({:.1})",
        1e9 * median_s / samples,
        1e9 * best_s / samples
    );
    println!("{tier:<28} {:>6} {rtf:>24} {ns:>20}", on_off(body));
}

fn print_rate_row(tier: &str, rate: f64, body: bool, rtf: f64, ns: f64) {
    println!(
        "{tier:<28} {rate:>10.0} {:>6} {rtf:>16.0} {ns:>12.1}",
        on_off(body)
    );
}
