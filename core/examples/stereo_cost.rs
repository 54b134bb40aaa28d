//! What the stereo image costs the drone: the live tier's four-string drone (radiated through
//! the body, Sa = D3, 60 bpm) rendered for 10 s with `Engine::process` (mono) and
//! `Engine::process_stereo`, alternately five times each; prints the median of each and their
//! ratio. `cargo run --release -p javari-core --example stereo_cost`.

use javari_core::engine::{Engine, EngineSettings, TanpuraOutput, TimedEvent};
use javari_core::tanpura::quality::Quality;
use std::time::Instant;

const RATE: f64 = 44_100.0;
const BLOCK: usize = 64;

fn drone() -> Engine {
    let mut settings = EngineSettings::default();
    settings.voice.quality = Quality::Live;
    settings.tanpura_output = TanpuraOutput::Radiated;
    settings.drone.enabled = true;
    settings.drone.tempo_sync = false;
    settings.stereo_width = 1.0;
    Engine::new(&settings, RATE, 8)
}

fn seconds(stereo: bool) -> f64 {
    let mut engine = drone();
    let (mut left, mut right) = ([0.0f32; BLOCK], [0.0f32; BLOCK]);
    let hold = [TimedEvent::note_on(0, 50, 1.0)];
    let blocks = (10.0 * RATE) as usize / BLOCK;
    let start = Instant::now();
    for index in 0..blocks {
        let events: &[TimedEvent] = if index == 0 { &hold } else { &[] };
        if stereo {
            engine.process_stereo(events, &mut left, &mut right);
        } else {
            engine.process(events, &mut left);
        }
    }
    std::hint::black_box((left, right));
    start.elapsed().as_secs_f64()
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn main() {
    let (mut mono, mut stereo) = (Vec::new(), Vec::new());
    for _ in 0..5 {
        mono.push(seconds(false));
        stereo.push(seconds(true));
    }
    let (mono, stereo) = (median(mono), median(stereo));
    println!(
        "10 s of the live drone: mono {mono:.3} s, stereo {stereo:.3} s, stereo costs {:+.1} %",
        100.0 * (stereo / mono - 1.0)
    );
}
