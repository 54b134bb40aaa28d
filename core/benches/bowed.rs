//! Cost of one bowed voice, both tiers (divan): the rounded-corner [`BowedString`] and the bow
//! table [`BowTableString`], body filter on and off, by block and by sample.
//!
//! `cargo bench -p javari-core --bench bowed` (one group: `-- scene`, `-- instrument`,
//! `-- steady`; one case, e.g. `-- 'scene::process::BowedString'`).
//!
//! **Reading the figures.** Every benchmark iteration renders one fixed block of 0.1 s of output:
//! 4410 samples at 44.1 kHz ([`BLOCK_SAMPLES`]; in `steady`, 0.1 s at that group's rate). Divan
//! reports the time per iteration, so **real-time factor = 0.1 s / reported time** (100 µs is
//! 1000× real time) for a single thread; ns per sample = reported time / 4410 at 44.1 kHz. Its
//! throughput column counts output samples per second.
//!
//! **What is timed.** Each voice is built, prepared and given its controls once per benchmark
//! (set-up, not timed) and then keeps playing across iterations: the bowed note is sustained, so
//! every timed block after the first (which holds the attack and falls in divan's tuning pass)
//! is the steady Helmholtz motion.
//!
//! - `scene`: the `cargo xtask bench` note (`BowedNote`): A3 = 220 Hz on the violin A constants,
//!   β = 0.1, v_b = 0.1 m/s, F_b = 0.4 N, 44.1 kHz, in 64-sample blocks into an `f32` buffer,
//!   body on and off; `scene::process` renders each block with `BowedVoice::process` (as xtask
//!   and the plugin do), `scene::next_sample` with a `next_sample` call per sample.
//! - `instrument`: the same note played through [`BowedInstrument`] (MIDI note 57, velocity 0.5,
//!   every control smoothed and set on the voice every sample, as the plugin plays it), both
//!   tiers, body on.
//! - `steady`: the rate table (violin A, 440 Hz, β = 0.1, F_b = 0.3 N, v_b = 0.1 m/s; 44.1, 48,
//!   96 and 192 kHz, body on and off), a `next_sample` call per sample, after 0.5 s of warm-up.
//!
//! For a profiler (`perf record`, `valgrind --tool=callgrind`), run one case alone with more
//! samples, e.g. `cargo bench -p javari-core --bench bowed -- 'scene::process::BowedString'
//! --sample-count 10000`, or with divan's `--test` to run each case exactly once.
//!
//! Nothing here asserts: speed is measured, never tested (house style 13). Under
//! `cargo test --all-targets` divan runs each benchmark once.

use std::fmt;

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use javari_core::bowed::{
    BowTableString, BowTier, BowedCapacity, BowedEvent, BowedInstrument, BowedPlayerSettings,
    BowedString, BowedVoice, StringConstants,
};

/// Output sample rate of the scene and the instrument, Hz.
const RATE_HZ: f64 = 44_100.0;

/// Simulated seconds per benchmark iteration.
const BLOCK_S: f64 = 0.1;

/// Output samples per benchmark iteration at 44.1 kHz: 0.1 s.
const BLOCK_SAMPLES: usize = 4410;

/// The `cargo xtask bench` (and typical host) block size.
const HOST_BLOCK: usize = 64;

fn main() {
    divan::main();
}

/// Body filter on or off.
#[derive(Clone, Copy)]
enum Body {
    On,
    Off,
}

impl Body {
    const BOTH: [Body; 2] = [Body::On, Body::Off];

    fn enabled(self) -> bool {
        matches!(self, Body::On)
    }
}

impl fmt::Display for Body {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.enabled() {
            "body on"
        } else {
            "body off"
        })
    }
}

/// A bowed tier with its constructor, for generic benchmarks.
trait Voice: BowedVoice {
    fn build() -> Self;
}

impl Voice for BowedString {
    fn build() -> Self {
        BowedString::new(BowedCapacity::default(), StringConstants::violin_a())
    }
}

impl Voice for BowTableString {
    fn build() -> Self {
        BowTableString::new(BowedCapacity::default(), StringConstants::violin_a())
    }
}

/// The xtask `BowedNote` scene's voice, prepared and bowing (at rest: the first block holds the
/// attack).
fn scene_voice<V: Voice>(body: Body) -> V {
    let mut voice = V::build();
    voice.prepare(RATE_HZ).unwrap();
    voice.set_pitch_hz(220.0);
    voice.set_bow_position(0.1);
    voice.set_bow_velocity_m_s(0.1);
    voice.set_bow_force_n(0.4);
    voice.set_body_enabled(body.enabled());
    voice
}

mod scene {
    use super::*;

    /// 0.1 s in 64-sample blocks, each rendered by `BowedVoice::process`.
    #[divan::bench(types = [BowedString, BowTableString], args = Body::BOTH)]
    fn process<V: Voice>(bencher: Bencher, body: Body) {
        let mut voice = scene_voice::<V>(body);
        let mut output = vec![0.0f32; BLOCK_SAMPLES];
        bencher
            .counter(ItemsCount::new(BLOCK_SAMPLES))
            .bench_local(|| {
                for block in output.chunks_mut(HOST_BLOCK) {
                    voice.process(block);
                }
                black_box(&output);
            });
    }

    /// 0.1 s in 64-sample blocks, each filled by a `BowedVoice::next_sample` call per sample.
    #[divan::bench(types = [BowedString, BowTableString], args = Body::BOTH)]
    fn next_sample<V: Voice>(bencher: Bencher, body: Body) {
        let mut voice = scene_voice::<V>(body);
        let mut output = vec![0.0f32; BLOCK_SAMPLES];
        bencher
            .counter(ItemsCount::new(BLOCK_SAMPLES))
            .bench_local(|| {
                for block in output.chunks_mut(HOST_BLOCK) {
                    for sample in block.iter_mut() {
                        *sample = voice.next_sample().radiated as f32;
                    }
                }
                black_box(&output);
            });
    }
}

/// The scene's note through the MIDI instrument (controls smoothed and set every sample), body
/// on; 0.1 s in 64-sample blocks of `BowedInstrument::next_sample`.
#[divan::bench(args = [BowTier::RoundedCorner, BowTier::BowTable])]
fn instrument(bencher: Bencher, tier: BowTier) {
    let settings = BowedPlayerSettings {
        tier,
        ..BowedPlayerSettings::default()
    };
    let mut player = BowedInstrument::new(StringConstants::violin_a(), settings, RATE_HZ).unwrap();
    player.handle(BowedEvent::NoteOn {
        note: 57,
        velocity: 0.5,
    });
    let mut output = vec![0.0f32; BLOCK_SAMPLES];
    bencher
        .counter(ItemsCount::new(BLOCK_SAMPLES))
        .bench_local(|| {
            for block in output.chunks_mut(HOST_BLOCK) {
                for sample in block.iter_mut() {
                    *sample = player.next_sample() as f32;
                }
            }
            black_box(&output);
        });
}

/// One case of the rate table.
#[derive(Clone, Copy)]
struct RateCase {
    rate_hz: f64,
    body: Body,
}

impl fmt::Display for RateCase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} kHz, {}", self.rate_hz / 1000.0, self.body)
    }
}

const RATE_CASES: [RateCase; 8] = {
    const fn case(rate_hz: f64, body: Body) -> RateCase {
        RateCase { rate_hz, body }
    }
    [
        case(44_100.0, Body::Off),
        case(44_100.0, Body::On),
        case(48_000.0, Body::Off),
        case(48_000.0, Body::On),
        case(96_000.0, Body::Off),
        case(96_000.0, Body::On),
        case(192_000.0, Body::Off),
        case(192_000.0, Body::On),
    ]
};

/// Steady Helmholtz motion at 440 Hz (F_b = 0.3 N) after 0.5 s of warm-up; 0.1 s at the case's
/// rate, a `next_sample` call per sample.
#[divan::bench(types = [BowedString, BowTableString], args = RATE_CASES)]
fn steady<V: Voice>(bencher: Bencher, case: RateCase) {
    let mut voice = V::build();
    voice.prepare(case.rate_hz).unwrap();
    voice.set_pitch_hz(440.0);
    voice.set_bow_position(0.1);
    voice.set_bow_velocity_m_s(0.1);
    voice.set_bow_force_n(0.3);
    voice.set_body_enabled(case.body.enabled());
    for _ in 0..(0.5 * case.rate_hz) as usize {
        black_box(voice.next_sample());
    }
    let samples = (BLOCK_S * case.rate_hz).round() as usize;
    bencher.counter(ItemsCount::new(samples)).bench_local(|| {
        let mut sum = 0.0;
        for _ in 0..samples {
            sum += voice.next_sample().radiated;
        }
        black_box(sum);
    });
}
