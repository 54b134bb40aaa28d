//! The bench's bowed note (`cargo xtask bench`'s `bowed-note`: A3 on the violin A constants,
//! β = 0.1, 0.1 m/s, 0.4 N, body on), timed three ways per voice so that the harness's share
//! can be told from the voice's: `cargo run --release -p javari-core --example bowed_note_cost
//! -- [SECONDS] [RUNS]`. "blocks" times each 64-sample block as the bench does (a clock read
//! per block), "whole" the same blocks under one clock read, "steady" the whole note again
//! without the reset to rest (no attack). Fastest of RUNS per way.

use javari_core::bowed::{BowTableString, BowedCapacity, BowedString, BowedVoice, StringConstants};
use std::time::Instant;

const SAMPLE_RATE: f64 = 44_100.0;
const BLOCK: usize = 64;

fn note<V: BowedVoice>(mut voice: V) -> V {
    voice.prepare(SAMPLE_RATE).expect("44.1 kHz");
    voice.set_pitch_hz(220.0);
    voice.set_bow_position(0.1);
    voice.set_bow_velocity_m_s(0.1);
    voice.set_bow_force_n(0.4);
    voice.set_body_enabled(true);
    voice
}

fn play<V: BowedVoice>(voice: &mut V, blocks: usize, per_block: bool) -> (f64, f64) {
    let mut block = [0.0f32; BLOCK];
    let mut checksum = 0.0;
    let mut seconds = 0.0;
    let whole = Instant::now();
    for _ in 0..blocks {
        let start = Instant::now();
        voice.process(&mut block);
        if per_block {
            seconds += start.elapsed().as_secs_f64();
        }
        checksum += block.iter().map(|&s| f64::from(s).abs()).sum::<f64>();
    }
    if !per_block {
        seconds = whole.elapsed().as_secs_f64();
    }
    (seconds, checksum)
}

fn time<V: BowedVoice>(name: &str, make: impl Fn() -> V, seconds: f64, runs: usize) {
    let blocks = (seconds * SAMPLE_RATE) as usize / BLOCK;
    let audio = (blocks * BLOCK) as f64 / SAMPLE_RATE;
    let mut best = [0.0f64; 3];
    let mut checksum = 0.0;
    for _ in 0..runs {
        for (way, best) in best.iter_mut().enumerate() {
            let mut voice = note(make());
            play(&mut voice, blocks, false);
            if way < 2 {
                voice.reset();
            }
            let (elapsed, sum) = play(&mut voice, blocks, way == 0);
            if way == 0 {
                checksum = sum;
            }
            *best = best.max(audio / elapsed);
        }
    }
    println!(
        "{name}: blocks {:.0}x, whole {:.0}x, steady {:.0}x real time (checksum {checksum:.12e})",
        best[0], best[1], best[2]
    );
}

fn main() {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args.next().map_or(3.0, |s| s.parse().expect("seconds"));
    let runs: usize = args.next().map_or(20, |s| s.parse().expect("runs"));
    let capacity = BowedCapacity::default();
    time(
        "rounded corner",
        || BowedString::new(capacity, StringConstants::violin_a()),
        seconds,
        runs,
    );
    time(
        "bow table",
        || BowTableString::new(capacity, StringConstants::violin_a()),
        seconds,
        runs,
    );
}
