//! Calibrations kept across runs: what `cargo xtask render` and the bench's playing-range grid
//! measured once is read back the next time instead of rendered again.
//!
//! A string's as-played calibration (`javari_core::tanpura::as_played`) costs 5 renders of 1.5 s
//! on the string's own tier, and up to 32 when its jawari is set: at the reference tier, 9.7 s
//! of the demo's 17.3 s on one core (stop 34). It depends only on the string's request (settings, pluck, velocities), the sample
//! rate and the code that renders it, so it is kept under `target/calibration-cache/`, one small
//! text file per calibration, named by a hash of
//! - the version of `core/` (its committed git tree, plus a hash of any uncommitted change to
//!   it and of its untracked files' names and contents; without git nothing is cached),
//! - the vector unit the kernels run on (`javari_core::simd::Kernels`: AVX-512, AVX2+FMA and
//!   scalar round differently),
//! - the request as `Debug` prints it (every number to the digit that reads back exactly) and
//!   the sample rate's bits.
//!
//! The file holds the offset and the thread move to the digit that reads back exactly, and the
//! request and version it was measured for: a file whose text is not that (a hash collision, a
//! truncated or edited file) is not used, and the calibration is measured again and written over
//! it. A failed write costs only a measurement next time. A calibration read back is thus the
//! calibration that would have been measured, to the bit (tested).

use javari_core::simd::Kernels;
use javari_core::tanpura::as_played::{Calibration, CalibrationRequest};
use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The version of `core/`: its committed tree and any uncommitted change, or `None` without git.
pub fn core_version(workspace: &Path) -> Option<String> {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(workspace)
            .output()
            .ok()
            .filter(|output| output.status.success())
            .map(|output| output.stdout)
    };
    let tree = git(&["rev-parse", "HEAD:core"])?;
    let diff = git(&["diff", "HEAD", "--", "core"])?;
    let untracked = git(&["ls-files", "--others", "--exclude-standard", "--", "core"])?;
    let mut hasher = DefaultHasher::new();
    diff.hash(&mut hasher);
    // Untracked files by name and content (an edited one is a change too).
    for name in String::from_utf8_lossy(&untracked).lines() {
        name.hash(&mut hasher);
        std::fs::read(workspace.join(name))
            .unwrap_or_default()
            .hash(&mut hasher);
    }
    Some(format!(
        "{}-{:016x}",
        String::from_utf8_lossy(&tree).trim(),
        hasher.finish()
    ))
}

/// The workspace's root (the directory above `xtask/`).
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap_or(Path::new("."))
        .to_path_buf()
}

/// Where a calibration came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    Measured,
    Cached,
}

/// The calibrations of one version of the code, in one directory.
#[derive(Debug, Clone)]
pub struct CalibrationCache {
    directory: PathBuf,
    /// The code's version and the vector unit, as written into every file.
    version: String,
}

impl CalibrationCache {
    /// The workspace's cache (`target/calibration-cache/`) for the current `core/`; `None`
    /// without git, when no version can be told.
    pub fn for_workspace() -> Option<Self> {
        let workspace = workspace();
        let version = core_version(&workspace)?;
        Some(Self::at(
            workspace.join("target/calibration-cache"),
            &version,
        ))
    }

    /// A cache in `directory` for code of `version` (the vector unit is added to it).
    pub fn at(directory: PathBuf, version: &str) -> Self {
        Self {
            directory,
            version: format!("{version} {}", Kernels::detect().name()),
        }
    }

    /// What a file records of the measurement: the version and the request.
    fn identity(&self, request: &CalibrationRequest, sample_rate_hz: f64) -> String {
        format!("{} | {:?} | {:e} Hz", self.version, request, sample_rate_hz)
    }

    fn file(&self, identity: &str) -> PathBuf {
        let mut hasher = DefaultHasher::new();
        identity.hash(&mut hasher);
        self.directory
            .join(format!("{:016x}.calibration", hasher.finish()))
    }

    /// The calibration kept for `request` at `sample_rate_hz`, if there is one that reads back
    /// whole and was measured for exactly this request and version.
    pub fn get(&self, request: &CalibrationRequest, sample_rate_hz: f64) -> Option<Calibration> {
        let identity = self.identity(request, sample_rate_hz);
        let text = std::fs::read_to_string(self.file(&identity)).ok()?;
        let (numbers, recorded) = text.split_once('\n')?;
        if recorded.trim_end_matches('\n') != identity {
            return None;
        }
        let mut numbers = numbers.split(' ').map(str::parse::<f64>);
        let offset_cents = numbers.next()?.ok()?;
        let thread_offset_m = numbers.next()?.ok()?;
        if numbers.next().is_some() || !offset_cents.is_finite() || !thread_offset_m.is_finite() {
            return None;
        }
        Some(Calibration {
            request: *request,
            sample_rate_hz,
            offset_cents,
            thread_offset_m,
        })
    }

    /// Keeps `calibration` (written whole or not at all: a partial file is renamed into place).
    pub fn put(&self, calibration: &Calibration) {
        let identity = self.identity(&calibration.request, calibration.sample_rate_hz);
        let path = self.file(&identity);
        let text = format!(
            "{:e} {:e}\n{identity}\n",
            calibration.offset_cents, calibration.thread_offset_m
        );
        let temporary = path.with_extension(format!("partial-{}", std::process::id()));
        if std::fs::create_dir_all(&self.directory).is_ok()
            && std::fs::write(&temporary, text).is_ok()
            && std::fs::rename(&temporary, &path).is_err()
        {
            let _ = std::fs::remove_file(&temporary);
        }
    }

    /// The calibration of `request`: the kept one, else `measure`'s, which is then kept.
    pub fn get_or_measure(
        &self,
        request: &CalibrationRequest,
        sample_rate_hz: f64,
        measure: impl FnOnce(&CalibrationRequest, f64) -> Calibration,
    ) -> (Calibration, Source) {
        let request = request.clamped();
        if let Some(kept) = self.get(&request, sample_rate_hz) {
            return (kept, Source::Cached);
        }
        let measured = measure(&request, sample_rate_hz);
        self.put(&measured);
        (measured, Source::Measured)
    }
}

/// [`CalibrationCache::get_or_measure`] through `cache` when there is one, else measured. The
/// calibration of the string whose jawari this one takes (the studio tier's: the reference's)
/// goes through `cache` too.
pub fn calibration(
    cache: Option<&CalibrationCache>,
    request: &CalibrationRequest,
    sample_rate_hz: f64,
) -> (Calibration, Source) {
    match cache {
        Some(cache) => cache.get_or_measure(request, sample_rate_hz, |request, rate| {
            Calibration::measure_with(request, rate, |jawari, rate| {
                calibration(Some(cache), jawari, rate).0
            })
        }),
        None => (
            Calibration::measure(request, sample_rate_hz),
            Source::Measured,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use javari_core::tanpura::excitation::Pluck;
    use javari_core::tanpura::quality::Quality;
    use javari_core::tanpura::voice::VoiceSettings;
    use std::cell::Cell;

    fn request(fundamental_hz: f64) -> CalibrationRequest {
        CalibrationRequest {
            settings: VoiceSettings {
                fundamental_hz,
                quality: Quality::Live,
                ..VoiceSettings::default()
            },
            pluck: Pluck::default(),
            velocities: [40.0 / 127.0, 110.0 / 127.0],
        }
    }

    /// Stands in for a measurement: numbers with every digit in use, so that a lossy round trip
    /// through the file would show.
    fn pretend_measure(request: &CalibrationRequest, sample_rate_hz: f64) -> Calibration {
        Calibration {
            request: *request,
            sample_rate_hz,
            offset_cents: -std::f64::consts::PI * 1.000_000_000_000_1,
            thread_offset_m: 1.0e-4 / 3.0,
        }
    }

    #[test]
    fn a_kept_calibration_reads_back_to_the_bit_and_is_not_measured_again() {
        let directory = tempfile::tempdir().unwrap();
        let cache = CalibrationCache::at(directory.path().to_path_buf(), "v1");
        let measured = Cell::new(0);
        let counting = |request: &CalibrationRequest, rate: f64| {
            measured.set(measured.get() + 1);
            pretend_measure(request, rate)
        };
        let (first, source) = cache.get_or_measure(&request(110.0), 44_100.0, counting);
        assert_eq!(source, Source::Measured);
        let (second, source) = cache.get_or_measure(&request(110.0), 44_100.0, counting);
        assert_eq!(source, Source::Cached);
        assert_eq!(measured.get(), 1);
        assert_eq!(first, second);
        assert_eq!(first.offset_cents.to_bits(), second.offset_cents.to_bits());
        assert_eq!(
            first.thread_offset_m.to_bits(),
            second.thread_offset_m.to_bits()
        );
    }

    #[test]
    fn another_string_rate_or_version_is_measured_afresh() {
        let directory = tempfile::tempdir().unwrap();
        let path = directory.path().to_path_buf();
        let cache = CalibrationCache::at(path.clone(), "v1");
        cache.get_or_measure(&request(110.0), 44_100.0, pretend_measure);
        assert!(cache.get(&request(110.0), 44_100.0).is_some());
        // A different note (by a part in 10¹⁵), sample rate, tier or version misses.
        assert!(cache
            .get(&request(110.0 * (1.0 + 1e-15)), 44_100.0)
            .is_none());
        assert!(cache.get(&request(110.0), 48_000.0).is_none());
        let mut other_tier = request(110.0);
        other_tier.settings.quality = Quality::Studio;
        assert!(cache.get(&other_tier, 44_100.0).is_none());
        assert!(CalibrationCache::at(path, "v2")
            .get(&request(110.0), 44_100.0)
            .is_none());
    }

    #[test]
    fn a_damaged_file_is_measured_again_and_mended() {
        let directory = tempfile::tempdir().unwrap();
        let cache = CalibrationCache::at(directory.path().to_path_buf(), "v1");
        let (kept, _) = cache.get_or_measure(&request(110.0), 44_100.0, pretend_measure);
        let file = std::fs::read_dir(directory.path())
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path();
        let whole = std::fs::read_to_string(&file).unwrap();
        let identity = whole.split_once('\n').unwrap().1.to_string();
        for damaged in [
            String::new(),
            whole.chars().take(whole.len() / 2).collect(),
            format!("NaN 0\n{identity}"),
            format!("1 2 3\n{identity}"),
            format!("1 x\n{identity}"),
            // The right name over another request's text (as a hash collision would be).
            whole.replace("Live", "Studio"),
        ] {
            std::fs::write(&file, &damaged).unwrap();
            assert!(
                cache.get(&request(110.0), 44_100.0).is_none(),
                "{damaged:?}"
            );
            let (again, source) = cache.get_or_measure(&request(110.0), 44_100.0, pretend_measure);
            assert_eq!((again, source), (kept, Source::Measured));
            assert_eq!(std::fs::read_to_string(&file).unwrap(), whole);
        }
    }

    /// The request is kept as the engine clamps it, so that the cached and the measured
    /// calibration carry the same request.
    #[test]
    fn a_request_out_of_range_is_kept_as_clamped() {
        let directory = tempfile::tempdir().unwrap();
        let cache = CalibrationCache::at(directory.path().to_path_buf(), "v1");
        let mut wild = request(110.0);
        wild.velocities = [f64::NAN, 7.0];
        let (measured, _) = cache.get_or_measure(&wild, 44_100.0, pretend_measure);
        let (cached, source) = cache.get_or_measure(&wild, 44_100.0, pretend_measure);
        assert_eq!(source, Source::Cached);
        assert_eq!(measured, cached);
        assert_eq!(cached.request, wild.clamped());
        assert_eq!(cached.request.velocities, [1.0, 1.0]);
    }
}
