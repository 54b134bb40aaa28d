//! The bench's playing-range grid: every tier against the reference on every pluck of
//! [`javari_core::analysis::playing_range::full_grid`] (keys 36–64, six velocities, two pluck
//! positions), measured by [`javari_core::analysis::listening`]: worst case and median of each
//! measure over the grid, and the worst point named.
//!
//! The reference renders are the expensive part (the reference tier runs near real time), so they
//! are cached under `target/bench-cache/playing-range/`, one file per pluck (its samples as
//! little-endian f32, exactly what the engine produced), keyed by the pluck's engine settings,
//! the render length and rate, and the version of `core/` (its git tree, plus the hash of any
//! uncommitted change to it). Without git the cache is not used. Renders run on all cores (rayon).
//!
//! Every pluck is tuned as `cargo xtask render` tunes it, by its sustained pitch as played
//! (`javari_core::tanpura::as_played`): each tier's string at each key and pluck position is
//! calibrated on that tier first (every calibration is kept for the next run, per version of
//! `core/`: `crate::calibration_cache`).
//!
//! [`measure_against_refined`] asks the same grid how far each tier, the reference included, lies
//! from the physics: every pluck against the reference's scheme refined fourfold in space and
//! time (N = 800 at 16×, `javari_core::analysis::refined`), every scheme tuned by linearisation
//! so that all are compared at equal physical parameters. The refined renders (sixteen times the
//! reference's work) are cached like the reference's.

use crate::calibration_cache::{calibration, core_version, workspace, CalibrationCache};
use javari_core::analysis::cents;
use javari_core::analysis::listening::{compare, sustained_pitch_hz, ListeningDifference};
use javari_core::analysis::playing_range::{
    calibration_request, full_grid, render_as_played, settings_for, GridPoint, CREST_KEYS, KEYS,
    NOTE_SECONDS, PLUCK_POSITIONS_M, VELOCITIES,
};
use javari_core::analysis::refined::{
    grid_render_linearised, grid_render_refined, yardstick_grid, YARDSTICK_REFINEMENT,
};
use javari_core::tanpura::as_played::Calibration;
use javari_core::tanpura::quality::Quality;
use rayon::prelude::*;
use std::collections::hash_map::DefaultHasher;
use std::fmt::Write as _;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

/// One tier's comparison over the grid.
#[derive(Debug, Clone)]
pub struct TierOverGrid {
    pub tier: &'static str,
    pub points: Vec<(GridPoint, ListeningDifference)>,
}

/// Worst case and median of one measure over the grid, and where the worst lies.
#[derive(Debug, Clone)]
pub struct Spread {
    pub worst: f64,
    pub median: f64,
    pub worst_at: GridPoint,
}

impl TierOverGrid {
    fn spread(&self, measure: impl Fn(&ListeningDifference) -> f64) -> Spread {
        let mut values: Vec<(f64, GridPoint)> = self
            .points
            .iter()
            .map(|(point, difference)| (measure(difference), *point))
            .collect();
        values.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (worst, worst_at) = values[values.len() - 1];
        Spread {
            worst,
            median: values[values.len() / 2].0,
            worst_at,
        }
    }

    /// The same comparison without the plucks of `keys`.
    pub fn without_keys(&self, keys: &std::ops::RangeInclusive<u8>) -> TierOverGrid {
        TierOverGrid {
            tier: self.tier,
            points: self
                .points
                .iter()
                .filter(|(point, _)| !keys.contains(&point.key))
                .cloned()
                .collect(),
        }
    }

    pub fn sustained_cents(&self) -> Spread {
        self.spread(|d| d.sustained_cents.abs())
    }
    pub fn glide_cents(&self) -> Spread {
        self.spread(|d| d.glide_cents)
    }
    pub fn band_level_db(&self) -> Spread {
        self.spread(|d| d.band_level_db)
    }
    pub fn centroid_error(&self) -> Spread {
        self.spread(|d| d.centroid_error)
    }
}

/// The cache file of a render of `point` of the kind `render` (a label naming the scheme and its
/// tuning).
fn cache_file(
    directory: &Path,
    version: &str,
    render: &str,
    point: &GridPoint,
    sample_rate_hz: f64,
) -> PathBuf {
    let mut hasher = DefaultHasher::new();
    render.hash(&mut hasher);
    version.hash(&mut hasher);
    format!("{:?}", settings_for(Quality::Reference, point)).hash(&mut hasher);
    point.key.hash(&mut hasher);
    point.velocity.hash(&mut hasher);
    NOTE_SECONDS.to_bits().hash(&mut hasher);
    sample_rate_hz.to_bits().hash(&mut hasher);
    directory.join(format!("{:016x}.f32", hasher.finish()))
}

fn read_cached(path: &Path, samples: usize) -> Option<Vec<f64>> {
    let bytes = std::fs::read(path).ok()?;
    (bytes.len() == 4 * samples).then(|| {
        bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
            .collect()
    })
}

fn write_cached(path: &Path, output: &[f64]) {
    // The engine's output is f32, so the round trip is exact. A failed write only costs a
    // re-render next time.
    let bytes: Vec<u8> = output
        .iter()
        .flat_map(|&x| (x as f32).to_le_bytes())
        .collect();
    let temporary = path.with_extension("partial");
    if std::fs::write(&temporary, bytes).is_ok() {
        let _ = std::fs::rename(&temporary, path);
    }
}

/// The bench's render cache: its directory and the version of `core/` (`None` without git).
fn render_cache() -> Option<(PathBuf, String)> {
    let workspace = workspace();
    core_version(&workspace).map(|version| {
        let directory = workspace.join("target/bench-cache/playing-range");
        let _ = std::fs::create_dir_all(&directory);
        (directory, version)
    })
}

/// `render()` of `point`, read from `cache` when an earlier run of this version of `core/` kept
/// it (`kind` names the scheme and its tuning), and kept there.
fn cached_render(
    cache: Option<&(PathBuf, String)>,
    kind: &str,
    point: &GridPoint,
    sample_rate_hz: f64,
    render: impl FnOnce() -> Vec<f64>,
) -> Vec<f64> {
    let samples = (NOTE_SECONDS * sample_rate_hz).round() as usize;
    let path = cache.map(|(dir, version)| cache_file(dir, version, kind, point, sample_rate_hz));
    if let Some(cached) = path.as_deref().and_then(|p| read_cached(p, samples)) {
        return cached;
    }
    let output = render();
    if let Some(path) = path {
        write_cached(&path, &output);
    }
    output
}

/// Every pluck of the grid on the reference and on `tiers`, each against the reference's scheme
/// refined [`YARDSTICK_REFINEMENT`] times, all tuned by linearisation (module doc). The refined
/// renders come from the cache when there. The reference comes first.
pub fn measure_against_refined(tiers: &[Quality], sample_rate_hz: f64) -> Vec<TierOverGrid> {
    let grid = full_grid();
    let cache = render_cache();
    let kind = format!("refined {YARDSTICK_REFINEMENT} times, tuned by linearisation");
    let (intervals, oversample) = yardstick_grid();
    eprintln!(
        "bench: playing range against N = {intervals} at {oversample}×, {} plucks ...",
        grid.len()
    );
    let schemes: Vec<Quality> = std::iter::once(Quality::Reference)
        .chain(tiers.iter().copied().filter(|&q| q != Quality::Reference))
        .collect();
    // One job per pluck: its refined render (the slow part), then every scheme against it.
    let per_point: Vec<Vec<ListeningDifference>> = grid
        .par_iter()
        .map(|point| {
            let refined = cached_render(cache.as_ref(), &kind, point, sample_rate_hz, || {
                grid_render_refined(point, sample_rate_hz)
            });
            schemes
                .iter()
                .map(|&quality| {
                    let render = grid_render_linearised(quality, point, sample_rate_hz, 0);
                    compare(&render, &refined, sample_rate_hz, point.nominal_hz())
                })
                .collect()
        })
        .collect();
    schemes
        .iter()
        .enumerate()
        .map(|(s, quality)| TierOverGrid {
            tier: quality.name(),
            points: grid
                .iter()
                .zip(&per_point)
                .map(|(point, differences)| (*point, differences[s]))
                .collect(),
        })
        .collect()
}

/// The table of [`measure_against_refined`]: worst / median of each measure per scheme.
pub fn against_refined_markdown(results: &[TierOverGrid]) -> String {
    let (intervals, oversample) = yardstick_grid();
    let mut text = format!(
        "\nThe same plucks against the physics: every tier and the reference against the \
         reference's scheme refined fourfold in space and time (N = {intervals} at {oversample}×), every scheme \
         tuned by linearisation (equal physical parameters, no calibration as played), worst / \
         median over the grid:\n\n\
         | scheme | sustained pitch, cents | glide, cents | band levels, dB RMS | centroid course | worst pitch at | worst bands at |\n\
         |---|---|---|---|---|---|---|\n"
    );
    for tier in results {
        let _ = writeln!(text, "{}", spread_row(tier));
    }
    text
}

/// A table row: the tier, worst / median of each measure, where the worst pitch and bands lie.
fn spread_row(tier: &TierOverGrid) -> String {
    let (pitch, glide, bands, centroid) = (
        tier.sustained_cents(),
        tier.glide_cents(),
        tier.band_level_db(),
        tier.centroid_error(),
    );
    format!(
        "| {} | {:.2} / {:.2} | {:.1} / {:.1} | {:.1} / {:.1} | {:.1} % / {:.1} % | {} | {} |",
        tier.tier,
        pitch.worst,
        pitch.median,
        glide.worst,
        glide.median,
        bands.worst,
        bands.median,
        100.0 * centroid.worst,
        100.0 * centroid.median,
        pitch.worst_at.label(),
        bands.worst_at.label(),
    )
}

/// Renders (or loads) the reference over the grid and compares `tiers` with it. The first
/// element is the reference itself against the keys' nominal pitches: its `sustained_cents` is
/// how far the reference sounds from the note it was tuned to (the other measures are zero).
pub fn measure(tiers: &[Quality], sample_rate_hz: f64) -> Vec<TierOverGrid> {
    let grid = full_grid();
    let calibration_cache = CalibrationCache::for_workspace();
    let cache = render_cache();
    eprintln!(
        "bench: playing range, {} plucks × {} tiers and the reference, on {} threads ...",
        grid.len(),
        tiers.len(),
        rayon::current_num_threads()
    );
    // Each tier's calibrations, one per key and pluck position (the reference's from the cache
    // when there), the reference's first so that the slowest jobs start first.
    let strings: Vec<(u8, f64)> = KEYS
        .iter()
        .flat_map(|&key| PLUCK_POSITIONS_M.map(|position| (key, position)))
        .collect();
    let mut calibration_jobs: Vec<(Quality, u8, f64)> = strings
        .iter()
        .map(|&(key, position)| (Quality::Reference, key, position))
        .collect();
    for &tier in tiers {
        calibration_jobs.extend(strings.iter().map(|&(key, position)| (tier, key, position)));
    }
    let calibrations: Vec<Calibration> = calibration_jobs
        .par_iter()
        .map(|&(quality, key, position)| {
            let request = calibration_request(quality, key, position);
            calibration(calibration_cache.as_ref(), &request, sample_rate_hz).0
        })
        .collect();
    let calibration_of = |quality: Quality, point: &GridPoint| {
        calibration_jobs
            .iter()
            .position(|&(q, key, position)| {
                q == quality && key == point.key && position == point.pluck_position_m
            })
            .map(|index| calibrations[index])
            .expect("every tier's string is calibrated")
    };
    // One job per (tier, pluck), the reference first.
    let mut jobs: Vec<(Option<Quality>, usize)> = (0..grid.len()).map(|i| (None, i)).collect();
    for &tier in tiers {
        jobs.extend((0..grid.len()).map(|i| (Some(tier), i)));
    }
    let renders: Vec<Vec<f64>> = jobs
        .par_iter()
        .map(|&(tier, index)| {
            let point = &grid[index];
            match tier {
                Some(quality) => render_as_played(
                    quality,
                    point,
                    NOTE_SECONDS,
                    sample_rate_hz,
                    &calibration_of(quality, point),
                ),
                None => cached_render(
                    cache.as_ref(),
                    "tuned as played",
                    point,
                    sample_rate_hz,
                    || {
                        render_as_played(
                            Quality::Reference,
                            point,
                            NOTE_SECONDS,
                            sample_rate_hz,
                            &calibration_of(Quality::Reference, point),
                        )
                    },
                ),
            }
        })
        .collect();
    let (references, tier_renders) = renders.split_at(grid.len());
    let reference_against_nominal = TierOverGrid {
        tier: Quality::Reference.name(),
        points: (0..grid.len())
            .into_par_iter()
            .map(|i| {
                let nominal = grid[i].nominal_hz();
                let pitch = sustained_pitch_hz(&references[i], sample_rate_hz, nominal);
                let difference = ListeningDifference {
                    sustained_cents: cents(pitch, nominal),
                    glide_cents: 0.0,
                    band_level_db: 0.0,
                    centroid_error: 0.0,
                };
                (grid[i], difference)
            })
            .collect(),
    };
    let compared = tiers.iter().enumerate().map(|(t, quality)| {
        let points = (0..grid.len())
            .into_par_iter()
            .map(|i| {
                let render = &tier_renders[t * grid.len() + i];
                let difference =
                    compare(render, &references[i], sample_rate_hz, grid[i].nominal_hz());
                (grid[i], difference)
            })
            .collect();
        TierOverGrid {
            tier: quality.name(),
            points,
        }
    });
    std::iter::once(reference_against_nominal)
        .chain(compared)
        .collect()
}

/// The grid's table: worst / median of each measure per tier, and where each worst lies.
pub fn to_markdown(results: &[TierOverGrid]) -> String {
    let grid = full_grid();
    let mut text = format!(
        "\nAcross the playing range ({} single plucks: keys 36–64 every third semitone and 64 \
         and every crest key 48–54, velocities {}, plucks at 0.35 and 0.20 m; {:.1} s \
         each, against the reference render of the same pluck; measures defined in \
         `core/src/analysis/listening.rs`), worst / median over the grid:\n\n\
         | tier | sustained pitch (0.3–1.5 s), cents | glide (first 0.3 s), cents | 1/6-octave band levels to 16 kHz, dB RMS | centroid course | worst pitch at | worst bands at |\n\
         |---|---|---|---|---|---|---|\n",
        grid.len(),
        VELOCITIES.map(|velocity| velocity.to_string()).join("/"),
        NOTE_SECONDS
    );
    for tier in results
        .iter()
        .filter(|t| t.tier != Quality::Reference.name())
    {
        let _ = writeln!(text, "{}", spread_row(tier));
    }
    if let Some(reference) = results.iter().find(|t| t.tier == Quality::Reference.name()) {
        let pitch = reference.sustained_cents();
        let _ = writeln!(
            text,
            "\nThe reference itself against the keys' nominal pitches (every tier is tuned as \
             played: its string's sustained pitches at velocities 40 and 110 centred on the \
             note, and its thread moved by a fraction of a millimetre where its plucks at 40, 75 \
             and 110 would not settle): its sustained pitch is off by {:.2} cents at worst ({}), \
             {:.2} cents median.",
            pitch.worst,
            pitch.worst_at.label(),
            pitch.median
        );
    }
    text.push_str(&away_from_the_crest_markdown(results));
    text
}

/// Each tier's worst plucks over the grid without [`CREST_KEYS`], where the reference is the
/// least resolved scheme: how far the tiers' misses are their own. Empty if no pluck is left.
fn away_from_the_crest_markdown(results: &[TierOverGrid]) -> String {
    let mut text = String::new();
    for tier in results
        .iter()
        .filter(|t| t.tier != Quality::Reference.name())
    {
        let away = tier.without_keys(&CREST_KEYS);
        if away.points.is_empty() {
            continue;
        }
        if text.is_empty() {
            let _ = write!(
                text,
                "\nAway from the crest keys ({}–{}, where the reference's grid is the least \
                 resolved scheme), worst over the other {} plucks:",
                CREST_KEYS.start(),
                CREST_KEYS.end(),
                away.points.len()
            );
        }
        let (pitch, bands, centroid) = (
            away.sustained_cents(),
            away.band_level_db(),
            away.centroid_error(),
        );
        let _ = write!(
            text,
            " {} pitch {:.2} cents ({}), band levels {:.1} dB ({}), centroid {:.1} % ({});",
            tier.tier,
            pitch.worst,
            pitch.worst_at.label(),
            bands.worst,
            bands.worst_at.label(),
            100.0 * centroid.worst,
            centroid.worst_at.label()
        );
    }
    if !text.is_empty() {
        text.pop();
        text.push_str(".\n");
    }
    text
}

/// Rows for the targets table: the live, fine (the default) and studio tiers' worst grid points
/// against issue 15's targets (sustained pitch 1 cent, band levels 5 dB, centroid 15 %).
pub fn target_rows(results: &[TierOverGrid]) -> Vec<(String, f64, f64, &'static str)> {
    let mut rows = Vec::new();
    for tier in results.iter().filter(|t| {
        [Quality::Live, Quality::Fine, Quality::Studio]
            .iter()
            .any(|quality| t.tier == quality.name())
    }) {
        rows.push((
            format!(
                "{} tier, worst pluck of the range: sustained pitch within 1 cent",
                tier.tier
            ),
            tier.sustained_cents().worst,
            1.0,
            " cents",
        ));
        rows.push((
            format!(
                "{} tier, worst pluck of the range: band levels within 5 dB RMS",
                tier.tier
            ),
            tier.band_level_db().worst,
            5.0,
            " dB",
        ));
        rows.push((
            format!(
                "{} tier, worst pluck of the range: centroid within 15 %",
                tier.tier
            ),
            100.0 * tier.centroid_error().worst,
            15.0,
            " %",
        ));
    }
    rows
}

/// The grid as JSON rows, one per tier and pluck.
pub fn to_json_rows(results: &[TierOverGrid]) -> Vec<String> {
    results
        .iter()
        .flat_map(|tier| {
            tier.points.iter().map(move |(point, d)| {
                format!(
                    "{{\"tier\": \"{}\", \"key\": {}, \"velocity\": {}, \"pluck_position_m\": {}, \
                     \"sustained_cents\": {:.4}, \"glide_cents\": {:.4}, \"band_level_db\": {:.4}, \
                     \"centroid_error\": {:.5}}}",
                    tier.tier,
                    point.key,
                    point.velocity,
                    point.pluck_position_m,
                    d.sustained_cents,
                    d.glide_cents,
                    d.band_level_db,
                    d.centroid_error
                )
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(key: u8, velocity: u8) -> GridPoint {
        GridPoint {
            key,
            velocity,
            pluck_position_m: 0.20,
        }
    }

    fn difference(cents: f64, band_level_db: f64) -> ListeningDifference {
        ListeningDifference {
            sustained_cents: cents,
            glide_cents: cents.abs(),
            band_level_db,
            centroid_error: 0.1,
        }
    }

    #[test]
    fn the_modal_tiers_are_held_to_issue_15s_targets() {
        let live = TierOverGrid {
            tier: Quality::Live.name(),
            points: vec![
                (point(51, 1), difference(10.9, 19.6)),
                (point(60, 127), difference(0.2, 9.7)),
            ],
        };
        let rows = target_rows(&[live]);
        let targets: Vec<(&str, f64, f64)> = rows
            .iter()
            .map(|(target, measured, goal, _)| (target.as_str(), *measured, *goal))
            .collect();
        assert_eq!(targets.len(), 3, "{targets:?}");
        assert!(targets[0].0.contains("live tier") && targets[0].0.contains("1 cent"));
        assert_eq!((targets[0].1, targets[0].2), (10.9, 1.0));
        assert!(targets[1].0.contains("band levels within 5 dB"));
        assert_eq!((targets[1].1, targets[1].2), (19.6, 5.0));
        assert!(targets[2].0.contains("centroid within 15 %"));
        // The reference's own row has no targets.
        let reference = TierOverGrid {
            tier: Quality::Reference.name(),
            points: vec![(point(60, 127), difference(0.2, 9.7))],
        };
        assert!(target_rows(&[reference]).is_empty());
    }

    #[test]
    fn the_worst_plucks_away_from_the_crest_keys_leave_the_crest_keys_out() {
        let live = TierOverGrid {
            tier: Quality::Live.name(),
            points: vec![
                (point(51, 1), difference(-11.9, 16.2)),
                (point(57, 1), difference(-1.87, 3.0)),
                (point(60, 40), difference(0.3, 12.0)),
            ],
        };
        let table = to_markdown(std::slice::from_ref(&live));
        assert!(
            table.contains(
                "Away from the crest keys (48–54, where the reference's grid is the least resolved \
                 scheme), worst over the other 2 plucks: live pitch 1.87 cents (key 57, velocity \
                 1, pluck at 0.20 m), band levels 12.0 dB (key 60, velocity 40, pluck at 0.20 m), \
                 centroid 10.0 % (key"
            ),
            "{table}"
        );
        // A grid of crest keys alone leaves nothing to say.
        let crest_only = TierOverGrid {
            tier: Quality::Live.name(),
            points: vec![(point(51, 1), difference(-11.9, 16.2))],
        };
        assert!(!to_markdown(&[crest_only]).contains("Away from the crest keys"));
    }

    #[test]
    fn the_table_against_the_physics_has_a_row_per_scheme_the_reference_first() {
        let scheme = |tier, worst_cents: f64| TierOverGrid {
            tier,
            points: vec![
                (point(51, 127), difference(-worst_cents, 5.4)),
                (point(60, 127), difference(0.2, 13.1)),
                (point(36, 1), difference(0.0, 0.6)),
            ],
        };
        let table = against_refined_markdown(&[scheme("reference", 16.53), scheme("live", 2.26)]);
        let reference = table.find("| reference | 16.53 / 0.20 |").expect(&table);
        let live = table.find("| live | 2.26 / 0.20 |").expect(&table);
        assert!(reference < live);
        assert!(table.contains("N = 800 at 16×"));
        assert!(table.contains(
            "| 13.1 / 5.4 | 10.0 % / 10.0 % | key 51, velocity 127, pluck at 0.20 m | key 60, \
             velocity 127, pluck at 0.20 m |"
        ));
    }
}
