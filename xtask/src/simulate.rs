//! `cargo xtask simulate`: a researcher's probe of one tanpura string.
//!
//! Runs one `FdString` at the internal rate and writes a CSV with the columns
//! `time_s,nut_force_n,bridge_force_n,energy_j,losses_j,newton_iterations,max_penetration_m`
//! (every step, or every `--every N` steps), and optionally a WAV of the nut force (minus its
//! rest value) at the internal rate, normalised to its peak.

use crate::args::{ArgError, Args};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::geometry::ThreadSettings;
use std::error::Error;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

pub const HELP: &str = "cargo xtask simulate [options]

  --seconds S              simulated time, 0 < S <= 60 (default 1)
  --lossless               gamma = eta = r = 0 (energy is then conserved to round-off)
  --excitation KIND        pluck | first-mode (default pluck)
  --thread on|off          the cotton thread (default on)
  --bridge full|off-beyond-thread   k_b = 0 for x > x_c with off-beyond-thread (default full)
  --kb K                   bridge stiffness k_b in N/m^2, 0 to 1e12 (default 1e8)
  --thread-position-mm X   thread position from the tuning bead, 30 to 45 (default 40)
  --pluck-position-mm X    pluck position from the tuning bead, 50 to 660 (default 350)
  --pluck-amplitude-mm A   finger lift (pluck) or first-mode amplitude, 0 to 5 (default 2)
  --oversample M           internal rate = M x 44.1 kHz, 1 to 16 (default 4, the seed's)
  --every N                write every N-th step, 1 to 1000000 (default 1)
  --out FILE.csv           CSV output (default simulate.csv)
  --wav FILE.wav           also write the nut force as a WAV at the internal rate";

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

pub fn parse(raw: &[String]) -> Result<SimulateOptions, ArgError> {
    let mut args = Args::parse(raw, &["lossless"])?;
    let seconds = args.number("seconds", 1.0, 1e-6, 60.0)?;
    let lossless = args.flag("lossless");
    let excitation = args.choice("excitation", "pluck", &["pluck", "first-mode"])?;
    let thread = args.choice("thread", "on", &["on", "off"])?;
    let bridge = args.choice("bridge", "full", &["full", "off-beyond-thread"])?;
    let kb = args.number("kb", 1e8, 0.0, 1e12)?;
    let (thread_min, thread_max) = ThreadSettings::POSITION_RANGE_M;
    let thread_position_mm = args.number(
        "thread-position-mm",
        40.0,
        thread_min * 1e3,
        thread_max * 1e3,
    )?;
    let pluck_position_mm = args.number("pluck-position-mm", 350.0, 50.0, 660.0)?;
    let amplitude_mm = args.number("pluck-amplitude-mm", 2.0, 0.0, 5.0)?;
    let oversample: usize = args.number("oversample", 4, 1, 16)?;
    let every: usize = args.number("every", 1, 1, 1_000_000)?;
    let out = PathBuf::from(args.text("out").unwrap_or_else(|| "simulate.csv".into()));
    let wav = args.text("wav").map(PathBuf::from);
    args.finish()?;
    if bridge == "off-beyond-thread" && thread == "off" {
        return Err(ArgError(
            "option `--bridge off-beyond-thread` needs `--thread on`: without a thread there is \
             no 'beyond the thread'"
                .into(),
        ));
    }

    let mut config = FdStringConfig::REFERENCE;
    config.time_step_s = 1.0 / (44_100.0 * oversample as f64);
    config.bridge.stiffness_n_m2 = kb;
    config.bridge.beyond_thread = bridge == "full";
    config.thread = (thread == "on").then_some(ThreadSettings {
        position_m: thread_position_mm * 1e-3,
        ..ThreadSettings::SEED
    });
    if lossless {
        config = config.lossless();
    }
    config.track_energy = true;
    Ok(SimulateOptions {
        seconds,
        config,
        first_mode: excitation == "first-mode",
        pluck: Pluck {
            position_m: pluck_position_mm * 1e-3,
            amplitude_m: amplitude_mm * 1e-3,
            ..Pluck::default()
        },
        every,
        out,
        wav,
    })
}

pub fn run(raw: &[String]) -> Result<(), Box<dyn Error>> {
    if raw.iter().any(|word| word == "--help" || word == "-h") {
        println!("{HELP}");
        return Ok(());
    }
    let options = parse(raw)?;
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

    fn words(text: &str) -> Vec<String> {
        text.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn defaults_are_the_seed_reference() {
        let options = parse(&[]).unwrap();
        assert_eq!(options.config.bridge, FdStringConfig::REFERENCE.bridge);
        assert_eq!(options.config.thread, FdStringConfig::REFERENCE.thread);
        assert_eq!(options.config.time_step_s, 1.0 / 176_400.0);
        assert!(!options.first_mode);
    }

    #[test]
    fn lossless_and_layout_options_map_onto_the_model() {
        let options = parse(&words(
            "--lossless --thread-position-mm 42 --bridge off-beyond-thread --kb 1e9 \
             --excitation first-mode --oversample 8",
        ))
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
        let error = parse(&words("--thread-position-mm 60")).unwrap_err();
        assert!(error.0.contains("--thread-position-mm") && error.0.contains("30 to 45"));
        let error = parse(&words("--excitation strum")).unwrap_err();
        assert!(error.0.contains("pluck, first-mode"));
        let error = parse(&words("--thread off --bridge off-beyond-thread")).unwrap_err();
        assert!(error.0.contains("--thread on"));
        assert!(parse(&words("--seconds 0")).is_err());
    }

    #[test]
    fn writes_the_specified_csv_columns() {
        let directory =
            std::env::temp_dir().join(format!("javari-simulate-{}", std::process::id()));
        std::fs::create_dir_all(&directory).unwrap();
        let csv = directory.join("probe.csv");
        let wav = directory.join("probe.wav");
        let raw = vec![
            "--seconds".to_string(),
            "0.002".to_string(),
            "--every".to_string(),
            "4".to_string(),
            "--out".to_string(),
            csv.display().to_string(),
            "--wav".to_string(),
            wav.display().to_string(),
        ];
        run(&raw).unwrap();
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
