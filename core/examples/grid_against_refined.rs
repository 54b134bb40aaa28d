//! Every tier and the reference itself against the reference's scheme refined fourfold in space
//! and time (N = 800 at 16×, `analysis::refined`), over the bench's playing-range grid:
//! `cargo run --release -p javari-core --example grid_against_refined [POSITIONS_M]
//! [--residual-modes N]` (positions such as `0.2,0.35`, default both; the modal tiers with N
//! residual modes, default none as the tiers run; the whole grid takes about three minutes on two
//! cores, almost all of it the refined renders). `-- --yardstick-check` asks instead how far the
//! yardstick moves when refined twice more, at six plucks; `-- --space-time KEY VELOCITY
//! POSITION_M` how far the seed's scheme lies from it at one pluck on grids refined in space or
//! in time alone; `-- --live-variants KEY VELOCITY POSITION_M` the live tier's string with a
//! shorter time step or other bridge points, and on grid modes with the reference's points at
//! one, two and four times the output rate; `-- --rate-grid` the live tier's string with and
//! without two residual modes, at the output rate and at four times it, over the whole grid
//! against the refined string and against the reference (both tuned by linearisation; about
//! five minutes on two cores); `-- --grid-modes` the same with every mode of the reference's FD
//! grid instead of the continuous string's (§10); `-- --grid-spacings` the grid modes with the
//! contact condensed on the nodes (§11) and contact points from the reference's spacing to the
//! tier's; `-- --bands KEY VELOCITY POSITION_M [--as-played]` which 1/6-octave bands part the
//! fine tier, the studio tier, the reference and the refined string at one pluck (with
//! `--as-played`, the tiers calibrated as the bench's grid calibrates them); `-- --fine-rates`
//! the fine tier's string at the output rate and at twice it over the whole grid against the
//! reference (tuned by linearisation; no refined renders). `cargo xtask bench` measures the same
//! without the residual modes, and caches the refined renders.
//!
//! Each pluck is the grid's (`refined::grid_pluck`), rendered by a fresh voice of each tier, every
//! tier tuned by linearising about its own rest state (no calibration as played), so that the
//! schemes are compared at equal physical parameters; the refined string is tuned and plucked
//! the same way. The four measures are the bench's (`analysis::listening::compare`). The figures
//! are quoted in `docs/modal-tanpura.md`, section 9 ("Stop 35"; `--rate-grid`: "Stop 40";
//! `--grid-modes`: section 10; `--grid-spacings`: section 11).

use javari_core::analysis::listening::{
    band_edges_hz, band_levels_db, compare, counted_band_differences_db, ListeningDifference,
};
use javari_core::analysis::playing_range::{
    calibrate, full_grid, render_as_played, GridPoint, CREST_KEYS, NOTE_SECONDS,
};
use javari_core::analysis::refined::{
    grid_pluck, grid_render_linearised, grid_render_refined, modal_variant_pluck,
    reference_pluck_on_grid, refined_reference_pluck, yardstick_grid, ModalVariant,
    YARDSTICK_REFINEMENT,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::VoiceSettings;
use rayon::prelude::*;

const SAMPLE_RATE_HZ: f64 = 44_100.0;
const TIERS: [Quality; 3] = [Quality::Reference, Quality::Studio, Quality::Live];

/// Each tier's distance from the refined render of `point`, in the order of [`TIERS`].
fn measure(point: &GridPoint, residual_modes: usize) -> Vec<ListeningDifference> {
    let refined = grid_render_refined(point, SAMPLE_RATE_HZ);
    TIERS
        .iter()
        .map(|&quality| {
            let output = grid_render_linearised(quality, point, SAMPLE_RATE_HZ, residual_modes);
            compare(&output, &refined, SAMPLE_RATE_HZ, point.nominal_hz())
        })
        .collect()
}

/// `--residual-modes N`: the modal tiers with N residual modes (`docs/modal-tanpura.md` §8).
fn residual_modes(args: &[String]) -> usize {
    args.iter()
        .position(|arg| arg == "--residual-modes")
        .map_or(0, |at| {
            args.get(at + 1)
                .and_then(|n| n.parse().ok())
                .expect("--residual-modes takes a count")
        })
}

/// A grid note of the live tier's string as `variant` changes it (`refined::modal_variant_pluck`).
fn live_variant_render(
    settings: &VoiceSettings,
    variant: &ModalVariant,
    pluck: &Pluck,
) -> Vec<f64> {
    modal_variant_pluck(
        settings,
        variant,
        pluck,
        javari_core::analysis::playing_range::NOTE_SECONDS,
        SAMPLE_RATE_HZ,
    )
    .expect("the live tier is modal")
}

/// `measure` of every point, on all cores (rayon), in the points' order.
fn measure_all<T: Send>(
    points: &[GridPoint],
    measure: impl Fn(&GridPoint) -> T + Sync + Send,
) -> Vec<T> {
    points.par_iter().map(measure).collect()
}

/// Worst and median of each measure over the plucks: (pitch, cents), (band levels, dB),
/// (centroid course, %).
fn summary(differences: &[&ListeningDifference]) -> [(f64, f64); 3] {
    let measures: [fn(&ListeningDifference) -> f64; 3] = [
        |d| d.sustained_cents.abs(),
        |d| d.band_level_db,
        |d| 100.0 * d.centroid_error,
    ];
    measures.map(|measure| {
        let values: Vec<f64> = differences.iter().map(|d| measure(d)).collect();
        let worst = values.iter().copied().fold(0.0, f64::max);
        (worst, median(values))
    })
}

/// `--rate-grid`: the live tier's string with and without two residual modes, at the output
/// rate and at four times it (`refined::modal_variant_pluck`, decimated as the FD tiers are),
/// over the whole grid, against N = 800 at 16× and against the reference, all tuned by
/// linearisation (`docs/modal-tanpura.md`, "Stop 40").
fn rate_grid() {
    let variants = [(0, 1), (0, 4), (2, 1), (2, 4)].map(|(residual_modes, oversample)| {
        (
            format!("{residual_modes} residual modes at {oversample}x"),
            ModalVariant {
                residual_modes,
                oversample,
                ..ModalVariant::default()
            },
        )
    });
    variants_over_grid(&variants);
}

/// `--grid-modes`: the live tier's string with the continuous string's modes (as the tier runs)
/// and with every mode of the reference's FD grid, on the tier's points and on points as fine as
/// the reference's barrier grid (`docs/modal-tanpura.md` §10).
fn grid_modes_grid() {
    let fine = ModalVariant {
        grid_modes: true,
        bridge_point_spacing_m: Some(0.18e-3),
        thread_point_spacing_m: Some(0.15e-3),
        ..ModalVariant::default()
    };
    let variants = [
        (
            "continuous modes (the tier)".to_owned(),
            ModalVariant::default(),
        ),
        (
            "grid modes, the tier's points".to_owned(),
            ModalVariant {
                grid_modes: true,
                ..ModalVariant::default()
            },
        ),
        ("grid modes, points every 0.18 / 0.15 mm".to_owned(), fine),
    ];
    variants_over_grid(&variants);
}

/// `--grid-spacings`: the live tier's string on every mode of the reference's grid, the contact
/// condensed on the grid's nodes (`docs/modal-tanpura.md` §11), with contact points from the
/// reference's spacing (0.18 mm on the bridge, 0.15 mm on the thread) to the tier's: how coarse
/// the points may be before the crest keys part from the reference.
fn grid_spacings_grid() {
    let variants = [
        (0.18e-3, 0.15e-3),
        (0.36e-3, 0.15e-3),
        (0.5e-3, 0.15e-3),
        (0.72e-3, 0.15e-3),
        (1.0e-3, 0.15e-3),
        (2.0e-3, 0.15e-3),
        (0.36e-3, 0.2e-3),
        (0.5e-3, 0.25e-3),
        (2.0e-3, 0.5e-3),
    ]
    .map(|(bridge_m, thread_m)| {
        (
            format!(
                "grid modes, points every {:.2} / {:.2} mm",
                1e3 * bridge_m,
                1e3 * thread_m
            ),
            ModalVariant {
                grid_modes: true,
                bridge_point_spacing_m: Some(bridge_m),
                thread_point_spacing_m: Some(thread_m),
                ..ModalVariant::default()
            },
        )
    });
    variants_over_grid(&variants);
}

/// `--fine-rates`: the fine tier's string as it runs (contact every output sample) and stepped at
/// twice the output rate (decimated as the FD tiers are; its grid modes keep the reference's
/// poles), over the whole grid against the reference, every scheme tuned by linearisation: what
/// the contact's time step costs issue 15's band levels, and what halving it costs in time.
fn fine_rates_grid() {
    let points = full_grid();
    let rates = [1usize, 2];
    let results = measure_all(&points, |point| {
        let reference = grid_render_linearised(Quality::Reference, point, SAMPLE_RATE_HZ, 0);
        let (settings, pluck) = grid_pluck(Quality::Fine, point);
        let nominal = point.nominal_hz();
        rates.map(|oversample| {
            let variant = ModalVariant {
                oversample,
                grid_modes: true,
                ..ModalVariant::default()
            };
            let started = std::time::Instant::now();
            let output = modal_variant_pluck(
                &settings,
                &variant,
                &pluck,
                javari_core::analysis::playing_range::NOTE_SECONDS,
                SAMPLE_RATE_HZ,
            )
            .expect("the fine tier is modal");
            let seconds = started.elapsed().as_secs_f64();
            (
                compare(&output, &reference, SAMPLE_RATE_HZ, nominal),
                seconds,
            )
        })
    });
    println!(
        "The fine tier's string over {} plucks against the reference, tuned by linearisation, \
         worst / median (pitch cents, band levels dB, centroid %); render seconds in all:",
        points.len()
    );
    for (column, oversample) in rates.iter().enumerate() {
        let differences: Vec<&ListeningDifference> =
            results.iter().map(|row| &row[column].0).collect();
        let seconds: f64 = results.iter().map(|row| row[column].1).sum();
        let figures = summary(&differences)
            .map(|(worst, median)| format!("{worst:5.2} / {median:4.2}"))
            .join(", ");
        let worst_bands = points
            .iter()
            .zip(&results)
            .max_by(|a, b| {
                a.1[column]
                    .0
                    .band_level_db
                    .total_cmp(&b.1[column].0.band_level_db)
            })
            .map(|(point, _)| point.label())
            .unwrap_or_default();
        println!(
            "at {oversample}x the output rate: {figures} | band levels worst at {worst_bands} | \
             {seconds:.1} s"
        );
    }
}

/// Each variant of the live tier's string over the whole grid, against N = 800 at 16× and
/// against the reference, all tuned by linearisation: worst / median of each measure, over every
/// pluck and over the plucks away from the crest keys (`playing_range::CREST_KEYS`).
fn variants_over_grid(variants: &[(String, ModalVariant)]) {
    let points = full_grid();
    let results = measure_all(&points, |point| {
        let refined = grid_render_refined(point, SAMPLE_RATE_HZ);
        let reference = grid_render_linearised(Quality::Reference, point, SAMPLE_RATE_HZ, 0);
        let (settings, pluck) = grid_pluck(Quality::Live, point);
        let nominal = point.nominal_hz();
        variants
            .iter()
            .map(|(_, variant)| {
                let output = live_variant_render(&settings, variant, &pluck);
                [
                    compare(&output, &refined, SAMPLE_RATE_HZ, nominal),
                    compare(&output, &reference, SAMPLE_RATE_HZ, nominal),
                ]
            })
            .collect::<Vec<_>>()
    });
    println!(
        "The live tier's string over {} plucks, worst / median (pitch cents, band levels dB, \
         centroid %):",
        points.len()
    );
    for (column, (name, _)) in variants.iter().enumerate() {
        let against = |which: usize, away_from_crest: bool| {
            let differences: Vec<&ListeningDifference> = points
                .iter()
                .zip(&results)
                .filter(|(point, _)| !away_from_crest || !CREST_KEYS.contains(&point.key))
                .map(|(_, row)| &row[column][which])
                .collect();
            summary(&differences)
                .map(|(worst, median)| format!("{worst:5.2} / {median:4.2}"))
                .join(", ")
        };
        println!(
            "{name} | against N = 800: {} | against the reference: {}",
            against(0, false),
            against(1, false)
        );
        println!(
            "{name}, away from keys {}-{} | against N = 800: {} | against the reference: {}",
            CREST_KEYS.start(),
            CREST_KEYS.end(),
            against(0, true),
            against(1, true)
        );
        let worst_at = |measure: fn(&ListeningDifference) -> f64| {
            points
                .iter()
                .zip(&results)
                .max_by(|a, b| measure(&a.1[column][1]).total_cmp(&measure(&b.1[column][1])))
                .map(|(point, _)| point.label())
                .unwrap_or_default()
        };
        println!(
            "{name}, worst against the reference | pitch at {} | band levels at {} | centroid at {}",
            worst_at(|d| d.sustained_cents.abs()),
            worst_at(|d| d.band_level_db),
            worst_at(|d| d.centroid_error)
        );
    }
}

/// The upper median, as the bench takes it.
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// `--yardstick-check`: how far the yardstick itself moves when refined twice more (N = 1600 at
/// 32×), at keys 51, 57 and 60, velocities 40 and 127, plucked at 0.20 m (about a minute and a
/// half on two cores).
fn yardstick_check() {
    let points: Vec<GridPoint> = [51, 57, 60]
        .into_iter()
        .flat_map(|key| {
            [40, 127].map(|velocity| GridPoint {
                key,
                velocity,
                pluck_position_m: 0.20,
            })
        })
        .collect();
    let (intervals, oversample) = yardstick_grid();
    println!(
        "N = {intervals} at {oversample}× against N = {} at {}× (cents, band levels dB, centroid %):",
        2 * intervals,
        2 * oversample
    );
    let differences = measure_all(&points, |point| {
        let (settings, pluck) = grid_pluck(Quality::Reference, point);
        let finer = refined_reference_pluck(
            &settings,
            2 * YARDSTICK_REFINEMENT,
            &pluck,
            javari_core::analysis::playing_range::NOTE_SECONDS,
            SAMPLE_RATE_HZ,
        )
        .expect("the reference tier is an FD tier")
        .output;
        let yardstick = grid_render_refined(point, SAMPLE_RATE_HZ);
        compare(&yardstick, &finer, SAMPLE_RATE_HZ, point.nominal_hz())
    });
    for (point, d) in points.iter().zip(differences) {
        println!(
            "{:<36} {:6.2} {:5.1} {:6.1}",
            point.label(),
            d.sustained_cents,
            d.band_level_db,
            100.0 * d.centroid_error
        );
    }
}

/// The pluck named by the three arguments after `flag` (KEY VELOCITY POSITION_M), and where
/// `flag` stands.
fn pluck_after(args: &[String], flag: &str) -> (usize, GridPoint) {
    let at = args
        .iter()
        .position(|arg| arg == flag)
        .unwrap_or_else(|| panic!("called without {flag}"));
    let number = |offset: usize, what: &str| -> f64 {
        args.get(at + offset)
            .and_then(|value| value.parse().ok())
            .unwrap_or_else(|| panic!("{flag} KEY VELOCITY POSITION_M: {what} missing"))
    };
    let point = GridPoint {
        key: number(1, "key") as u8,
        velocity: number(2, "velocity") as u8,
        pluck_position_m: number(3, "pluck position"),
    };
    (at, point)
}

/// `--space-time KEY VELOCITY POSITION_M [GRIDS]`: one pluck of the grid on the seed's scheme
/// on other grids (GRIDS such as `200x4,400x2`, N intervals at an oversampling; default N = 200
/// and 400 at 2×, 4×, 8× and 16×, N = 300 and 400 at 3× and N = 800 at 4×) against the yardstick,
/// with each render's wall time (one at a time): whether the reference's distance from it is
/// spatial or temporal (`docs/modal-tanpura.md` §9, "Stop 35").
fn space_time(args: &[String]) {
    let (at, point) = pluck_after(args, "--space-time");
    let grids: Vec<(usize, usize)> = match args.get(at + 4) {
        Some(list) => list
            .split(',')
            .map(|grid| {
                grid.split_once('x')
                    .and_then(|(n, o)| Some((n.parse().ok()?, o.parse().ok()?)))
                    .expect("grids such as 200x4,400x2")
            })
            .collect(),
        None => [200, 400]
            .into_iter()
            .flat_map(|intervals| [2, 4, 8, 16].map(|oversample| (intervals, oversample)))
            .chain([(300, 3), (400, 3), (800, 4)])
            .collect(),
    };
    let (intervals, oversample) = yardstick_grid();
    println!(
        "{} on the seed's scheme against N = {intervals} at {oversample}× (cents, band levels dB, centroid %, render s), tuned by linearisation:",
        point.label()
    );
    let yardstick = grid_render_refined(&point, SAMPLE_RATE_HZ);
    let (settings, pluck) = grid_pluck(Quality::Reference, &point);
    for (intervals, oversample) in grids {
        let started = std::time::Instant::now();
        let output = reference_pluck_on_grid(
            &settings,
            intervals,
            oversample,
            &pluck,
            javari_core::analysis::playing_range::NOTE_SECONDS,
            SAMPLE_RATE_HZ,
        )
        .expect("the reference tier is an FD tier")
        .output;
        let seconds = started.elapsed().as_secs_f64();
        let d = compare(&output, &yardstick, SAMPLE_RATE_HZ, point.nominal_hz());
        println!(
            "N = {intervals:<4} at {oversample:>2}×  {:6.2} {:5.1} {:6.1} {seconds:6.2}",
            d.sustained_cents,
            d.band_level_db,
            100.0 * d.centroid_error
        );
    }
}

/// `--live-variants KEY VELOCITY POSITION_M`: one pluck of the grid on the live tier's string as
/// it is, run at 2× and 4× the output rate and decimated, with the bridge's points every 1,
/// 0.5 and 0.25 mm, and on grid modes with the reference's points at 1×, 2× and 4×, against the
/// reference tier and against the yardstick, all tuned by linearisation: whether the live tier's
/// distance from the reference comes from its time step or its bridge points
/// (`docs/modal-tanpura.md` §9, "Stop 35"), and the grid modes' from their time step (§10).
fn live_variants(args: &[String]) {
    let (_, point) = pluck_after(args, "--live-variants");
    let variants = [
        ("the live tier", ModalVariant::default()),
        (
            "at 2× the output rate",
            ModalVariant {
                oversample: 2,
                ..ModalVariant::default()
            },
        ),
        (
            "at 4× the output rate",
            ModalVariant {
                oversample: 4,
                ..ModalVariant::default()
            },
        ),
    ]
    .into_iter()
    .chain(
        [
            ("bridge points every 1 mm", 1.0e-3),
            ("every 0.5 mm", 0.5e-3),
            ("every 0.25 mm", 0.25e-3),
        ]
        .map(|(name, spacing_m)| {
            let variant = ModalVariant {
                bridge_point_spacing_m: Some(spacing_m),
                ..ModalVariant::default()
            };
            (name, variant)
        }),
    )
    .chain(
        [
            ("grid modes, fine points", 1),
            ("the same at 2x", 2),
            ("the same at 4x", 4),
        ]
        .map(|(name, oversample)| {
            let variant = ModalVariant {
                grid_modes: true,
                bridge_point_spacing_m: Some(0.18e-3),
                thread_point_spacing_m: Some(0.15e-3),
                oversample,
                ..ModalVariant::default()
            };
            (name, variant)
        }),
    );
    let reference = grid_render_linearised(Quality::Reference, &point, SAMPLE_RATE_HZ, 0);
    let yardstick = grid_render_refined(&point, SAMPLE_RATE_HZ);
    let (settings, pluck) = grid_pluck(Quality::Live, &point);
    println!(
        "{}, tuned by linearisation: against the reference tier | against the yardstick (cents, band levels dB, centroid %)",
        point.label()
    );
    for (name, variant) in variants {
        let output = live_variant_render(&settings, &variant, &pluck);
        let row = |against: &[f64]| {
            let d = compare(&output, against, SAMPLE_RATE_HZ, point.nominal_hz());
            format!(
                "{:6.2} {:5.1} {:6.1}",
                d.sustained_cents,
                d.band_level_db,
                100.0 * d.centroid_error
            )
        };
        println!("{name:<26} {} | {}", row(&reference), row(&yardstick));
    }
}

/// Per band of [`band_edges_hz`]: the RMS and the mean over the frames of `render`'s level less
/// `reference`'s, counted as the band-level measure counts it
/// ([`counted_band_differences_db`]), and in how many frames the band counted.
fn band_differences(render: &[f64], reference: &[f64]) -> Vec<(f64, f64, usize)> {
    let (mine, theirs) = (
        band_levels_db(render, SAMPLE_RATE_HZ),
        band_levels_db(reference, SAMPLE_RATE_HZ),
    );
    let bands = theirs.first().map_or(0, Vec::len);
    let mut sums = vec![(0.0, 0.0, 0usize); bands];
    for (frame, reference_frame) in mine.iter().zip(&theirs) {
        for (band, difference) in counted_band_differences_db(frame, reference_frame) {
            sums[band].0 += difference.powi(2);
            sums[band].1 += difference;
            sums[band].2 += 1;
        }
    }
    sums.into_iter()
        .map(|(squares, sum, count)| {
            let frames = count.max(1) as f64;
            ((squares / frames).sqrt(), sum / frames, count)
        })
        .collect()
}

/// `--bands KEY VELOCITY POSITION_M [--as-played]`: one pluck of the grid on the reference, the
/// fine and the studio tier and the refined string, all tuned by linearisation (with
/// `--as-played` the three tiers calibrated as played, as the bench's grid renders them; the
/// refined string stays linearised): each pair's band-level distance (the bench's measure), then
/// band by band the reference's mean level, each difference's RMS over the frames and the fine
/// tier's mean difference (see [`band_differences`]): which bands part the tiers, which way,
/// and whether the reference is nearer the refined string there than the fine tier is.
fn bands(args: &[String]) {
    let (_, point) = pluck_after(args, "--bands");
    let as_played = args.iter().any(|arg| arg == "--as-played");
    let render = |quality| {
        if as_played {
            let calibration = calibrate(quality, point.key, point.pluck_position_m, SAMPLE_RATE_HZ);
            render_as_played(quality, &point, NOTE_SECONDS, SAMPLE_RATE_HZ, &calibration)
        } else {
            grid_render_linearised(quality, &point, SAMPLE_RATE_HZ, 0)
        }
    };
    let (reference, fine, studio) = (
        render(Quality::Reference),
        render(Quality::Fine),
        render(Quality::Studio),
    );
    let refined = grid_render_refined(&point, SAMPLE_RATE_HZ);
    let nominal = point.nominal_hz();
    let distance = |a: &[f64], b: &[f64]| compare(a, b, SAMPLE_RATE_HZ, nominal).band_level_db;
    let tuning = if as_played {
        "the tiers tuned as played, the refined string by linearisation"
    } else {
        "tuned by linearisation"
    };
    println!("{}, {tuning}: band-level distances (dB RMS)", point.label());
    for (label, render, against) in [
        ("fine against the reference", &fine, &reference),
        ("studio against the reference", &studio, &reference),
        ("the reference against refined", &reference, &refined),
        ("fine against refined", &fine, &refined),
        ("studio against refined", &studio, &refined),
    ] {
        println!("  {label:<32} {:5.2}", distance(render, against));
    }
    let levels = band_levels_db(&reference, SAMPLE_RATE_HZ);
    let pairs = [
        band_differences(&fine, &reference),
        band_differences(&studio, &reference),
        band_differences(&reference, &refined),
        band_differences(&fine, &refined),
    ];
    println!("band centre Hz, reference mean dB, frames counted; RMS dB: fine−ref, studio−ref, ref−refined, fine−refined; mean dB: fine−ref");
    for (band, edges) in band_edges_hz(SAMPLE_RATE_HZ).windows(2).enumerate() {
        let mean = levels.iter().map(|frame| frame[band]).sum::<f64>() / levels.len().max(1) as f64;
        println!(
            "{:8.0} {:7.1} {:3} {:6.2} {:6.2} {:6.2} {:6.2} {:+6.2}",
            (edges[0] * edges[1]).sqrt(),
            mean,
            pairs[0][band].2,
            pairs[0][band].0,
            pairs[1][band].0,
            pairs[2][band].0,
            pairs[3][band].0,
            pairs[0][band].1
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|arg| arg == "--bands") {
        bands(&args);
        return;
    }
    if args.iter().any(|arg| arg == "--yardstick-check") {
        yardstick_check();
        return;
    }
    if args.iter().any(|arg| arg == "--space-time") {
        space_time(&args);
        return;
    }
    if args.iter().any(|arg| arg == "--live-variants") {
        live_variants(&args);
        return;
    }
    if args.iter().any(|arg| arg == "--grid-spacings") {
        grid_spacings_grid();
        return;
    }
    if args.iter().any(|arg| arg == "--grid-modes") {
        grid_modes_grid();
        return;
    }
    if args.iter().any(|arg| arg == "--fine-rates") {
        fine_rates_grid();
        return;
    }
    if args.iter().any(|arg| arg == "--rate-grid") {
        rate_grid();
        return;
    }
    let residual_modes = residual_modes(&args);
    let positions: Option<Vec<f64>> =
        args.get(1)
            .filter(|arg| !arg.starts_with("--"))
            .map(|list| {
                list.split(',')
                    .map(|p| p.parse().expect("positions in metres, such as 0.2,0.35"))
                    .collect()
            });
    let points: Vec<GridPoint> = full_grid()
        .into_iter()
        .filter(|point| {
            positions.as_ref().is_none_or(|list| {
                list.iter()
                    .any(|p| (p - point.pluck_position_m).abs() < 1e-9)
            })
        })
        .collect();
    let results: Vec<(usize, Vec<ListeningDifference>)> =
        measure_all(&points, |point| measure(point, residual_modes))
            .into_iter()
            .enumerate()
            .collect();

    let (intervals, oversample) = yardstick_grid();
    println!(
        "Against N = {intervals} at {oversample}× (cents, band levels dB, centroid %), tuned by \
         linearisation, modal tiers with {residual_modes} residual modes:"
    );
    print!("{:<36}", "pluck");
    for quality in TIERS {
        print!(" | {:^20}", quality.name());
    }
    println!();
    for (index, differences) in &results {
        print!("{:<36}", points[*index].label());
        for difference in differences {
            print!(
                " | {:6.2} {:5.1} {:6.1}",
                difference.sustained_cents,
                difference.band_level_db,
                100.0 * difference.centroid_error
            );
        }
        println!();
    }
    println!("\nWorst / median over {} plucks:", results.len());
    for (tier, quality) in TIERS.iter().enumerate() {
        let column: Vec<&ListeningDifference> = results
            .iter()
            .map(|(_, differences)| &differences[tier])
            .collect();
        let [pitch, bands, centroid] = summary(&column);
        let nearer = results
            .iter()
            .filter(|(_, d)| d[tier].band_level_db < d[0].band_level_db)
            .count();
        println!(
            "{:<9} pitch {:6.2} / {:4.2} cents, band levels {:5.1} / {:4.1} dB, centroid {:5.1} / \
             {:4.1} %; band levels nearer than the reference's at {nearer} plucks",
            quality.name(),
            pitch.0,
            pitch.1,
            bands.0,
            bands.1,
            centroid.0,
            centroid.1,
        );
    }
}
