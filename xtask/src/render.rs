//! `cargo xtask render`: MIDI file (or the built-in demo scene) to a WAV file, through the same
//! engine the plugin runs (`javari_core::engine::render`).
//!
//! Options: `cargo xtask render --help`. The WAV file is mono, 32-bit float at full scale ±1. A
//! progress bar goes to stderr.

use crate::args::number_in;
use crate::plot::heatmap;
use clap::builder::PossibleValuesParser;
use clap::Parser;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use javari_core::analysis::power_spectrum;
use javari_core::engine::bowed_stability::bowed_stability;
use javari_core::engine::midi_file;
use javari_core::engine::pitch::note_to_hz;
use javari_core::engine::preset::{Preset, QUALITY_NAMES};
use javari_core::engine::render::ScoreAction;
use javari_core::engine::render::{render, render_with, rendered_length, RenderOptions, Score};
use javari_core::engine::wav::write_wav;
use javari_core::engine::{EngineEvent, EngineSettings, Instrument, VoiceTask};
use javari_core::tanpura::quality::Quality;
use rayon::prelude::*;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Parser)]
pub struct RenderArgs {
    /// Standard MIDI file; without it the built-in demo scene is rendered.
    #[arg(long, value_name = "FILE")]
    midi: Option<PathBuf>,
    /// Preset file (presets/*.toml); default: the classic settings.
    #[arg(long, value_name = "FILE")]
    preset: Option<PathBuf>,
    /// Output WAV file; default out/demo.wav, or out/<midi name>.wav.
    #[arg(long, value_name = "FILE.wav")]
    out: Option<PathBuf>,
    /// Output sample rate, Hz (8000 to 192000).
    #[arg(long, value_name = "HZ", default_value_t = 44_100.0,
          value_parser = number_in(8_000.0, 192_000.0))]
    sample_rate: f64,
    /// Samples per process call, as a host's buffer size (1 to 65536).
    #[arg(long, value_name = "N", default_value_t = 512, value_parser = number_in(1usize, 65_536))]
    block_size: usize,
    /// Quality tier; `preset` keeps the preset's own (reference without a preset).
    #[arg(long, value_name = "TIER", default_value = "preset",
          value_parser = PossibleValuesParser::new(QUALITY_NAMES.into_iter().chain(["preset"])))]
    quality: String,
    /// Seconds rendered after the last event (0 to 60).
    #[arg(long, value_name = "S", default_value_t = 3.0, value_parser = number_in(0.0, 60.0))]
    tail_seconds: f64,
    /// Also write a spectrogram of the result as a PNG.
    #[arg(long, value_name = "FILE.png")]
    plot: Option<PathBuf>,
    /// Threads that run the voices (1 to 256; default: every core). The output is bit-identical
    /// for any number.
    #[arg(long, value_name = "N", value_parser = number_in(1usize, 256))]
    jobs: Option<usize>,
}

pub fn run(args: RenderArgs) -> Result<(), Box<dyn std::error::Error>> {
    let RenderArgs {
        midi,
        preset: preset_path,
        out,
        sample_rate: sample_rate_hz,
        block_size,
        quality,
        tail_seconds: tail_s,
        plot,
        jobs,
    } = args;
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let quality = Quality::from_name(&quality);

    let (score, default_out) = match &midi {
        Some(path) => {
            let stem = path
                .file_stem()
                .map_or("render".into(), |stem| stem.to_string_lossy().into_owned());
            (
                midi_file::load(path)?,
                PathBuf::from(format!("out/{stem}.wav")),
            )
        }
        None => (Score::demo(), PathBuf::from("out/demo.wav")),
    };
    let out = out.unwrap_or(default_out);
    let mut settings = match &preset_path {
        Some(path) => Preset::load(path)?.settings,
        None => EngineSettings::default(),
    };
    if let Some(quality) = quality {
        settings.voice.quality = quality;
    }
    warn_if_bowed_preset_is_unstable(&settings, &score);
    let options = RenderOptions {
        sample_rate_hz,
        block_size,
        tail_s,
        ..RenderOptions::default()
    };

    let total = rendered_length(&score, &options);
    eprintln!(
        "rendering {} ({:.1} s at {} Hz, {} quality, {jobs} thread{}) to {}",
        midi.as_deref()
            .map_or("the demo scene".to_string(), |path| path
                .display()
                .to_string()),
        total as f64 / sample_rate_hz,
        sample_rate_hz,
        settings.voice.quality.name(),
        if jobs == 1 { "" } else { "s" },
        out.display()
    );
    let started = Instant::now();
    let bar = progress_bar(total);
    let signal = render_on(jobs, &settings, &score, &options, &mut |done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let elapsed_s = started.elapsed().as_secs_f64();
    write_wav(&out, &signal, sample_rate_hz)?;
    let peak = signal.iter().fold(0.0f32, |peak, x| peak.max(x.abs()));
    eprintln!(
        "wrote {}: {} samples, peak {:.1} dBFS, {:.2} s compute, real-time factor {:.2}",
        out.display(),
        signal.len(),
        20.0 * f64::from(peak).log10(),
        elapsed_s,
        (signal.len() as f64 / sample_rate_hz) / elapsed_s
    );
    if let Some(plot) = plot {
        write_spectrogram(&plot, &signal, sample_rate_hz)?;
        eprintln!("wrote the spectrogram {}", plot.display());
    }
    Ok(())
}

/// [`render`] with the voices of each segment on `jobs` threads (rayon); one job renders on this
/// thread exactly as the plugin does. The voices' outputs are summed in a fixed order
/// ([`javari_core::engine::Engine::process_with`]), so the signal does not depend on `jobs`.
fn render_on(
    jobs: usize,
    settings: &EngineSettings,
    score: &Score,
    options: &RenderOptions,
    progress: &mut (dyn FnMut(usize, usize) + Send),
) -> Result<Vec<f32>, rayon::ThreadPoolBuildError> {
    if jobs <= 1 {
        return Ok(render(settings, score, options, progress));
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build()?;
    // The whole render runs inside the pool, so that handing out a segment's voices is a cheap
    // fork-join among its threads.
    Ok(pool.install(|| {
        let runner = |tasks: &mut [VoiceTask<'_>]| tasks.par_iter_mut().for_each(VoiceTask::run);
        render_with(settings, score, options, &runner, progress)
    }))
}

/// Frame length and hop of the spectrogram, samples.
const SPECTROGRAM_FRAME: usize = 2048;
const SPECTROGRAM_COLUMNS: usize = 400;
/// Frequency rows (linear, 0 Hz to the top frequency) and the dynamic range shown, dB.
const SPECTROGRAM_ROWS: usize = 256;
const SPECTROGRAM_RANGE_DB: f64 = 90.0;

/// A spectrogram of `signal` (Hann-windowed 2048-sample frames, magnitude in dB relative to the
/// loudest bin, up to 10 kHz or Nyquist) as a PNG heat map.
fn write_spectrogram(
    path: &std::path::Path,
    signal: &[f32],
    sample_rate_hz: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let samples: Vec<f64> = signal.iter().map(|&x| f64::from(x)).collect();
    let top_hz = (0.5 * sample_rate_hz).min(10_000.0);
    let bin_hz = sample_rate_hz / SPECTROGRAM_FRAME as f64;
    let hop = (samples.len().saturating_sub(SPECTROGRAM_FRAME) / SPECTROGRAM_COLUMNS).max(1);
    let columns =
        (samples.len().saturating_sub(SPECTROGRAM_FRAME) / hop + 1).min(SPECTROGRAM_COLUMNS);
    let mut levels = vec![f64::MIN; SPECTROGRAM_ROWS * columns];
    for column in 0..columns {
        let spectrum = power_spectrum(&samples, column * hop, SPECTROGRAM_FRAME, SPECTROGRAM_FRAME);
        for row in 0..SPECTROGRAM_ROWS {
            let frequency = top_hz * (row as f64 + 0.5) / SPECTROGRAM_ROWS as f64;
            let bin = ((frequency / bin_hz).round() as usize).min(spectrum.len() - 1);
            levels[row * columns + column] = 10.0 * (spectrum[bin] + 1e-30).log10();
        }
    }
    let loudest = levels.iter().cloned().fold(f64::MIN, f64::max);
    let duration_s = samples.len() as f64 / sample_rate_hz;
    heatmap(
        path,
        &levels,
        SPECTROGRAM_ROWS,
        columns,
        (0.0, duration_s),
        (0.0, top_hz),
        (loudest - SPECTROGRAM_RANGE_DB, loudest),
        (
            "Spectrogram (dB re the loudest bin)",
            "time (s)",
            "frequency (Hz)",
        ),
    )?;
    Ok(())
}

/// For a bowed preset: the stability margin of its Helmholtz motion (Woodhouse's analysis,
/// `javari_core::stability::voice_link`) at every note the score plays, with the preset's bow
/// controls; a warning for each note where it is unstable.
fn warn_if_bowed_preset_is_unstable(settings: &EngineSettings, score: &Score) {
    if settings.instrument != Instrument::Bowed {
        return;
    }
    let mut notes: Vec<u8> = score
        .events
        .iter()
        .filter_map(|event| match event.action {
            ScoreAction::Engine(EngineEvent::NoteOn { note, velocity }) if velocity > 0.0 => {
                Some(note)
            }
            _ => None,
        })
        .collect();
    notes.sort_unstable();
    notes.dedup();
    for note in notes {
        let check = bowed_stability(&settings.bowed, note);
        match check {
            Ok(margin) if !margin.stable => eprintln!(
                "warning: the bowed preset's Helmholtz motion is unstable at note {note} \
                 ({:.1} Hz): bow force {:.3} N is above the critical {:.3} N (margin {:.2}); \
                 expect a raucous or subharmonic sound",
                note_to_hz(note),
                margin.bow_force_n,
                margin.critical_bow_force_n.unwrap_or(0.0),
                margin.margin
            ),
            Ok(_) => {}
            Err(error) => eprintln!("warning: no stability margin for note {note}: {error}"),
        }
    }
}

/// The render's progress bar on stderr (indicatif), hidden when stderr is not a terminal (a log
/// file or CI gets the summary lines only).
fn progress_bar(total: usize) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("[{bar:40}] {percent:>3}%  {eta} left")
            .expect("a valid template")
            .progress_chars("#> "),
    );
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_number_of_jobs_renders_the_same_bits() {
        // Overlapping notes on several strings, so that several voices share each segment.
        let mut score = Score::default();
        for (index, note) in [43u8, 48, 52, 55, 36, 60].into_iter().enumerate() {
            score.note(0.02 * index as f64, 0.2, note, 0.9);
        }
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Draft;
        let options = RenderOptions {
            tail_s: 0.1,
            block_size: 256,
            ..RenderOptions::default()
        };
        let bits = |jobs| {
            let signal = render_on(jobs, &settings, &score, &options, &mut |_, _| {}).unwrap();
            signal.iter().map(|x| x.to_bits()).collect::<Vec<u32>>()
        };
        let one = bits(1);
        assert!(one.iter().any(|&x| f32::from_bits(x) != 0.0));
        for jobs in [2, 3, 8] {
            assert!(one == bits(jobs), "{jobs} jobs differ from one");
        }
    }
}
