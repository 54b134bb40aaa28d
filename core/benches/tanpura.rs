//! Cost of the tanpura: one string at the modal live and fine tiers and at the FD reference
//! tier, the four-string instrument, and the reference FD string's two Newton solvers (divan).
//!
//! `cargo bench -p javari-core --bench tanpura` (one group: `-- one_string`, `-- four_strings`,
//! `-- fd_string`, `-- free_steps`).
//!
//! **Reading the figures.** Every benchmark iteration renders one fixed block of 0.1 s: 4410
//! output samples at 44.1 kHz ([`BLOCK_SAMPLES`]), or for `fd_string` the 17 640 FD steps of 0.1 s
//! at the reference's 4 × 44.1 kHz. Divan reports the time per iteration, so
//! **real-time factor = 0.1 s / reported time** (10 ms is 10× real time, 200 ms is 0.5×); its
//! throughput column counts output samples (FD steps for `fd_string`) per second.
//!
//! **What is timed.** Each iteration starts from the same state, a string (or all four strings)
//! plucked with `Pluck::default()` (2 mm at 0.35 m, 10 mm fingertip) from rest, and times the
//! first 0.1 s after the release, where the contact with bridge and thread is busiest. Building
//! the voice (once per benchmark), cloning it and plucking it (the static pluck solve) are set-up
//! and are not timed.
//!
//! - `one_string`: a [`TanpuraVoice`] at the seed's reference string and settings
//!   ([`VoiceSettings::default`]) on the modal live tier (the fastest that plays the jawari),
//!   the modal fine tier (the plugin's default: the reference's grid in modes, contact on the
//!   grid's nodes) and the FD reference tier (4 × oversampled, Δx = 3.34 mm, Newton to 1e-13 m
//!   through the condensed solver, with its decimator), rendered by `TanpuraVoice::process`.
//! - `four_strings`: the [`Tanpura`] drone (Pa, Sa, Sa, low Sa on the same settings), all four
//!   strings plucked together, one `Tanpura::next_sample` per output sample, at the three tiers.
//! - `fd_string`: the reference [`FdString`] stepped alone (no voice, no decimator) with the
//!   condensed solver and with the plain full Newton.
//! - `free_steps`: one call of the live tier's free-step kernel, its matrix on a cache line and
//!   16 bytes off it (the time per iteration is the kernel's, not 0.1 s of audio).
//!
//! Newton's iteration counts are not reported here (`cargo xtask bench` and `cargo xtask simulate`
//! give them). Nothing here asserts: speed is measured, never tested (house style 13). Under
//! `cargo test --all-targets` divan runs each benchmark once.

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use javari_core::simd::{CacheAligned, Kernels};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig, SolverKind};
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{Tanpura, TanpuraVoice, VoiceSettings};

/// Output sample rate, Hz.
const RATE_HZ: f64 = 44_100.0;

/// Simulated seconds per benchmark iteration.
const BLOCK_S: f64 = 0.1;

/// Output samples per benchmark iteration: 0.1 s at 44.1 kHz.
const BLOCK_SAMPLES: usize = 4410;

/// The tiers compared: the fastest modal tier, the plugin's default and the renderer's.
const TIERS: [Quality; 3] = [Quality::Live, Quality::Fine, Quality::Reference];

fn main() {
    divan::main();
}

fn settings(quality: Quality) -> VoiceSettings {
    VoiceSettings {
        quality,
        ..VoiceSettings::default()
    }
}

#[divan::bench(args = TIERS, max_time = 10)]
fn one_string(bencher: Bencher, quality: Quality) {
    let voice = TanpuraVoice::new(&settings(quality), RATE_HZ);
    bencher
        .counter(ItemsCount::new(BLOCK_SAMPLES))
        .with_inputs(|| {
            let mut voice = voice.clone();
            voice.pluck(&Pluck::default());
            (voice, vec![0.0f32; BLOCK_SAMPLES])
        })
        .bench_local_refs(|(voice, block)| {
            voice.process(block);
            black_box(block);
        });
}

#[divan::bench(args = TIERS, max_time = 10)]
fn four_strings(bencher: Bencher, quality: Quality) {
    let settings = settings(quality);
    let tanpura = Tanpura::new(&settings, settings.fundamental_hz, RATE_HZ);
    bencher
        .counter(ItemsCount::new(BLOCK_SAMPLES))
        .with_inputs(|| {
            let mut tanpura = tanpura.clone();
            for index in 0..4 {
                tanpura.pluck(index, &Pluck::default());
            }
            (tanpura, vec![0.0f32; BLOCK_SAMPLES])
        })
        .bench_local_refs(|(tanpura, block)| {
            for sample in block.iter_mut() {
                *sample = tanpura.next_sample();
            }
            black_box(block);
        });
}

#[divan::bench(args = [SolverKind::Condensed, SolverKind::FullNewton], max_time = 10)]
fn fd_string(bencher: Bencher, solver: SolverKind) {
    let mut config = FdStringConfig::REFERENCE;
    config.solver = solver;
    let steps = (BLOCK_S / config.time_step_s).round() as usize;
    let string = FdString::new(config);
    bencher
        .counter(ItemsCount::new(steps))
        .with_inputs(|| {
            let mut string = string.clone();
            string.pluck(&Pluck::default());
            string
        })
        .bench_local_refs(|string| {
            for _ in 0..steps {
                string.step();
            }
            black_box(string.nut_force_n());
        });
}

/// Bytes by which the free-step matrix is moved off a cache line in [`free_steps`].
const MISALIGNMENTS_BYTES: [usize; 2] = [0, 16];

/// The modal live tier's free-step kernel alone (`Kernels::leading_dots`: 36 contact points'
/// rows of 96 f32 modes, row stride 128, against one vector), with the matrix starting on a
/// cache line and 16 bytes off it: what `simd::CacheAligned` buys. One call per iteration.
#[divan::bench(args = MISALIGNMENTS_BYTES)]
fn free_steps(bencher: Bencher, misalignment_bytes: usize) {
    const POINTS: usize = 36;
    const STRIDE: usize = 128;
    const LANES: usize = 96;
    let offset = misalignment_bytes / std::mem::size_of::<f32>();
    let mut storage = CacheAligned::new(POINTS * STRIDE + offset, 0.0f32);
    for (index, value) in storage[offset..].iter_mut().enumerate() {
        *value = (index as f32 * 0.01).sin();
    }
    let x: Vec<f32> = (0..LANES).map(|k| (k as f32 * 0.3).cos()).collect();
    let kernels = Kernels::detect();
    let mut out = [0.0f64; POINTS];
    bencher.bench_local(|| {
        kernels.leading_dots(black_box(&storage[offset..]), STRIDE, &x, &mut out);
        black_box(&out);
    });
}
