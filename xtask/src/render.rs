//! `cargo xtask render`: MIDI file (or the built-in demo scene) to a WAV file, through the same
//! engine the plugin runs (`javari_core::engine::render`).
//!
//! Options: `cargo xtask render --help`. The WAV file is mono, 32-bit float at full scale ±1.
//!
//! Bounded work, clear errors:
//! - the MIDI file's warnings (cut-short tracks, unreadable events, notes that never end;
//!   `javari_core::engine::midi_file`) are printed before anything else; a file it refuses
//!   (meaningless time, no notes) is an error;
//! - a score none of whose notes the instrument can play is refused, and notes it cannot play are
//!   named in a warning;
//! - the rendered length is announced before the work starts; a score longer than
//!   `--max-seconds` (default one hour) is refused with where its time goes, never cut;
//! - samples are streamed block by block to a file without a name in the output's directory
//!   (Linux `O_TMPFILE`), so memory does not grow with the length; only when the render
//!   succeeded is the file given a name and renamed onto the output, so a failed, interrupted or
//!   killed render (even by SIGKILL) leaves nothing on disk and the previous output untouched.
//!   Where the file system cannot make an unnamed file, a hidden named one
//!   (`.NAME.partial-XXXXXX`) is used instead, removed on any failure; only a render killed
//!   outright can then leave it behind, never a damaged output;
//! - a render that is silent from start to end is an error rather than a quiet WAV of zeros.
//!
//! Progress goes to stderr: an indicatif bar on a terminal, a plain line every 10 % otherwise (a
//! log gets lines, not carriage returns).

use crate::args::number_in;
use crate::calibration_cache::{calibration, CalibrationCache, Source};
use crate::plot::heatmap;
use clap::builder::PossibleValuesParser;
use clap::Parser;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use javari_core::analysis::power_spectrum;
use javari_core::engine::bowed_stability::bowed_stability;
use javari_core::engine::midi_file::{self, format_time, MidiScore};
use javari_core::engine::pitch::note_to_hz;
use javari_core::engine::preset::{Preset, QUALITY_NAMES};
use javari_core::engine::render::{
    calibration_need_samples, calibration_requests, render_blocks_scheduled, rendered_length,
    RenderOptions, Score,
};
use javari_core::engine::wav::read_wav;
use javari_core::engine::{EngineSettings, Instrument, VoiceRunner, VoiceTask};
use javari_core::tanpura::as_played::{with_plucks_at_once, Calibration};
use javari_core::tanpura::quality::Quality;
use rayon::prelude::*;
use std::io::{BufWriter, IsTerminal};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
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
    /// Samples per process call, as a host's buffer size (1 to 65536). The output is the same
    /// for any; long blocks let each voice run as one long task a segment on the threads
    /// (`docs/performance.md`, stop 68).
    #[arg(long, value_name = "N", default_value_t = RENDER_BLOCK, value_parser = number_in(1usize, 65_536))]
    block_size: usize,
    /// Quality tier; `preset` keeps the preset's own (reference without a preset).
    #[arg(long, value_name = "TIER", default_value = "preset",
          value_parser = PossibleValuesParser::new(QUALITY_NAMES.into_iter().chain(["preset"])))]
    quality: String,
    /// Seconds rendered after the last event (0 to 60).
    #[arg(long, value_name = "S", default_value_t = 3.0, value_parser = number_in(0.0, 60.0))]
    tail_seconds: f64,
    /// Sets one preset key for this render, as written in a preset file (repeatable; every key
    /// of `presets/*.toml`, e.g. `--set drone_pattern=five --set reference_a4_hz=432
    /// --set drone_string_fine_tune_cents=[0,-2] --set stereo_width=0.8`); applied after
    /// `--preset`.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = key_value)]
    set: Vec<(String, String)>,
    /// Write the stereo image (two channels, as the plugin plays: the strings spread by the
    /// preset's `stereo_width`; their mid is the mono output) instead of the mono output.
    #[arg(long)]
    stereo: bool,
    /// Also write a spectrogram of the result as a PNG (of the mid signal when stereo).
    #[arg(long, value_name = "FILE.png")]
    plot: Option<PathBuf>,
    /// Also write the result's long-term spectrum as a PNG (the radiated spectrum when the
    /// output is radiated): power averaged over the whole render, dB re its peak, to 16 kHz.
    #[arg(long, value_name = "FILE.png")]
    spectrum: Option<PathBuf>,
    /// Threads that measure the strings' calibrations and run the voices (1 to 256; default: every
    /// core), besides the one that drives the render when more than one; a calibration renders up
    /// to N of a check's plucks at once, on threads of its own. The output is bit-identical for
    /// any number.
    #[arg(long, value_name = "N", value_parser = number_in(1usize, 256))]
    jobs: Option<usize>,
    /// Longest render allowed, s (1 to 86400; default one hour): a score whose rendered length
    /// (its last event plus the tail) is longer is refused before any work, with where its time
    /// goes; it is never cut short.
    #[arg(long, value_name = "S", default_value_t = 3600.0, value_parser = number_in(1.0, 86_400.0))]
    max_seconds: f64,
    /// Measure every string's as-played calibration afresh, neither reading nor keeping
    /// calibrations in `target/calibration-cache/` (kept there by default, per version of
    /// `core/`, so that rendering the same strings again skips their calibration renders).
    #[arg(long)]
    no_calibration_cache: bool,
}

/// The render's default block: offline, a segment's voices run as one task each through the
/// control ticks that change nothing (`Engine::process_with`), up to the block's end, so a long
/// block lets the threads share the voices of a segment evenly (the demo with its calibrations
/// read back, on two cores: 7.4–7.6 s at 512 samples, 6.4–6.6 s at 32768; stop 68).
pub(crate) const RENDER_BLOCK: usize = 32_768;

/// Largest WAV data chunk: its length field has 32 bits.
const WAV_MAX_DATA_BYTES: u64 = u32::MAX as u64 - 44;
/// Bytes per sample of the output (mono 32-bit float).
const WAV_BYTES_PER_SAMPLE: u64 = 4;

pub fn run(args: RenderArgs) -> Result<(), Box<dyn std::error::Error>> {
    let RenderArgs {
        midi,
        preset: preset_path,
        out,
        sample_rate: sample_rate_hz,
        block_size,
        quality,
        tail_seconds: tail_s,
        set,
        stereo,
        plot,
        spectrum,
        jobs,
        max_seconds,
        no_calibration_cache,
    } = args;
    let channels = if stereo { 2 } else { 1 };
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let quality = Quality::from_name(&quality);

    let (read, default_out) = match &midi {
        Some(path) => {
            let stem = path
                .file_stem()
                .map_or("render".into(), |stem| stem.to_string_lossy().into_owned());
            (
                Some(midi_file::load(path)?),
                PathBuf::from(format!("out/{stem}.wav")),
            )
        }
        None => (None, PathBuf::from("out/demo.wav")),
    };
    let source = midi
        .as_deref()
        .map_or("the demo scene".to_string(), |path| {
            path.display().to_string()
        });
    if let Some(read) = &read {
        for warning in &read.warnings {
            eprintln!("warning: {source}: {warning}");
        }
    }
    let score = read
        .as_ref()
        .map_or_else(Score::demo, |read| read.score.clone());
    let out = out.unwrap_or(default_out);
    let preset = match &preset_path {
        Some(path) => Preset::load(path)?,
        None => Preset {
            name: "default".to_string(),
            settings: EngineSettings::default(),
        },
    };
    let mut settings = if set.is_empty() {
        preset.settings
    } else {
        preset.with_overrides(&set)?.settings
    };
    if let Some(quality) = quality {
        settings.voice.quality = quality;
    }
    check_playable_notes(&settings, &score, &source)?;
    warn_if_bowed_preset_is_unstable(&settings, &score);
    let options = RenderOptions {
        sample_rate_hz,
        block_size,
        channels,
        tail_s,
        ..RenderOptions::default()
    };

    let total = rendered_length(&score, &options);
    let length_s = score.end_s + tail_s;
    check_length(
        length_s,
        max_seconds,
        (sample_rate_hz, channels),
        &source,
        read.as_ref(),
    )?;
    eprintln!(
        "rendering {source} ({:.1} s at {} Hz, {} quality, {jobs} thread{}) to {}",
        total as f64 / sample_rate_hz,
        sample_rate_hz,
        settings.voice.quality.name(),
        if jobs == 1 { "" } else { "s" },
        out.display()
    );
    let started = Instant::now();
    let cache = if no_calibration_cache {
        None
    } else {
        CalibrationCache::for_workspace()
    };
    let mut progress = Progress::new(total, sample_rate_hz);
    let mut wav = PendingWav::create(&out, sample_rate_hz, channels)?;
    let mut peak = 0.0f32;
    let mut written = 0usize;
    let tuned = render_on(
        jobs,
        &settings,
        &score,
        &options,
        cache.as_ref(),
        &mut |block| {
            peak = block.iter().fold(peak, |peak, x| peak.max(x.abs()));
            written += block.len() / channels;
            progress.update(written);
            wav.write(block)
        },
    )?;
    progress.finish();
    if let Some(summary) = tuning_summary(&tuned, jobs) {
        eprintln!("{summary}");
    }
    if peak == 0.0 {
        return Err(format!(
            "{source}: the render is silent from start to end ({:.1} s), so no file is written; \
             check that the preset's instrument plays the file's notes",
            total as f64 / sample_rate_hz
        )
        .into());
    }
    wav.commit()?;
    let elapsed_s = started.elapsed().as_secs_f64();
    eprintln!(
        "wrote {}: {written} samples ({channels} channel{}), peak {:.1} dBFS, {:.2} s compute, real-time factor {:.2}",
        out.display(),
        if channels == 1 { "" } else { "s" },
        20.0 * f64::from(peak).log10(),
        elapsed_s,
        (written as f64 / sample_rate_hz) / elapsed_s
    );
    if plot.is_some() || spectrum.is_some() {
        let (signal, _) = read_wav(&out)?;
        if let Some(plot) = plot {
            write_spectrogram(&plot, &signal, sample_rate_hz)?;
            eprintln!("wrote the spectrogram {}", plot.display());
        }
        if let Some(path) = spectrum {
            write_long_term_spectrum(&path, &signal, sample_rate_hz, &settings)?;
            eprintln!("wrote the long-term spectrum {}", path.display());
        }
    }
    Ok(())
}

/// A `--set` argument: `KEY=VALUE`.
fn key_value(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((key, value)) if !key.trim().is_empty() => {
            Ok((key.trim().to_string(), value.trim().to_string()))
        }
        _ => Err(format!(
            "`{text}` is not KEY=VALUE (a preset key, e.g. drone_pattern=five)"
        )),
    }
}

/// Refuses a render longer than `max_seconds` or than a WAV file holds, saying where a MIDI
/// file's time goes.
fn check_length(
    length_s: f64,
    max_seconds: f64,
    (sample_rate_hz, channels): (f64, usize),
    source: &str,
    read: Option<&MidiScore>,
) -> Result<(), String> {
    let why = read.map_or(String::new(), |read| {
        format!(" ({})", read.describe_length())
    });
    if length_s.is_nan() || length_s > max_seconds {
        return Err(format!(
            "{source} would render {} with the tail{why}, longer than --max-seconds {max_seconds}; \
             raise --max-seconds to render it all",
            format_time(length_s)
        ));
    }
    let bytes = length_s * sample_rate_hz * (channels * WAV_BYTES_PER_SAMPLE as usize) as f64;
    if bytes > WAV_MAX_DATA_BYTES as f64 {
        return Err(format!(
            "{source} would render {} at {sample_rate_hz} Hz, {:.1} GB of samples, more than a \
             WAV file holds (4 GB); lower --sample-rate or shorten the file",
            format_time(length_s),
            bytes / 1e9
        ));
    }
    Ok(())
}

/// Refuses a score none of whose notes the tanpura can play (they would render silence), and
/// warns about the notes it cannot play. The bowed string and the drone play any note they get.
fn check_playable_notes(
    settings: &EngineSettings,
    score: &Score,
    source: &str,
) -> Result<(), String> {
    if settings.instrument != Instrument::Tanpura || settings.drone.enabled {
        return Ok(());
    }
    let notes = score.played_notes();
    let unplayable: Vec<u8> = notes
        .iter()
        .copied()
        .filter(|&note| settings.tuning.playable_note_hz(note).is_none())
        .collect();
    if unplayable.is_empty() {
        return Ok(());
    }
    let (lowest, highest) = (
        unplayable.iter().min().copied().unwrap_or(0),
        unplayable.iter().max().copied().unwrap_or(0),
    );
    let what = format!(
        "{} of its {} notes (from note {lowest}, {:.1} Hz, to note {highest}, {:.1} Hz) lie \
         outside the tanpura's range, notes 16 to 95 (20 to 2000 Hz), and are not played",
        unplayable.len(),
        notes.len(),
        settings.tuning.note_hz(lowest),
        settings.tuning.note_hz(highest)
    );
    if unplayable.len() == notes.len() {
        return Err(format!("{source}: nothing to play: {what}"));
    }
    eprintln!("warning: {source}: {what}");
    Ok(())
}

/// Where a [`PendingWav`]'s samples are until the commit.
enum Temporary {
    /// A file without a name (`O_TMPFILE`): nothing to clean up, whatever ends the process. The
    /// handle keeps the file open for the commit's `linkat`.
    #[cfg(target_os = "linux")]
    Unnamed {
        handle: std::fs::File,
        directory: PathBuf,
    },
    /// A hidden named file, removed when dropped without a commit.
    Named(tempfile::TempPath),
}

/// A WAV file being written (see the module doc): samples go to an unnamed file in the output's
/// directory (or a hidden named one), which [`PendingWav::commit`] names and renames onto the
/// output. Dropped without a commit (an error, a panic), nothing is left and the output is
/// untouched; killed, the unnamed file vanishes with the process.
struct PendingWav {
    writer: hound::WavWriter<BufWriter<std::fs::File>>,
    temporary: Temporary,
    out: PathBuf,
    name: String,
}

/// A file without a name in `directory`, with the permissions any new file gets.
#[cfg(target_os = "linux")]
fn unnamed_file(directory: &Path) -> Option<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .mode(0o666)
        .custom_flags(libc::O_TMPFILE)
        .open(directory)
        .ok()
}

/// Gives the unnamed file behind `handle` the name `target` (`linkat` of `/proc/self/fd/N`).
#[cfg(target_os = "linux")]
fn name_unnamed_file(handle: &std::fs::File, target: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::io::AsRawFd;
    let source = std::ffi::CString::new(format!("/proc/self/fd/{}", handle.as_raw_fd()))?;
    let target = std::ffi::CString::new(target.as_os_str().as_bytes())?;
    // SAFETY: both paths are NUL-terminated C strings that outlive the call.
    let result = unsafe {
        libc::linkat(
            libc::AT_FDCWD,
            source.as_ptr(),
            libc::AT_FDCWD,
            target.as_ptr(),
            libc::AT_SYMLINK_FOLLOW,
        )
    };
    if result == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

impl PendingWav {
    fn create(out: &Path, sample_rate_hz: f64, channels: usize) -> Result<Self, String> {
        let directory = match out.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent,
            _ => Path::new("."),
        };
        std::fs::create_dir_all(directory)
            .map_err(|error| format!("cannot create {}: {error}", directory.display()))?;
        let name = out.file_name().map_or("render.wav".into(), |name| {
            name.to_string_lossy().into_owned()
        });
        let spec = hound::WavSpec {
            channels: channels.clamp(1, 2) as u16,
            sample_rate: sample_rate_hz.round() as u32,
            bits_per_sample: 32,
            sample_format: hound::SampleFormat::Float,
        };
        let (file, temporary) = match Self::unnamed(directory) {
            Some((file, temporary)) => (file, temporary),
            None => {
                let mut builder = tempfile::Builder::new();
                let prefix = format!(".{name}.partial-");
                builder.prefix(&prefix);
                // A temporary file is private (0600) by default; the output gets the
                // permissions any new file gets (0666 less the umask), as `File::create` would
                // give it.
                #[cfg(unix)]
                builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
                let file = builder.tempfile_in(directory).map_err(|error| {
                    format!("cannot create a file in {}: {error}", directory.display())
                })?;
                let (file, path) = file.into_parts();
                (file, Temporary::Named(path))
            }
        };
        let writer = hound::WavWriter::new(BufWriter::new(file), spec)
            .map_err(|error| format!("cannot write {}: {error}", out.display()))?;
        Ok(Self {
            writer,
            temporary,
            out: out.to_path_buf(),
            name,
        })
    }

    #[cfg(target_os = "linux")]
    fn unnamed(directory: &Path) -> Option<(std::fs::File, Temporary)> {
        let file = unnamed_file(directory)?;
        let handle = file.try_clone().ok()?;
        Some((
            file,
            Temporary::Unnamed {
                handle,
                directory: directory.to_path_buf(),
            },
        ))
    }

    #[cfg(not(target_os = "linux"))]
    fn unnamed(_directory: &Path) -> Option<(std::fs::File, Temporary)> {
        None
    }

    /// True when the samples go to a file without a name.
    #[cfg(test)]
    fn is_unnamed(&self) -> bool {
        !matches!(self.temporary, Temporary::Named(_))
    }

    fn write(&mut self, samples: &[f32]) -> Result<(), String> {
        for &sample in samples {
            self.writer
                .write_sample(sample)
                .map_err(|error| format!("cannot write {}: {error}", self.out.display()))?;
        }
        Ok(())
    }

    /// Completes the WAV header and puts the file in place of the output.
    fn commit(self) -> Result<(), String> {
        let fail =
            |error: &dyn std::fmt::Display| format!("cannot write {}: {error}", self.out.display());
        self.writer.finalize().map_err(|error| fail(&error))?;
        match self.temporary {
            Temporary::Named(path) => path.persist(&self.out).map_err(|error| fail(&error)),
            #[cfg(target_os = "linux")]
            Temporary::Unnamed { handle, directory } => {
                // A fresh hidden name beside the output, then an atomic rename onto it.
                let named = tempfile::Builder::new()
                    .prefix(&format!(".{}.partial-", self.name))
                    .make_in(&directory, |path| name_unnamed_file(&handle, path))
                    .map_err(|error| fail(&error))?;
                named
                    .into_temp_path()
                    .persist(&self.out)
                    .map_err(|error| fail(&error))
            }
        }
    }
}

/// Render progress on stderr: an indicatif bar on a terminal; elsewhere (a log, CI) a plain line
/// at every tenth of the work, so that a log never fills with carriage-return updates.
enum Progress {
    Bar(ProgressBar),
    Lines {
        total: usize,
        sample_rate_hz: f64,
        next_tenth: usize,
    },
}

impl Progress {
    fn new(total: usize, sample_rate_hz: f64) -> Self {
        if std::io::stderr().is_terminal() {
            let bar =
                ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template("[{bar:40}] {percent:>3}%  {eta} left")
                    .expect("a valid template")
                    .progress_chars("#> "),
            );
            Progress::Bar(bar)
        } else {
            Progress::Lines {
                total,
                sample_rate_hz,
                next_tenth: 1,
            }
        }
    }

    fn update(&mut self, done: usize) {
        match self {
            Progress::Bar(bar) => bar.set_position(done as u64),
            Progress::Lines {
                total,
                sample_rate_hz,
                next_tenth,
            } => {
                if let Some(line) = progress_line(done, *total, *sample_rate_hz, next_tenth) {
                    eprintln!("{line}");
                }
            }
        }
    }

    fn finish(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}

/// The plain progress line due when `done` of `total` samples are rendered, if it passed the
/// next tenth (one line per call even when a block jumps several tenths); moves `next_tenth` on.
fn progress_line(
    done: usize,
    total: usize,
    sample_rate_hz: f64,
    next_tenth: &mut usize,
) -> Option<String> {
    let tenths = (done as u128 * 10 / total.max(1) as u128) as usize;
    if *next_tenth > 10 || tenths < *next_tenth {
        return None;
    }
    *next_tenth = tenths + 1;
    Some(format!(
        "rendered {}% ({:.1} of {:.1} s)",
        tenths * 10,
        done as f64 / sample_rate_hz,
        total as f64 / sample_rate_hz
    ))
}

/// One string's as-played calibration as a render took it: where it came from and how long it
/// took to read or measure.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tuned {
    calibration: Calibration,
    source: Source,
    seconds: f64,
}

/// Renders `score` with every string it plucks tuned by its sustained pitch as played
/// (`javari_core::tanpura::as_played`), the voices of each segment on a rayon pool; one job
/// renders on this thread exactly as the plugin does. The voices' outputs are summed in a fixed
/// order ([`javari_core::engine::Engine::process_with`]), so the signal does not depend on
/// `jobs`.
///
/// Each string's calibration is read from `cache` when an earlier run kept it, else measured and
/// kept, and handed to the engine just before the sample that first plucks the string
/// ([`render_blocks_scheduled`], [`calibration_need_samples`]), whatever `jobs` is. With one job
/// it is measured there. With `jobs` > 1 the pool has `jobs` threads for the calibrations and the
/// voices and one more, which drives the render: it hands out each segment's voices and takes
/// some of them, and when a string it is about to pluck is still being measured it waits, taking
/// no calibration itself, so that it resumes as soon as that one is done; each check of a
/// calibration renders up to `jobs` of its plucks at once, on threads of its own
/// (`as_played::with_plucks_at_once`: the same calibration to the bit). The calibrations are
/// queued in the order their strings are first plucked, so the render of the first notes
/// proceeds while the later strings are measured. (Stop 58 measured three ways on two cores: the
/// render on a thread outside the pool paid a pool hand-over per block, 0.79-0.81 s against
/// 0.41-0.44 s for the demo at the live tier with its calibrations read back; a render thread
/// that measured queued strings while it waited could be stuck in a long one while the render
/// could have gone on, 12.91-13.00 s against 11.72-12.39 s for the studio's first render.)
/// Returns the calibrations taken, in the order of
/// [`calibration_requests`].
pub(crate) fn render_on(
    jobs: usize,
    settings: &EngineSettings,
    score: &Score,
    options: &RenderOptions,
    cache: Option<&CalibrationCache>,
    emit: &mut (dyn FnMut(&[f32]) -> Result<(), String> + Send),
) -> Result<Vec<Tuned>, String> {
    let requests = calibration_requests(settings, score);
    let needed_at = calibration_need_samples(settings, score, options.sample_rate_hz, &requests);
    let measure = |index: usize| {
        let started = Instant::now();
        // A check's plucks render on `jobs` threads at most (one thread with one job).
        let (calibration, source) = with_plucks_at_once(jobs, || {
            calibration(cache, &requests[index], options.sample_rate_hz)
        });
        Tuned {
            calibration,
            source,
            seconds: started.elapsed().as_secs_f64(),
        }
    };
    let mut tuned: Vec<Option<Tuned>> = vec![None; requests.len()];
    if jobs <= 1 {
        let mut take = |index: usize| {
            let measured = measure(index);
            tuned[index] = Some(measured);
            measured.calibration
        };
        render_blocks_scheduled(settings, &needed_at, &mut take, score, options, None, emit)?;
        return Ok(tuned.into_iter().flatten().collect());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs + 1)
        .build()
        .map_err(|error| format!("cannot start {} threads: {error}", jobs + 1))?;
    let mut queue: Vec<usize> = (0..requests.len()).collect();
    queue.sort_by_key(|&index| (needed_at[index], index));
    let (sender, receiver) = crossbeam::channel::unbounded();
    // Set when the render fails: the strings not yet started are then not measured.
    let abandoned = AtomicBool::new(false);
    // The whole render runs inside the pool, so that handing out a segment's voices is a cheap
    // fork-join among its threads.
    let rendered = pool.install(|| {
        rayon::scope_fifo(|scope| {
            // First in, first out, for this thread and for the threads that steal them.
            for &index in &queue {
                let sender = sender.clone();
                let (measure, abandoned) = (&measure, &abandoned);
                scope.spawn_fifo(move |_| {
                    if abandoned.load(Ordering::Relaxed) {
                        return;
                    }
                    // Sent even if the measurement panics, so that the render never waits for a
                    // string that will not come; the scope then passes the panic on.
                    let measured = std::panic::catch_unwind(AssertUnwindSafe(|| measure(index)));
                    // The receiver outlives every job.
                    let _ = sender.send((index, measured.as_ref().ok().copied()));
                    if let Err(panic) = measured {
                        std::panic::resume_unwind(panic);
                    }
                });
            }
            let mut take = |index: usize| loop {
                if let Some(measured) = tuned[index] {
                    return measured.calibration;
                }
                let received = receiver.recv().expect("the sender outlives the render");
                match received {
                    (done, Some(measured)) => tuned[done] = Some(measured),
                    (done, None) => panic!("measuring the calibration of string {done} panicked"),
                }
            };
            let runner =
                |tasks: &mut [VoiceTask<'_>]| tasks.par_iter_mut().for_each(VoiceTask::run);
            let runner: VoiceRunner<'_> = &runner;
            let rendered = render_blocks_scheduled(
                settings,
                &needed_at,
                &mut take,
                score,
                options,
                Some(runner),
                emit,
            );
            abandoned.store(rendered.is_err(), Ordering::Relaxed);
            rendered
        })
    });
    // The scope has run every job: the strings the render ended before plucking are measured and
    // kept all the same, unless the render failed.
    drop(sender);
    for (done, measured) in receiver.try_iter() {
        tuned[done] = measured;
    }
    rendered?;
    Ok(tuned.into_iter().flatten().collect())
}

/// What the render's as-played tuning did, for the log: none when no string was tuned.
fn tuning_summary(tuned: &[Tuned], jobs: usize) -> Option<String> {
    if tuned.is_empty() {
        return None;
    }
    let cached = tuned
        .iter()
        .filter(|tuned| tuned.source == Source::Cached)
        .count();
    let largest = tuned
        .iter()
        .map(|tuned| tuned.calibration.offset_cents.abs())
        .fold(0.0, f64::max);
    let moved: Vec<f64> = tuned
        .iter()
        .map(|tuned| tuned.calibration.thread_offset_m)
        .filter(|&offset| offset != 0.0)
        .collect();
    let threads = if moved.is_empty() {
        String::new()
    } else {
        let largest_move_mm = moved.iter().fold(0.0f64, |a, b| a.max(b.abs())) * 1e3;
        format!(
            "; the jawari set on {} string{} by moving its thread at most {largest_move_mm:.2} mm",
            moved.len(),
            if moved.len() == 1 { "" } else { "s" }
        )
    };
    let kept = match cached {
        0 => String::new(),
        n if n == tuned.len() => {
            "; every calibration read from target/calibration-cache, measured by an earlier run"
                .to_string()
        }
        n => format!(
            "; {n} of the calibrations read from target/calibration-cache, measured by an \
             earlier run"
        ),
    };
    let seconds: f64 = tuned.iter().map(|tuned| tuned.seconds).sum();
    let alongside = if jobs > 1 {
        ", alongside the render"
    } else {
        ""
    };
    Some(format!(
        "tuned {} string{} by their sustained pitch as played ({seconds:.1} s of calibration \
         summed over the strings{alongside}; largest offset from the linearised tuning {largest:.1} \
         cents{threads}{kept})",
        tuned.len(),
        if tuned.len() == 1 { "" } else { "s" },
    ))
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

/// Frame of the long-term spectrum, samples (5.4 Hz bins at 44.1 kHz), hopped by half.
const LONG_TERM_FRAME: usize = 8192;
/// Highest frequency and lowest level the long-term spectrum shows.
const LONG_TERM_TOP_HZ: f64 = 16_000.0;
const LONG_TERM_RANGE_DB: f64 = 100.0;

/// The power spectrum of `signal` averaged over Hann-windowed frames (Welch), in dB re its
/// largest bin (floored at −100 dB), from the first bin up to 16 kHz (or Nyquist):
/// (frequency in Hz, level in dB) per bin.
fn long_term_spectrum(signal: &[f32], sample_rate_hz: f64) -> Vec<(f64, f64)> {
    let samples: Vec<f64> = signal.iter().map(|&x| f64::from(x)).collect();
    let hop = LONG_TERM_FRAME / 2;
    let frames = (samples.len().saturating_sub(LONG_TERM_FRAME) / hop + 1).max(1);
    let mut average = vec![0.0; LONG_TERM_FRAME / 2 + 1];
    for frame in 0..frames {
        let spectrum = power_spectrum(&samples, frame * hop, LONG_TERM_FRAME, LONG_TERM_FRAME);
        for (sum, power) in average.iter_mut().zip(spectrum) {
            *sum += power / frames as f64;
        }
    }
    let bin_hz = sample_rate_hz / LONG_TERM_FRAME as f64;
    let top_hz = LONG_TERM_TOP_HZ.min(0.5 * sample_rate_hz);
    let loudest = average.iter().cloned().fold(0.0, f64::max).max(1e-30);
    average
        .iter()
        .enumerate()
        .skip(1)
        .map(|(bin, power)| {
            (
                bin as f64 * bin_hz,
                10.0 * (power / loudest + 1e-30).log10(),
            )
        })
        .take_while(|(frequency, _)| *frequency <= top_hz)
        .map(|(frequency, level)| (frequency, level.max(-LONG_TERM_RANGE_DB)))
        .collect()
}

/// [`long_term_spectrum`] as a line plot at `path`.
fn write_long_term_spectrum(
    path: &std::path::Path,
    signal: &[f32],
    sample_rate_hz: f64,
    settings: &EngineSettings,
) -> Result<(), Box<dyn std::error::Error>> {
    let points = long_term_spectrum(signal, sample_rate_hz);
    let what = match (settings.instrument, settings.tanpura_output) {
        (Instrument::Bowed, _) => "bowed string",
        (Instrument::Tanpura, javari_core::engine::TanpuraOutput::Radiated) => "radiated sound",
        (Instrument::Tanpura, javari_core::engine::TanpuraOutput::Pickup) => "pickup force",
    };
    crate::plot::line_plot(
        path,
        &crate::plot::LinePlot {
            title: format!("Long-term spectrum of the {what} (dB re its peak)"),
            x_label: "frequency (Hz)".into(),
            y_label: "level (dB)".into(),
            y_scale: crate::plot::AxisScale::Linear,
            right_label: None,
            series: vec![crate::plot::Series::new(what, points, [40, 70, 160])],
        },
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
    let mut notes = score.played_notes();
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

#[cfg(test)]
mod tests {
    use super::*;
    use javari_core::engine::render::render_blocks_calibrated;

    /// The samples of `render_on` with `jobs` threads, and the calibrations it took.
    fn rendered_bits(
        jobs: usize,
        settings: &EngineSettings,
        score: &Score,
        options: &RenderOptions,
        cache: Option<&CalibrationCache>,
    ) -> (Vec<u32>, Vec<Calibration>) {
        let mut bits = Vec::new();
        let tuned = render_on(jobs, settings, score, options, cache, &mut |block| {
            bits.extend(block.iter().map(|x| x.to_bits()));
            Ok(())
        })
        .unwrap();
        (bits, tuned.iter().map(|tuned| tuned.calibration).collect())
    }

    #[test]
    fn every_number_of_jobs_renders_the_same_bits() {
        // Overlapping notes on several strings, so that several voices share each segment; the
        // later strings are measured while the first ones render.
        let mut score = Score::default();
        for (index, note) in [43u8, 48, 52, 55, 36, 60].into_iter().enumerate() {
            score.note(0.02 * index as f64, 0.2, note, 0.9);
        }
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Live;
        let options = RenderOptions {
            tail_s: 0.1,
            block_size: 256,
            ..RenderOptions::default()
        };
        let (one, calibrations) = rendered_bits(1, &settings, &score, &options, None);
        assert_eq!(calibrations.len(), 6, "every string tuned as played");
        assert!(one.iter().any(|&x| f32::from_bits(x) != 0.0));
        for jobs in [2, 3, 8] {
            let (bits, taken) = rendered_bits(jobs, &settings, &score, &options, None);
            assert!(one == bits, "{jobs} jobs differ from one");
            assert_eq!(taken, calibrations);
        }
        // The same samples as with every calibration given before the first block.
        let mut up_front = Vec::new();
        render_blocks_calibrated(
            &settings,
            &calibrations,
            &score,
            &options,
            None,
            &mut |block| {
                up_front.extend(block.iter().map(|x| x.to_bits()));
                Ok::<(), String>(())
            },
        )
        .unwrap();
        assert!(
            one == up_front,
            "a calibration handed over late changed the render"
        );
    }

    /// A render that fails (here, its output cannot be written) returns the error and does not
    /// go on measuring the strings it had queued for later.
    #[test]
    fn a_failed_render_stops_measuring_its_later_strings() {
        let mut score = Score::default();
        let notes = [36u8, 39, 42, 45, 48, 51, 54, 57, 60, 63];
        for (index, note) in notes.into_iter().enumerate() {
            score.note(1.0 + index as f64, 0.5, note, 0.8);
        }
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Live;
        let directory = tempfile::tempdir().unwrap();
        let cache = CalibrationCache::at(directory.path().to_path_buf(), "test");
        let options = RenderOptions::default();
        let mut blocks = 0;
        let failed = render_on(2, &settings, &score, &options, Some(&cache), &mut |_| {
            blocks += 1;
            if blocks * options.block_size > 44_100 + 2 * options.block_size {
                Err("disk full".to_string())
            } else {
                Ok(())
            }
        });
        assert_eq!(failed.unwrap_err(), "disk full");
        let measured = std::fs::read_dir(directory.path()).unwrap().count();
        assert!(
            (1..notes.len()).contains(&measured),
            "{measured} of {} strings measured",
            notes.len()
        );
    }

    /// A render keeps the calibrations it measured, exactly, and a second render of the same
    /// strings reads them instead of measuring.
    #[test]
    fn a_render_reads_back_the_calibrations_an_earlier_one_measured() {
        let mut score = Score::default();
        for (index, note) in [48u8, 55].into_iter().enumerate() {
            score.note(0.05 * index as f64, 0.2, note, 0.8);
        }
        let mut settings = EngineSettings::default();
        settings.voice.quality = Quality::Live;
        let options = RenderOptions {
            tail_s: 0.05,
            ..RenderOptions::default()
        };
        let directory = tempfile::tempdir().unwrap();
        let cache = CalibrationCache::at(directory.path().to_path_buf(), "test");
        let calibrate = |jobs, cache| rendered_bits(jobs, &settings, &score, &options, cache).1;
        let fresh = calibrate(1, None);
        let first = calibrate(2, Some(&cache));
        assert_eq!(fresh.len(), 2);
        assert_eq!(first, fresh);
        for calibration in &first {
            assert_eq!(
                cache.get(&calibration.request, 44_100.0),
                Some(*calibration)
            );
            // Marked, so that a calibration read back tells itself from a measured one.
            cache.put(&Calibration {
                offset_cents: calibration.offset_cents + 1.0,
                ..*calibration
            });
        }
        let second = calibrate(1, Some(&cache));
        for (second, first) in second.iter().zip(&first) {
            assert_eq!(second.offset_cents, first.offset_cents + 1.0);
        }
        // Without the cache, measured again.
        assert_eq!(calibrate(1, None), fresh);
    }

    /// A fresh directory for one test's files.
    fn scratch_directory(name: &str) -> PathBuf {
        let directory =
            std::env::temp_dir().join(format!("javari-render-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&directory);
        std::fs::create_dir_all(&directory).unwrap();
        directory
    }

    fn file_names(directory: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(directory)
            .unwrap()
            .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// A one-track MIDI file (480 ticks per beat) holding `events` after its header.
    fn midi_bytes(events: &[u8]) -> Vec<u8> {
        let mut bytes = b"MThd\0\0\0\x06\0\0\0\x01\x01\xe0MTrk".to_vec();
        bytes.extend_from_slice(&(events.len() as u32).to_be_bytes());
        bytes.extend_from_slice(events);
        bytes
    }

    /// Delta 0, note-on C3; 0.1 s (96 ticks) later its note-off; end of track.
    const SHORT_NOTE: &[u8] = b"\x00\x90\x30\x64\x60\x80\x30\x00\x00\xff\x2f\x00";

    fn render_args(midi: &Path, out: &Path, extra: &[&str]) -> RenderArgs {
        let mut line = vec![
            "render".to_string(),
            "--midi".to_string(),
            midi.display().to_string(),
            "--out".to_string(),
            out.display().to_string(),
            "--quality".to_string(),
            "live".to_string(),
            "--tail-seconds".to_string(),
            "0.1".to_string(),
            "--jobs".to_string(),
            "1".to_string(),
        ];
        line.extend(extra.iter().map(|arg| arg.to_string()));
        RenderArgs::try_parse_from(line).unwrap()
    }

    /// The withdrawn draft tier is refused by name, with the tiers there are.
    #[test]
    fn the_withdrawn_draft_tier_is_refused_with_the_tiers_there_are() {
        let error = RenderArgs::try_parse_from(["render", "--quality", "draft"]).unwrap_err();
        let message = error.to_string();
        assert!(message.contains("'draft'"), "{message}");
        assert!(
            message.contains("live, fine, studio, reference"),
            "{message}"
        );
    }

    #[test]
    fn an_abandoned_wav_leaves_the_previous_file_and_no_temporary_file() {
        let directory = scratch_directory("abandoned");
        let out = directory.join("take.wav");
        std::fs::write(&out, b"the previous render").unwrap();
        let mut wav = PendingWav::create(&out, 44_100.0, 1).unwrap();
        wav.write(&[0.5; 1000]).unwrap();
        assert_eq!(
            file_names(&directory).len(),
            if wav.is_unnamed() { 1 } else { 2 },
            "the temporary file is beside the output, or has no name"
        );
        drop(wav);
        assert_eq!(std::fs::read(&out).unwrap(), b"the previous render");
        assert_eq!(file_names(&directory), ["take.wav"]);

        let mut wav = PendingWav::create(&out, 44_100.0, 1).unwrap();
        wav.write(&[0.25, -0.5]).unwrap();
        wav.commit().unwrap();
        assert_eq!(read_wav(&out).unwrap(), (vec![0.25, -0.5], 44_100.0));
        assert_eq!(file_names(&directory), ["take.wav"]);
        // The output has the permissions of any new file, not a temporary file's.
        let created = directory.join("created");
        std::fs::File::create(&created).unwrap();
        let permissions = |path: &Path| std::fs::metadata(path).unwrap().permissions();
        assert_eq!(permissions(&out), permissions(&created));
        std::fs::remove_file(&created).unwrap();
        std::fs::remove_dir_all(&directory).unwrap();
    }

    #[test]
    fn the_long_term_spectrum_of_a_tone_peaks_at_its_frequency() {
        let rate = 44_100.0;
        let tone: Vec<f32> = (0..3 * 44_100)
            .map(|n| (2.0 * std::f64::consts::PI * 1000.0 * n as f64 / rate).sin() as f32)
            .collect();
        let spectrum = long_term_spectrum(&tone, rate);
        let (peak_hz, peak_db) = spectrum
            .iter()
            .cloned()
            .fold(
                (0.0, f64::MIN),
                |best, point| if point.1 > best.1 { point } else { best },
            );
        assert!(
            (peak_hz - 1000.0).abs() < rate / LONG_TERM_FRAME as f64,
            "{peak_hz} Hz"
        );
        assert_eq!(peak_db, 0.0);
        assert!(spectrum.last().unwrap().0 <= LONG_TERM_TOP_HZ);
        let far = spectrum.iter().find(|point| point.0 > 4000.0).unwrap();
        assert!(far.1 < -60.0, "{far:?}: a pure tone has nothing at 4 kHz");
    }

    #[test]
    fn a_render_killed_outright_leaves_nothing_behind() {
        let directory = scratch_directory("killed");
        let out = directory.join("take.wav");
        std::fs::write(&out, b"the previous render").unwrap();
        let mut wav = PendingWav::create(&out, 44_100.0, 1).unwrap();
        wav.write(&[0.5; 10_000]).unwrap();
        let unnamed = wav.is_unnamed();
        // No destructor runs, as when the process is killed.
        std::mem::forget(wav);
        assert_eq!(std::fs::read(&out).unwrap(), b"the previous render");
        if unnamed {
            assert_eq!(file_names(&directory), ["take.wav"]);
        } else {
            println!("this file system makes no unnamed files: a hidden one stays behind");
        }
        std::fs::remove_dir_all(&directory).unwrap();
    }

    #[test]
    fn the_streamed_wav_has_the_bytes_of_the_whole_signal_written_at_once() {
        let directory = scratch_directory("streamed");
        let signal: Vec<f32> = (0..5000).map(|index| (index as f32 * 0.01).sin()).collect();
        let whole = directory.join("whole.wav");
        javari_core::engine::wav::write_wav(&whole, &signal, 48_000.0).unwrap();
        let streamed = directory.join("streamed.wav");
        let mut wav = PendingWav::create(&streamed, 48_000.0, 1).unwrap();
        for block in signal.chunks(512) {
            wav.write(block).unwrap();
        }
        wav.commit().unwrap();
        assert_eq!(
            std::fs::read(&whole).unwrap(),
            std::fs::read(&streamed).unwrap()
        );
        std::fs::remove_dir_all(&directory).unwrap();
    }

    #[test]
    fn a_refused_render_leaves_the_previous_file_untouched() {
        let directory = scratch_directory("refused");
        let out = directory.join("song.wav");
        std::fs::write(&out, b"the previous render").unwrap();
        let cases: [(&str, Vec<u8>, &[&str], &str); 4] = [
            // A controller and a silent note-on: no note at all.
            (
                "quiet.mid",
                midi_bytes(b"\x00\xb0\x07\x64\x00\x90\x30\x00\x00\xff\x2f\x00"),
                &[],
                "no notes",
            ),
            // Only note 10 (14.6 Hz), below the tanpura's range.
            (
                "low.mid",
                midi_bytes(b"\x00\x90\x0a\x64\x60\x80\x0a\x00\x00\xff\x2f\x00"),
                &[],
                "nothing to play",
            ),
            // The note-off 2^28 − 1 ticks (about 78 hours at 120 bpm) after the note-on.
            (
                "far.mid",
                midi_bytes(b"\x00\x90\x30\x64\xff\xff\xff\x7f\x80\x30\x00\x00\xff\x2f\x00"),
                &[],
                "longer than --max-seconds 3600",
            ),
            // A note of 2 s (1920 ticks) and --max-seconds 1.
            (
                "two-seconds.mid",
                midi_bytes(b"\x00\x90\x30\x64\x8f\x00\x80\x30\x00\x00\xff\x2f\x00"),
                &["--max-seconds", "1"],
                "2.10 s with the tail (its last event is at 2.00 s, at track 1, byte 31;",
            ),
        ];
        for (name, bytes, extra, expected) in cases {
            let midi = directory.join(name);
            std::fs::write(&midi, bytes).unwrap();
            let started = Instant::now();
            let error = run(render_args(&midi, &out, extra))
                .unwrap_err()
                .to_string();
            assert!(
                started.elapsed().as_secs_f64() < 1.0,
                "{name} took long to refuse"
            );
            assert!(error.contains(expected), "{name}: {error}");
            assert!(error.contains(name), "{name}: {error}");
            std::fs::remove_file(&midi).unwrap();
            assert_eq!(
                std::fs::read(&out).unwrap(),
                b"the previous render",
                "{name}"
            );
            assert_eq!(file_names(&directory), ["song.wav"], "{name}");
        }
        std::fs::remove_dir_all(&directory).unwrap();
    }

    #[test]
    fn a_file_cut_short_renders_what_was_read() {
        let directory = scratch_directory("cut");
        let midi = directory.join("cut.mid");
        // Cut inside the note-off: the note is read, its end is lost.
        let whole = midi_bytes(SHORT_NOTE);
        std::fs::write(&midi, &whole[..whole.len() - 6]).unwrap();
        let out = directory.join("cut.wav");
        run(render_args(&midi, &out, &[])).unwrap();
        let (signal, rate) = read_wav(&out).unwrap();
        assert_eq!(rate, 44_100.0);
        // The note-on at 0 s is the last event read: the tail alone follows it.
        assert_eq!(signal.len(), 4411);
        assert!(signal.iter().any(|&x| x != 0.0));
        assert_eq!(file_names(&directory), ["cut.mid", "cut.wav"]);
        std::fs::remove_dir_all(&directory).unwrap();
    }

    #[test]
    fn a_log_gets_a_plain_line_per_tenth() {
        let mut next_tenth = 1;
        let lines: Vec<String> = (1..=40)
            .filter_map(|block| progress_line(block * 25, 1000, 100.0, &mut next_tenth))
            .collect();
        assert_eq!(lines.len(), 10, "{lines:?}");
        assert_eq!(lines[0], "rendered 10% (1.0 of 10.0 s)");
        assert_eq!(lines[9], "rendered 100% (10.0 of 10.0 s)");
        assert!(lines.iter().all(|line| !line.contains('\r')));
        // A block that jumps several tenths gives one line.
        let mut next_tenth = 1;
        assert_eq!(
            progress_line(700, 1000, 100.0, &mut next_tenth).as_deref(),
            Some("rendered 70% (7.0 of 10.0 s)")
        );
        assert_eq!(progress_line(750, 1000, 100.0, &mut next_tenth), None);
    }

    #[test]
    fn max_seconds_defaults_to_an_hour_and_is_checked() {
        let args = RenderArgs::try_parse_from(["render"]).unwrap();
        assert_eq!(args.max_seconds, 3600.0);
        assert!(RenderArgs::try_parse_from(["render", "--max-seconds", "0"]).is_err());
        assert!(check_length(3600.0, 3600.0, (44_100.0, 1), "x", None).is_ok());
        let error = check_length(f64::NAN, 3600.0, (44_100.0, 1), "x", None).unwrap_err();
        assert!(error.contains("--max-seconds"), "{error}");
        let error = check_length(80_000.0, 86_400.0, (192_000.0, 1), "x", None).unwrap_err();
        assert!(error.contains("more than a WAV file holds"), "{error}");
    }
}
