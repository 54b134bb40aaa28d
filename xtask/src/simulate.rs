//! `cargo xtask simulate`: a researcher's probe of one tanpura string.
//!
//! Runs one `FdString` at the internal rate and writes a CSV with the columns
//! `time_s,nut_force_n,bridge_force_n,energy_j,losses_j,newton_iterations,max_penetration_m`
//! (every step, or every `--every N` steps), and optionally a WAV of the nut force (minus its
//! rest value) at the internal rate, normalised to its peak.

use crate::args::number_in;
use clap::{Parser, ValueEnum};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::geometry::ThreadSettings;
use std::error::Error;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, ValueEnum)]
pub enum Excitation {
    /// A finger pressed to static equilibrium and released.
    Pluck,
    /// The string's first linear mode.
    FirstMode,
}

#[derive(Debug, Clone, Copy, PartialEq, ValueEnum)]
pub enum OnOff {
    On,
    Off,
}

#[derive(Debug, Clone, Copy, PartialEq, ValueEnum)]
pub enum Bridge {
    Full,
    /// k_b = 0 for x > x_c.
    OffBeyondThread,
}

#[derive(Debug, Parser)]
pub struct SimulateArgs {
    /// Simulated time, s (0 < S <= 60).
    #[arg(long, value_name = "S", default_value_t = 1.0, value_parser = number_in(1e-6, 60.0))]
    seconds: f64,
    /// gamma = eta = r = 0 (energy is then conserved to round-off).
    #[arg(long)]
    lossless: bool,
    /// How the string is set in motion.
    #[arg(long, value_name = "KIND", value_enum, default_value_t = Excitation::Pluck)]
    excitation: Excitation,
    /// The cotton thread.
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    thread: OnOff,
    /// Bridge contact everywhere, or none past the thread.
    #[arg(long, value_enum, default_value_t = Bridge::Full)]
    bridge: Bridge,
    /// Bridge stiffness k_b, N/m^2 (0 to 1e12).
    #[arg(long, value_name = "K", default_value_t = 1e8, value_parser = number_in(0.0, 1e12))]
    kb: f64,
    /// Thread position from the tuning bead, mm.
    #[arg(long, value_name = "X", default_value_t = 40.0, value_parser = number_in(
        ThreadSettings::POSITION_RANGE_M.0 * 1e3,
        ThreadSettings::POSITION_RANGE_M.1 * 1e3,
    ))]
    thread_position_mm: f64,
    /// Pluck position from the tuning bead, mm (50 to 660).
    #[arg(long, value_name = "X", default_value_t = 350.0, value_parser = number_in(50.0, 660.0))]
    pluck_position_mm: f64,
    /// Finger lift (pluck) or first-mode amplitude, mm (0 to 5).
    #[arg(long, value_name = "A", default_value_t = 2.0, value_parser = number_in(0.0, 5.0))]
    pluck_amplitude_mm: f64,
    /// Internal rate = M x 44.1 kHz (1 to 16; 4 is the seed's).
    #[arg(long, value_name = "M", default_value_t = 4, value_parser = number_in(1usize, 16))]
    oversample: usize,
    /// Write every N-th step (1 to 1000000).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = number_in(1usize, 1_000_000))]
    every: usize,
    /// CSV output.
    #[arg(long, value_name = "FILE.csv", default_value = "simulate.csv")]
    out: PathBuf,
    /// Also write the nut force as a WAV at the internal rate.
    #[arg(long, value_name = "FILE.wav")]
    wav: Option<PathBuf>,
}

/// Everything `simulate` needs, parsed and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateOptions {
    pub seconds: f64,
    pub config: FdStringConfig,
    pub first_mode: bool,
    pub pluck: Pluck,
    pub every: usize,
    pub out: PathBuf,
    pub wav: Option<PathBuf>,
}

/// The string configuration and run options of the command line, or why they do not fit.
pub fn options(args: SimulateArgs) -> Result<SimulateOptions, String> {
    if args.bridge == Bridge::OffBeyondThread && args.thread == OnOff::Off {
        return Err(
            "option `--bridge off-beyond-thread` needs `--thread on`: without a thread there is \
             no 'beyond the thread'"
                .into(),
        );
    }

    let mut config = FdStringConfig::REFERENCE;
    config.time_step_s = 1.0 / (44_100.0 * args.oversample as f64);
    config.bridge.stiffness_n_m2 = args.kb;
    config.bridge.beyond_thread = args.bridge == Bridge::Full;
    config.thread = (args.thread == OnOff::On).then_some(ThreadSettings {
        position_m: args.thread_position_mm * 1e-3,
        ..ThreadSettings::SEED
    });
    if args.lossless {
        config = config.lossless();
    }
    config.track_energy = true;
    Ok(SimulateOptions {
        seconds: args.seconds,
        config,
        first_mode: args.excitation == Excitation::FirstMode,
        pluck: Pluck {
            position_m: args.pluck_position_mm * 1e-3,
            amplitude_m: args.pluck_amplitude_mm * 1e-3,
            ..Pluck::default()
        },
        every: args.every,
        out: args.out,
        wav: args.wav,
    })
}

pub fn run(args: SimulateArgs) -> Result<(), Box<dyn Error>> {
    let options =
        options(args).unwrap_or_else(|message| crate::usage_error("simulate", message).exit());
    let mut string = FdString::new(options.config);
    if options.first_mode {
        string.excite_first_mode(options.pluck.amplitude_m);
    } else {
        string.pluck(&options.pluck);
    }
    let steps = (options.seconds / options.config.time_step_s).round() as usize;
    let file = File::create(&options.out)
        .map_err(|error| format!("cannot create `{}`: {error}", options.out.display()))?;
    let mut csv = BufWriter::new(file);
    writeln!(
        csv,
        "time_s,nut_force_n,bridge_force_n,energy_j,losses_j,newton_iterations,max_penetration_m"
    )?;
    let mut nut_signal = Vec::with_capacity(if options.wav.is_some() { steps } else { 0 });
    let rest_nut = string.rest_nut_force_n();
    for step in 1..=steps {
        string.step();
        if options.wav.is_some() {
            nut_signal.push(string.nut_force_n() - rest_nut);
        }
        if step % options.every == 0 {
            writeln!(
                csv,
                "{:.9e},{:.9e},{:.9e},{:.12e},{:.12e},{},{:.6e}",
                step as f64 * options.config.time_step_s,
                string.nut_force_n(),
                string.bridge_force_n(),
                string.energy_j(),
                string.cumulative_losses_j(),
                string.newton_stats().last_iterations,
                string.max_penetration_m(),
            )?;
        }
    }
    csv.flush()?;
    if let Some(path) = &options.wav {
        write_normalised_wav(path, &nut_signal, 1.0 / options.config.time_step_s)?;
    }
    let stats = string.newton_stats();
    eprintln!(
        "simulated {:.3} s ({steps} steps): Newton mean {:.2}, max {}, cap hits {}; wrote {}",
        options.seconds,
        stats.mean_iterations(),
        stats.max_iterations,
        stats.cap_hits,
        options.out.display()
    );
    Ok(())
}

/// Writes `signal` as 32-bit float mono, scaled so that its peak is at −1 dBFS.
fn write_normalised_wav(
    path: &PathBuf,
    signal: &[f64],
    sample_rate_hz: f64,
) -> Result<(), Box<dyn Error>> {
    let peak = signal.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let gain = if peak > 0.0 { 0.891 / peak } else { 0.0 };
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: sample_rate_hz.round() as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let mut writer = hound::WavWriter::create(path, spec)
        .map_err(|error| format!("cannot create `{}`: {error}", path.display()))?;
    for sample in signal {
        writer.write_sample((sample * gain) as f32)?;
    }
    writer.finalize()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The options of a command line, or the error clap or the checks would print.
    fn parse(line: &str) -> Result<SimulateOptions, String> {
        let words = std::iter::once("simulate").chain(line.split_whitespace());
        let args = SimulateArgs::try_parse_from(words).map_err(|error| error.to_string())?;
        options(args)
    }

    #[test]
    fn defaults_are_the_seed_reference() {
        let options = parse("").unwrap();
        assert_eq!(options.config.bridge, FdStringConfig::REFERENCE.bridge);
        assert_eq!(options.config.thread, FdStringConfig::REFERENCE.thread);
        assert_eq!(options.config.time_step_s, 1.0 / 176_400.0);
        assert!(!options.first_mode);
    }

    #[test]
    fn lossless_and_layout_options_map_onto_the_model() {
        let options = parse(
            "--lossless --thread-position-mm 42 --bridge off-beyond-thread --kb 1e9 \
             --excitation first-mode --oversample 8",
        )
        .unwrap();
        assert_eq!(options.config.string.gamma_per_s, 0.0);
        assert_eq!(options.config.bridge.damping_s_m, 0.0);
        assert!(!options.config.bridge.beyond_thread);
        assert_eq!(options.config.bridge.stiffness_n_m2, 1e9);
        assert!((options.config.thread.unwrap().position_m - 0.042).abs() < 1e-15);
        assert!(options.first_mode);
        assert_eq!(options.config.time_step_s, 1.0 / 352_800.0);
    }

    #[test]
    fn invalid_values_name_the_option_and_its_range() {
        let error = parse("--thread-position-mm 60").unwrap_err();
        assert!(
            error.contains("--thread-position-mm") && error.contains("30 to 45"),
            "{error}"
        );
        let error = parse("--excitation strum").unwrap_err();
        assert!(error.contains("pluck, first-mode"), "{error}");
        let error = parse("--thread off --bridge off-beyond-thread").unwrap_err();
        assert!(error.contains("--thread on"), "{error}");
        assert!(parse("--seconds 0").is_err());
        let error = parse("--sekonds 2").unwrap_err();
        assert!(error.contains("--sekonds"), "{error}");
    }

    #[test]
    fn writes_the_specified_csv_columns() {
        let directory =
            std::env::temp_dir().join(format!("javari-simulate-{}", std::process::id()));
        std::fs::create_dir_all(&directory).unwrap();
        let csv = directory.join("probe.csv");
        let wav = directory.join("probe.wav");
        let args = SimulateArgs::try_parse_from([
            "simulate".to_string(),
            "--seconds".to_string(),
            "0.002".to_string(),
            "--every".to_string(),
            "4".to_string(),
            "--out".to_string(),
            csv.display().to_string(),
            "--wav".to_string(),
            wav.display().to_string(),
        ])
        .unwrap();
        run(args).unwrap();
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next().unwrap(),
            "time_s,nut_force_n,bridge_force_n,energy_j,losses_j,newton_iterations,max_penetration_m"
        );
        let rows: Vec<&str> = lines.collect();
        // 0.002 s at 176.4 kHz is 353 steps (rounded); every 4th gives 88 rows.
        assert_eq!(rows.len(), 88);
        assert!(rows.iter().all(|row| row.split(',').count() == 7));
        let reader = hound::WavReader::open(&wav).unwrap();
        assert_eq!(reader.spec().sample_rate, 176_400);
        assert_eq!(reader.len(), 353);
        std::fs::remove_dir_all(&directory).unwrap();
    }
}
