//! `cargo xtask <command>`: the project's offline tools.
//!
//! clap parses every command line (help texts and errors are generated from the option structs
//! in each command's module); this file holds the command tree, dispatches and reports errors.

mod args;
mod bench;
mod bundle;
mod calibration_cache;
mod playing_range;
mod plot;
mod render;
mod simulate;
mod soak;
mod stability;

use clap::{CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

/// Javari's offline tools: render, bundle, simulate, bench, stability, soak.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask", bin_name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a MIDI file (or the built-in demo) to WAV through the plugin's engine.
    Render(render::RenderArgs),
    /// Build target/bundled/<package>.clap and .vst3 (`cargo xtask bundle javari --release`).
    Bundle(bundle::BundleArgs),
    /// The same as `bundle`, as a universal binary (macOS).
    BundleUniversal(bundle::BundleArgs),
    /// Probe one tanpura string: CSV of nut force, bridge force, energy, Newton statistics.
    Simulate(simulate::SimulateArgs),
    /// Every quality tier on the same scenes: speed, block times, error against reference.
    Bench(bench::BenchArgs),
    /// Woodhouse stability analysis: thresholds, eigenvalues, paper sweeps, preset margins.
    Stability(stability::StabilityArgs),
    /// Simulated hours of play with every parameter automated: block times, allocations, NaNs.
    Soak(soak::SoakArgs),
}

/// A command-line error found after parsing (a check that spans several options), reported as
/// clap reports its own: the message, the subcommand's usage line, exit code 2.
pub fn usage_error(subcommand: &str, message: impl std::fmt::Display) -> clap::Error {
    let mut cli = Cli::command();
    cli.build();
    let command = cli
        .find_subcommand_mut(subcommand)
        .expect("a subcommand of the tree");
    command.error(clap::error::ErrorKind::ArgumentConflict, message)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: Result<(), Box<dyn std::error::Error>> = match cli.command {
        Command::Render(args) => render::run(args),
        Command::Bundle(args) => bundle::run("bundle", args),
        Command::BundleUniversal(args) => bundle::run("bundle-universal", args),
        Command::Simulate(args) => simulate::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Stability(args) => stability::run(args),
        Command::Soak(args) => soak::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_tree_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn every_command_has_generated_help() {
        for command in ["render", "bundle", "simulate", "bench", "stability", "soak"] {
            let error = Cli::try_parse_from(["cargo xtask", command, "--help"]).unwrap_err();
            assert_eq!(
                error.kind(),
                clap::error::ErrorKind::DisplayHelp,
                "{command}"
            );
            let help = error.to_string();
            assert!(help.contains("Usage: cargo xtask"), "{command}: {help}");
        }
    }

    #[test]
    fn checks_after_parsing_report_like_clap() {
        let error = usage_error("stability", "option `--csv` writes a sweep");
        assert_eq!(error.exit_code(), 2);
        let text = error.to_string();
        assert!(
            text.starts_with("error: option `--csv` writes a sweep"),
            "{text}"
        );
        assert!(text.contains("Usage: cargo xtask stability"), "{text}");
    }

    #[test]
    fn bundle_passes_its_arguments_through() {
        let cli = Cli::try_parse_from(["cargo xtask", "bundle", "javari", "--release"]).unwrap();
        let Command::Bundle(args) = cli.command else {
            panic!("not bundle")
        };
        assert_eq!(args.args, ["javari", "--release"]);
    }
}
