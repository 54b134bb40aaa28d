//! `cargo bench -p javari-core --bench tanpura`: real-time factors (simulated seconds per CPU
//! second) of one string and of the four-string instrument at the seed's reference
//! configuration (Δx = 3.34 mm, 4 × 44.1 kHz, full Newton to 1e-13 m through the condensed
//! solver), with the Newton iteration statistics. Also the plain full-Newton reference path.

use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig, SolverKind};
use javari_core::tanpura::{Tanpura, VoiceSettings};
use std::time::Instant;

const SECONDS: f64 = 2.0;

fn one_string(solver: SolverKind) {
    let mut config = FdStringConfig::REFERENCE;
    config.solver = solver;
    let mut string = FdString::new(config);
    string.pluck(&Pluck::default());
    let steps = (SECONDS / config.time_step_s) as usize;
    let start = Instant::now();
    for _ in 0..steps {
        string.step();
    }
    let elapsed = start.elapsed().as_secs_f64();
    let stats = string.newton_stats();
    println!(
        "one string, {solver:?}: {:.2}x real time ({:.2} us per step); Newton mean {:.2}, max {}, cap hits {}",
        SECONDS / elapsed,
        elapsed / steps as f64 * 1e6,
        stats.mean_iterations(),
        stats.max_iterations,
        stats.cap_hits
    );
}

fn four_strings() {
    let settings = VoiceSettings::default();
    let mut tanpura = Tanpura::new(&settings, settings.fundamental_hz, 44_100.0);
    for index in 0..4 {
        tanpura.pluck(index, &Pluck::default());
    }
    let samples = (SECONDS * 44_100.0) as usize;
    let start = Instant::now();
    let mut checksum = 0.0f64;
    for _ in 0..samples {
        checksum += tanpura.next_sample() as f64;
    }
    let elapsed = start.elapsed().as_secs_f64();
    let stats = tanpura.newton_stats();
    println!(
        "four-string tanpura: {:.2}x real time; Newton mean {:.2}, max {}, cap hits {} (checksum {checksum:.3e})",
        SECONDS / elapsed,
        stats.mean_iterations(),
        stats.max_iterations,
        stats.cap_hits
    );
}

fn main() {
    println!("tanpura at the reference configuration, {SECONDS} s simulated after a pluck");
    one_string(SolverKind::Condensed);
    one_string(SolverKind::FullNewton);
    four_strings();
}
