//! `cargo xtask <command>`: the project's offline tools.
//!
//! Each command lives in its own module; this file only dispatches and reports errors.

mod args;
mod bench;
mod bundle;
mod plot;
mod render;
mod simulate;
mod stability;

use std::process::ExitCode;

const USAGE: &str = "usage: cargo xtask <command> [options]

commands:
  render      MIDI file (or the built-in demo) to WAV through the plugin's engine
  bundle      build target/bundled/<package>.clap and .vst3 (cargo xtask bundle javari --release)
  simulate    probe one tanpura string: CSV of nut force, bridge force, energy, Newton statistics
              (`cargo xtask simulate --help` lists its options)
  bench       every quality tier on the same scenes: speed, block times, error against reference
  stability   Woodhouse stability analysis: thresholds, eigenvalues, paper sweeps, preset margin";

fn main() -> ExitCode {
    let raw: Vec<String> = std::env::args().skip(1).collect();
    let Some((command, rest)) = raw.split_first() else {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    };
    let result: Result<(), Box<dyn std::error::Error>> = match command.as_str() {
        "render" => render::run(rest),
        "bundle" | "bundle-universal" => bundle::run(&raw),
        "simulate" => simulate::run(rest),
        "bench" => bench::run(rest),
        "stability" => stability::run(rest),
        "help" | "--help" | "-h" => {
            println!("{USAGE}");
            Ok(())
        }
        other => Err(format!("unknown command `{other}`\n{USAGE}").into()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(2)
        }
    }
}
