//! `cargo xtask render`: MIDI file (or the built-in demo scene) to a WAV file, through the same
//! engine the plugin runs (`javari_core::engine::render`).
//!
//! Options:
//!   --midi FILE          standard MIDI file; without it the built-in demo scene is rendered
//!   --preset FILE        preset file (presets/*.toml); default: the classic settings
//!   --out FILE.wav       default out/demo.wav, or out/<midi name>.wav
//!   --sample-rate HZ     8000–192000, default 44100
//!   --block-size N       1–65536 samples per process call, default 512
//!   --quality TIER       draft | live | studio | reference, or preset (default: the preset's
//!                        own, else reference)
//!   --tail-seconds S     0–60 s rendered after the last event, default 3
//!   --plot FILE.png      spectrogram of the result (needs the plot module)
//!
//! The WAV file is mono, 32-bit float at full scale ±1. A progress bar goes to stderr.

use crate::args::Args;
use javari_core::engine::midi_file;
use javari_core::engine::preset::{Preset, QUALITY_NAMES};
use javari_core::engine::render::{render, rendered_length, RenderOptions, Score};
use javari_core::engine::wav::write_wav;
use javari_core::engine::EngineSettings;
use javari_core::quality::Quality;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

pub fn run(raw: &[String]) -> Result<(), Box<dyn std::error::Error>> {
    let mut args = Args::parse(raw, &[])?;
    let midi = args.text("midi").map(PathBuf::from);
    let preset_path = args.text("preset").map(PathBuf::from);
    let out = args.text("out").map(PathBuf::from);
    let sample_rate_hz: f64 = args.number("sample-rate", 44_100.0, 8_000.0, 192_000.0)?;
    let block_size: usize = args.number("block-size", 512, 1, 65_536)?;
    // "preset" keeps the preset's own quality.
    let mut quality_choices = QUALITY_NAMES.to_vec();
    quality_choices.push("preset");
    let quality = args.choice("quality", "preset", &quality_choices)?;
    let quality = Quality::from_name(quality);
    let tail_s: f64 = args.number("tail-seconds", 3.0, 0.0, 60.0)?;
    let plot = args.text("plot").map(PathBuf::from);
    args.finish()?;

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
    let options = RenderOptions {
        sample_rate_hz,
        block_size,
        tail_s,
        ..RenderOptions::default()
    };

    let total = rendered_length(&score, &options);
    eprintln!(
        "rendering {} ({:.1} s at {} Hz, {} quality) to {}",
        midi.as_deref()
            .map_or("the demo scene".to_string(), |path| path
                .display()
                .to_string()),
        total as f64 / sample_rate_hz,
        sample_rate_hz,
        settings.voice.quality.name(),
        out.display()
    );
    let started = Instant::now();
    let mut bar = ProgressBar::new();
    let signal = render(&settings, &score, &options, &mut |done, total| {
        bar.update(done, total)
    });
    bar.finish();
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
        return Err(format!(
            "option `--plot {}`: the spectrogram plotter is not available in this build yet",
            plot.display()
        )
        .into());
    }
    Ok(())
}

/// A one-line progress bar on stderr, redrawn when the percentage changes.
struct ProgressBar {
    last_percent: Option<usize>,
    started: Instant,
}

impl ProgressBar {
    const WIDTH: usize = 40;

    fn new() -> Self {
        Self {
            last_percent: None,
            started: Instant::now(),
        }
    }

    fn update(&mut self, done: usize, total: usize) {
        let percent = (done * 100).checked_div(total).unwrap_or(100);
        if self.last_percent == Some(percent) {
            return;
        }
        self.last_percent = Some(percent);
        let filled = percent * Self::WIDTH / 100;
        let elapsed = self.started.elapsed().as_secs_f64();
        let remaining = if done > 0 {
            elapsed * (total - done) as f64 / done as f64
        } else {
            0.0
        };
        eprint!(
            "\r[{}{}] {percent:3}%  {remaining:5.1} s left",
            "#".repeat(filled),
            " ".repeat(Self::WIDTH - filled)
        );
        let _ = std::io::stderr().flush();
    }

    fn finish(&self) {
        eprintln!();
    }
}
