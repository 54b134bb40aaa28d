//! The live tier's string on the reference's grid modes (`docs/modal-tanpura.md` §10–11),
//! plucked as the bench's one-string scene plucks it, timed:
//! `cargo run --release -p javari-core --example grid_mode_cost -- [KEY] [BRIDGE/THREAD] [nodes|points]`
//! (defaults: key 60, contact points every 0.18 / 0.15 mm as the reference's barrier grids, the
//! contact condensed on the grid's nodes). Prints the real-time factor of three runs of 3 s,
//! Newton's updates per step, a checksum of the nut force and what one of the voice's tuning
//! passes costs (a new tension and the linearised fundamental) and a pluck of the ringing string,
//! with the linearised fundamental, so that the condensed and the
//! point-level solves can be compared for cost and for the same string. A timing loop for
//! profiling; the bench is the figure of record.

use javari_core::analysis::refined::reference_grid_modes;
use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::modal::{GridModes, ModalString};
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::VoiceSettings;
use std::time::Instant;

const SAMPLE_RATE: f64 = 44_100.0;
const SECONDS: f64 = 3.0;

fn main() {
    let mut args = std::env::args().skip(1);
    let key: u8 = args.next().map_or(60, |s| s.parse().expect("key"));
    let spacings = args.next().unwrap_or_else(|| "0.18/0.15".to_owned());
    let (bridge_mm, thread_mm) = spacings
        .split_once('/')
        .map(|(b, t)| {
            (
                b.parse::<f64>().expect("bridge"),
                t.parse::<f64>().expect("thread"),
            )
        })
        .expect("spacings as BRIDGE/THREAD in mm");
    let condensed = args.next().is_none_or(|solve| solve != "points");
    let settings = VoiceSettings {
        quality: Quality::Live,
        fundamental_hz: note_to_hz(key),
        ..VoiceSettings::default()
    };
    let mut config = settings
        .modal_config_at(Quality::Live, SAMPLE_RATE)
        .expect("the live tier is modal");
    config.grid_modes = Some(GridModes {
        condensed,
        ..reference_grid_modes(SAMPLE_RATE)
    });
    config.bridge_point_spacing_m = 1e-3 * bridge_mm;
    config.thread_point_spacing_m = 1e-3 * thread_mm;
    let steps = (SECONDS * SAMPLE_RATE) as usize;
    for run in 0..3 {
        let mut string = ModalString::<f32>::new(config);
        string.pluck(&Pluck::default());
        let mut checksum = 0.0;
        let start = Instant::now();
        for _ in 0..steps {
            string.step();
            checksum += string.nut_force_change_n().abs();
        }
        let factor = SECONDS / start.elapsed().as_secs_f64();
        // A retune of the ringing string: a new configuration (the tension 0.1 % up or down,
        // alternately) and its linearised fundamental, as each of the voice's tuning passes.
        let retunes = 20;
        let start = Instant::now();
        for retune in 0..retunes {
            let mut changed = config;
            changed.string.tension_n *= if retune % 2 == 0 { 1.001 } else { 1.0 };
            string.set_config(changed);
            string.linearised_fundamental_hz();
        }
        let retune_us = start.elapsed().as_secs_f64() / retunes as f64 * 1e6;
        // Plucks of the ringing string (the finger's press solved with the contact).
        let start = Instant::now();
        for _ in 0..retunes {
            string.pluck(&Pluck::default());
        }
        let pluck_us = start.elapsed().as_secs_f64() / retunes as f64 * 1e6;
        string.set_config(config);
        println!(
            "run {run}: key {key}, {} points, {} nodes: {factor:.2}x real time, Newton {:.3} \
             updates per step, checksum {checksum:.9e}; a tuning pass (new tension, linearised \
             fundamental) {retune_us:.0} µs, a pluck {pluck_us:.0} µs; linearised fundamental \
             {:.9} Hz",
            string.point_positions_m().len(),
            string.contact_node_count(),
            string.newton_stats().mean_iterations(),
            string.linearised_fundamental_hz()
        );
    }
}
