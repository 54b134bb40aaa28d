//! `cargo xtask stability`: Woodhouse's linearised stability analysis of Helmholtz motion
//! (seed 001; `javari_core::stability`).
//!
//! Three modes:
//!
//! - one case: `--p P --q Q --lambda L --gamma G [--sigma S] [--slip N] [--zeta Z]
//!   [--formulation spacetime|compact] [--json]` prints the threshold ζ_c, α = ζ/ε and the
//!   eigenvalues (by decreasing modulus) at `--zeta`, or at the threshold when it is absent;
//! - a sweep: `--sweep fig7|fig8|fig13|fig10 [--csv FILE] [--png FILE]` recomputes the paper's
//!   threshold curves;
//! - a preset: `--preset FILE [--json]` prints the stability margin of a bowed setting, either an
//!   analysis-grid setting (keys below) or one of the instrument's bowed presets
//!   (`presets/bowed-*.toml`, checked across the string's range).
//!
//! `--slip N` counts slipping steps per period in the chosen formulation's own time step. The
//! space-time step is one segment's travel: a period has 2(p + q) steps and the Helmholtz motion
//! slips for 2p of them (eq. 15); Fig. 8's regime is `--slip p` (eq. 16). The compact step is two
//! space-time steps: a period has p + q steps and the Helmholtz motion slips for p. The default is
//! the Helmholtz value. `--sigma` selects the three-tap rounded corner of eq. 22 (compact only);
//! α is then ζ/(1 − λ − 2σ) and `null` for a lossless pulse (λ + 2σ = 1, eq. 23).

use crate::args::{number_in, number_where};
use crate::plot::{self, AxisScale, LinePlot, Series, SeriesStyle, PALETTE};
use clap::{Parser, ValueEnum};
use javari_core::engine::bowed_stability::bowed_stability;
use javari_core::engine::preset::Preset as EnginePreset;
use javari_core::engine::{BowedStringKind, Instrument};
use javari_core::stability::{
    stability_margin, BowedSetting, CompactModel, ContactPattern, Eigenvalue, PeriodicMotion,
    ReflectionFunction, SpaceTimeModel, StabilityMargin, ThresholdOutcome, ThresholdSearch,
    TransferModel,
};
use rayon::prelude::*;
use std::error::Error;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Largest p or q accepted: the space-time matrix has 2(p + q) rows.
const MAX_SEGMENTS: usize = 500;

/// The termination reflection of Figs. 7, 8, 10 and 13 (section 2.4).
const SWEEP_LAMBDA: f64 = 0.9995;

#[derive(Debug, Clone, Copy, PartialEq, ValueEnum)]
enum Formulation {
    /// Eq. 14–16: one state per segment, Raman's model only.
    #[value(name = "spacetime")]
    SpaceTime,
    /// Eq. 21–22: half the size, also the three-tap rounded corner.
    Compact,
}

#[derive(Debug, Clone, PartialEq)]
struct CaseOptions {
    p: usize,
    q: usize,
    lambda: f64,
    gamma: f64,
    sigma: Option<f64>,
    slip: Option<usize>,
    zeta: Option<f64>,
    formulation: Formulation,
    json: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, ValueEnum)]
enum Figure {
    Fig7,
    Fig8,
    Fig13,
    Fig10,
}

#[derive(Debug, Clone, PartialEq)]
enum Command {
    Case(CaseOptions),
    Sweep {
        figure: Figure,
        csv: Option<PathBuf>,
        png: Option<PathBuf>,
    },
    Preset {
        path: PathBuf,
        json: bool,
    },
}

/// The options of a single case, which `--sweep` and `--preset` replace.
const CASE_OPTIONS: [&str; 8] = [
    "p",
    "q",
    "lambda",
    "gamma",
    "sigma",
    "slip",
    "zeta",
    "formulation",
];

/// One case: `--p P --q Q --lambda L --gamma G [--sigma S] [--slip N] [--zeta Z]
/// [--formulation spacetime|compact] [--json]`; a sweep: `--sweep FIG [--csv FILE] [--png FILE]`;
/// a preset's margin: `--preset FILE [--json]`.
#[derive(Debug, Parser)]
pub struct StabilityArgs {
    /// Bridge-side segments (1 to 500).
    #[arg(long, value_name = "P", required_unless_present_any = ["sweep", "preset"],
          value_parser = number_in(1usize, MAX_SEGMENTS))]
    p: Option<usize>,
    /// Finger-side segments (1 to 500).
    #[arg(long, value_name = "Q", required_unless_present_any = ["sweep", "preset"],
          value_parser = number_in(1usize, MAX_SEGMENTS))]
    q: Option<usize>,
    /// Termination reflection magnitude (0 < lambda <= 1).
    #[arg(long, value_name = "L", required_unless_present_any = ["sweep", "preset"],
          value_parser = number_where(|value| value > 0.0 && value <= 1.0, "a number above 0 and up to 1"))]
    lambda: Option<f64>,
    /// Sticking reflection magnitude (0 to 1).
    #[arg(long, value_name = "G", required_unless_present_any = ["sweep", "preset"],
          value_parser = number_in(0.0, 1.0))]
    gamma: Option<f64>,
    /// Side taps of the three-tap rounded corner of eq. 22 (0 to 1; compact only).
    #[arg(long, value_name = "S", value_parser = number_in(0.0, 1.0))]
    sigma: Option<f64>,
    /// Slipping steps per period in the formulation's own step (default: Helmholtz).
    #[arg(long, value_name = "N")]
    slip: Option<usize>,
    /// Where the eigenvalues are evaluated (-1 to 1e6; default: at the threshold).
    #[arg(long, value_name = "Z", value_parser = number_in(-1.0, 1e6))]
    zeta: Option<f64>,
    /// State-vector formulation.
    #[arg(long, value_enum, default_value_t = Formulation::Compact)]
    formulation: Formulation,
    /// Print one JSON object (a case) or array (an instrument preset).
    #[arg(long, conflicts_with = "sweep")]
    json: bool,
    /// Recompute one of the paper's threshold figures.
    #[arg(long, value_enum, value_name = "FIG", conflicts_with_all = CASE_OPTIONS)]
    sweep: Option<Figure>,
    /// Write the sweep as CSV (else it is printed).
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Plot the sweep as PNG.
    #[arg(long, value_name = "FILE")]
    png: Option<PathBuf>,
    /// Margin of a bowed setting: an analysis-grid file or presets/bowed-*.toml.
    #[arg(long, value_name = "FILE", conflicts_with_all = CASE_OPTIONS, conflicts_with = "sweep")]
    preset: Option<PathBuf>,
}

pub fn run(args: StabilityArgs) -> Result<(), Box<dyn Error>> {
    let command = command(args).unwrap_or_else(|message| {
        crate::usage_error("stability", message).exit();
    });
    print!("{}", execute(&command)?);
    Ok(())
}

/// What to compute, or why the options do not fit together.
fn command(args: StabilityArgs) -> Result<Command, String> {
    if let Some(figure) = args.sweep {
        return Ok(Command::Sweep {
            figure,
            csv: args.csv,
            png: args.png,
        });
    }
    // (clap's `requires` would be waived here: `--sweep` conflicts with the case options.)
    if args.csv.is_some() || args.png.is_some() {
        let option = if args.csv.is_some() { "--csv" } else { "--png" };
        return Err(format!(
            "option `{option}` writes a sweep: it needs `--sweep`"
        ));
    }
    if let Some(path) = args.preset {
        return Ok(Command::Preset {
            path,
            json: args.json,
        });
    }
    // clap has checked that these are present when there is neither a sweep nor a preset.
    let (Some(p), Some(q), Some(lambda), Some(gamma)) = (args.p, args.q, args.lambda, args.gamma)
    else {
        return Err("options `--p`, `--q`, `--lambda` and `--gamma` are required".into());
    };
    let formulation = args.formulation;
    let period = match formulation {
        Formulation::SpaceTime => 2 * (p + q),
        Formulation::Compact => p + q,
    };
    if let Some(slip) = args.slip.filter(|&slip| slip > period) {
        return Err(format!(
            "option `--slip`: {slip} is out of range, expected a number from 0 to {period}"
        ));
    }
    let sigma = args.sigma;
    if sigma.is_some() && formulation == Formulation::SpaceTime {
        return Err(
            "option `--sigma`: the three-tap reflection function needs `--formulation compact` \
             (the space-time formulation is Raman's model only)"
                .into(),
        );
    }
    if sigma.is_some() && p < 2 {
        return Err(format!(
            "option `--p`: {p} is out of range, the three-tap reflection function (--sigma) needs \
             p of at least 2"
        ));
    }
    Ok(Command::Case(CaseOptions {
        p,
        q,
        lambda,
        gamma,
        sigma,
        slip: args.slip,
        zeta: args.zeta,
        formulation,
        json: args.json,
    }))
}

fn execute(command: &Command) -> Result<String, Box<dyn Error>> {
    match command {
        Command::Case(options) => run_case(options),
        Command::Sweep { figure, csv, png } => run_sweep(*figure, csv.as_deref(), png.as_deref()),
        Command::Preset { path, json } => {
            let text = std::fs::read_to_string(path)
                .map_err(|error| format!("preset `{}`: {error}", path.display()))?;
            if is_engine_preset(&text) {
                return engine_preset_report(&text, path, *json);
            }
            let setting = parse_preset(&text)
                .map_err(|error| format!("preset `{}`: {error}", path.display()))?;
            let margin = stability_margin(&setting)?;
            Ok(if *json {
                margin_json(&margin)
            } else {
                margin_text(&setting, &margin)
            })
        }
    }
}

/// Whether a preset file is one of the instrument's (`presets/*.toml`, with an `instrument`
/// key) rather than an analysis-grid setting.
fn is_engine_preset(text: &str) -> bool {
    text.lines()
        .any(|line| line.trim_start().starts_with("instrument"))
}

/// Notes at which a bowed instrument preset is checked: the string's playable range in steps
/// of a fifth (violin A: G3 to E6; cello D: C2 to C5).
fn preset_notes(string: BowedStringKind) -> Vec<u8> {
    let (low, high) = match string {
        BowedStringKind::ViolinA => (55u8, 88u8),
        BowedStringKind::CelloD => (36, 72),
    };
    (low..=high).step_by(7).collect()
}

/// The margin of an instrument preset's bow (its pressure, speed and position) across the
/// string's range, one line per note, or a JSON array.
fn engine_preset_report(text: &str, path: &Path, json: bool) -> Result<String, Box<dyn Error>> {
    let file = path.display().to_string();
    let preset = EnginePreset::parse(text, &file)?;
    if preset.settings.instrument != Instrument::Bowed {
        return Err(format!(
            "preset `{file}`: `instrument` is \"tanpura\"; the stability analysis is for bowed presets"
        )
        .into());
    }
    let mut lines = Vec::new();
    for note in preset_notes(preset.settings.bowed.string) {
        let verdict = bowed_stability(&preset.settings.bowed, note)?;
        lines.push(if json {
            format!(
                "{{\"note\": {note}, \"bow_force_n\": {:.6}, \"critical_bow_force_n\": {}, \"margin\": {:.6}, \"stable\": {}}}",
                verdict.bow_force_n,
                verdict
                    .critical_bow_force_n
                    .map_or("null".to_string(), |force| format!("{force:.6}")),
                verdict.margin,
                verdict.stable
            )
        } else {
            format!(
                "note {note:3}: bow force {:.3} N, critical {}, margin {:.2}: {}",
                verdict.bow_force_n,
                verdict
                    .critical_bow_force_n
                    .map_or("none".to_string(), |force| format!("{force:.3} N")),
                verdict.margin,
                if verdict.stable { "STABLE" } else { "UNSTABLE" }
            )
        });
    }
    Ok(if json {
        format!("[{}]\n", lines.join(", "))
    } else {
        format!(
            "preset `{}` ({}):\n{}\n",
            preset.name,
            file,
            lines.join("\n")
        )
    })
}

/// The analysis of one case: threshold and spectrum.
struct CaseResult {
    outcome: ThresholdOutcome,
    spectrum: Vec<Eigenvalue>,
    evaluated_at: f64,
    size: usize,
}

fn analyse<M: TransferModel>(
    motion: PeriodicMotion<M>,
    zeta: Option<f64>,
) -> Result<CaseResult, Box<dyn Error>> {
    let outcome = ThresholdSearch::default().run(&motion)?;
    let (spectrum, evaluated_at) = match (zeta, &outcome) {
        (Some(zeta), _) => (motion.spectrum(zeta)?, zeta),
        (None, ThresholdOutcome::Crossing(threshold)) => {
            (threshold.spectrum.clone(), threshold.zeta)
        }
        (None, ThresholdOutcome::StableUpTo { zeta_max }) => {
            (motion.spectrum(*zeta_max)?, *zeta_max)
        }
        (None, ThresholdOutcome::UnstableFrom { zeta_min, spectrum }) => {
            (spectrum.clone(), *zeta_min)
        }
    };
    Ok(CaseResult {
        outcome,
        spectrum,
        evaluated_at,
        size: motion.model.state_len(),
    })
}

fn case_result(options: &CaseOptions) -> Result<CaseResult, Box<dyn Error>> {
    let (p, q) = (options.p, options.q);
    match options.formulation {
        Formulation::SpaceTime => {
            let pattern = ContactPattern::single_slip(2 * (p + q), options.slip.unwrap_or(2 * p))?;
            let model = SpaceTimeModel::new(p, q, options.lambda)?;
            analyse(
                PeriodicMotion::new(model, pattern, options.gamma)?,
                options.zeta,
            )
        }
        Formulation::Compact => {
            let pattern = ContactPattern::single_slip(p + q, options.slip.unwrap_or(p))?;
            let model = match options.sigma {
                Some(sigma) => CompactModel::three_tap(p, q, options.lambda, sigma)?,
                None => CompactModel::raman(p, q, options.lambda)?,
            };
            analyse(
                PeriodicMotion::new(model, pattern, options.gamma)?,
                options.zeta,
            )
        }
    }
}

fn json_number(value: f64) -> String {
    if value.is_finite() {
        format!("{value}")
    } else {
        "null".into()
    }
}

fn eigenvalue_json(eigenvalue: &Eigenvalue) -> String {
    format!(
        "{{\"abs\": {}, \"phase_over_2pi\": {}, \"subharmonic_order\": {}}}",
        json_number(eigenvalue.modulus),
        json_number(eigenvalue.phase_over_2pi),
        eigenvalue.subharmonic_order
    )
}

/// α = ζ/ε (eq. 13), where ε = 1 − |area| is the loss of each termination's reflection
/// function (1 − λ in Raman's model, 1 − λ − 2σ for the three-tap one); undefined when lossless.
fn alpha(zeta: f64, reflection_area: f64) -> f64 {
    let epsilon = 1.0 - reflection_area;
    if epsilon > 0.0 {
        zeta / epsilon
    } else {
        f64::NAN
    }
}

fn reflection_area(options: &CaseOptions) -> f64 {
    options.lambda + 2.0 * options.sigma.unwrap_or(0.0)
}

fn run_case(options: &CaseOptions) -> Result<String, Box<dyn Error>> {
    let result = case_result(options)?;
    let threshold = result.outcome.crossing();
    let zeta_c = threshold.map_or(f64::NAN, |threshold| threshold.zeta);
    if options.json {
        let critical = threshold.map_or("null".to_string(), |threshold| {
            eigenvalue_json(&threshold.critical)
        });
        let eigenvalues: Vec<String> = result.spectrum.iter().map(eigenvalue_json).collect();
        return Ok(format!(
            "{{\"zeta_c\": {}, \"alpha\": {}, \"critical\": {critical}, \"eigenvalues\": [{}]}}\n",
            json_number(zeta_c),
            json_number(alpha(zeta_c, reflection_area(options))),
            eigenvalues.join(", ")
        ));
    }
    let mut text = String::new();
    let formulation = match options.formulation {
        Formulation::SpaceTime => "space-time",
        Formulation::Compact => "compact",
    };
    writeln!(
        text,
        "{formulation} formulation, p = {}, q = {}, state size {}, lambda = {}, gamma = {}{}",
        options.p,
        options.q,
        result.size,
        options.lambda,
        options.gamma,
        options
            .sigma
            .map_or(String::new(), |sigma| format!(", sigma = {sigma}"))
    )?;
    match &result.outcome {
        ThresholdOutcome::Crossing(threshold) => writeln!(
            text,
            "threshold zeta_c = {:.10} (alpha = {:.6}), critical |mu| = {:.6}, phase/2pi = {:.4}, \
             subharmonic order {}",
            threshold.zeta,
            alpha(threshold.zeta, reflection_area(options)),
            threshold.critical.modulus,
            threshold.critical.phase_over_2pi,
            threshold.critical.subharmonic_order
        )?,
        ThresholdOutcome::StableUpTo { zeta_max } => {
            writeln!(text, "stable for every zeta up to {zeta_max}")?
        }
        ThresholdOutcome::UnstableFrom { zeta_min, .. } => {
            writeln!(text, "unstable already at zeta = {zeta_min}")?
        }
    }
    writeln!(text, "eigenvalues at zeta = {}:", result.evaluated_at)?;
    writeln!(text, "  |mu|        phase/2pi  order")?;
    for eigenvalue in &result.spectrum {
        writeln!(
            text,
            "  {:<10.6}  {:>8.4}  {:>5}",
            eigenvalue.modulus, eigenvalue.phase_over_2pi, eigenvalue.subharmonic_order
        )?;
    }
    Ok(text)
}

/// One point of a sweep.
struct SweepRow {
    p: usize,
    q: usize,
    slip_steps: usize,
    formulation: Formulation,
    zeta_c: f64,
    order: Option<u32>,
}

fn sweep_rows(figure: Figure) -> Result<Vec<SweepRow>, Box<dyn Error>> {
    let search = ThresholdSearch::default();
    // (p, q, slipping steps) of every case of the figure.
    let cases: Vec<(usize, usize, usize)> = match figure {
        Figure::Fig7 | Figure::Fig8 | Figure::Fig13 => (1..=10)
            .flat_map(|p| (p..=20).map(move |q| (p, q, p)))
            .collect(),
        Figure::Fig10 => [(3, 16), (4, 15), (5, 14), (6, 13), (7, 12)]
            .into_iter()
            .flat_map(|(p, q)| (1..=30).map(move |slip| (p, q, slip)))
            .collect(),
    };
    // The cases are independent: rayon spreads them over the cores; `collect` keeps their order.
    let rows: Result<Vec<SweepRow>, String> = cases
        .par_iter()
        .map(|&(p, q, slip)| {
            sweep_case(&search, figure, p, q, slip)
                .map_err(|error| format!("p = {p}, q = {q}, slip = {slip}: {error}"))
        })
        .collect();
    Ok(rows?)
}

/// One case of a sweep: its threshold by the formulation the figure uses.
fn sweep_case(
    search: &ThresholdSearch,
    figure: Figure,
    p: usize,
    q: usize,
    slip_steps: usize,
) -> Result<SweepRow, Box<dyn Error>> {
    let (formulation, outcome) = match figure {
        Figure::Fig7 | Figure::Fig13 => {
            let gamma = if figure == Figure::Fig7 { 1.0 } else { 0.9 };
            // The compact formulation: the same spectrum as eq. 15, half the size.
            let motion = PeriodicMotion::new(
                CompactModel::raman(p, q, SWEEP_LAMBDA)?,
                ContactPattern::helmholtz_compact(p, q)?,
                gamma,
            )?;
            (Formulation::Compact, search.run(&motion)?)
        }
        // Fig. 8 — eq. 16: M₁^p M₂^{2q+p}, an odd slip count needs the space-time form — and
        // Fig. 10, the slip time swept.
        Figure::Fig8 | Figure::Fig10 => {
            let motion = PeriodicMotion::new(
                SpaceTimeModel::new(p, q, SWEEP_LAMBDA)?,
                ContactPattern::single_slip(2 * (p + q), slip_steps)?,
                1.0,
            )?;
            (Formulation::SpaceTime, search.run(&motion)?)
        }
    };
    let threshold = outcome.crossing();
    Ok(SweepRow {
        p,
        q,
        slip_steps,
        formulation,
        zeta_c: threshold.map_or(f64::NAN, |threshold| threshold.zeta),
        order: threshold.map(|threshold| threshold.critical.subharmonic_order),
    })
}

fn sweep_csv(rows: &[SweepRow]) -> String {
    let mut csv = String::from("p,q,beta,formulation,slip_steps,zeta_c,alpha,subharmonic_order\n");
    for row in rows {
        let formulation = match row.formulation {
            Formulation::SpaceTime => "spacetime",
            Formulation::Compact => "compact",
        };
        let _ = writeln!(
            csv,
            "{},{},{},{formulation},{},{},{},{}",
            row.p,
            row.q,
            row.p as f64 / (row.p + row.q) as f64,
            row.slip_steps,
            csv_number(row.zeta_c),
            csv_number(alpha(row.zeta_c, SWEEP_LAMBDA)),
            row.order.map_or(String::new(), |order| order.to_string())
        );
    }
    csv
}

fn csv_number(value: f64) -> String {
    if value.is_finite() {
        format!("{value}")
    } else {
        String::new()
    }
}

fn sweep_plot(figure: Figure, rows: &[SweepRow]) -> LinePlot {
    let beta = |row: &SweepRow| row.p as f64 / (row.p + row.q) as f64;
    match figure {
        Figure::Fig10 => {
            let mut series = Vec::new();
            for (index, (p, q)) in [(3, 16), (4, 15), (5, 14), (6, 13), (7, 12)]
                .into_iter()
                .enumerate()
            {
                let case: Vec<&SweepRow> =
                    rows.iter().filter(|row| row.p == p && row.q == q).collect();
                let mut line = Series::new(
                    format!("p:q = {p}:{q}"),
                    case.iter()
                        .map(|row| (row.slip_steps as f64, alpha(row.zeta_c, SWEEP_LAMBDA)))
                        .collect(),
                    PALETTE[index],
                );
                line.ringed = case
                    .iter()
                    .filter(|row| row.slip_steps == 2 * p)
                    .map(|row| (row.slip_steps as f64, alpha(row.zeta_c, SWEEP_LAMBDA)))
                    .collect();
                series.push(line);
            }
            LinePlot {
                title: "Fig. 10: threshold vs slip time (Raman, lambda = 0.9995; rings: Helmholtz)"
                    .into(),
                x_label: "slipping steps per period (space-time, period 38)".into(),
                y_label: "alpha = zeta / epsilon".into(),
                y_scale: AxisScale::Log10,
                right_label: None,
                series,
            }
        }
        _ => {
            let mut sorted: Vec<&SweepRow> = rows.iter().collect();
            sorted.sort_by(|a, b| beta(a).total_cmp(&beta(b)).then(a.p.cmp(&b.p)));
            let threshold = Series::new(
                "threshold alpha",
                sorted
                    .iter()
                    .map(|row| (beta(row), alpha(row.zeta_c, SWEEP_LAMBDA)))
                    .collect(),
                PALETTE[0],
            );
            let mut order = Series::new(
                "subharmonic order (right)",
                sorted
                    .iter()
                    .filter_map(|row| row.order.map(|order| (beta(row), f64::from(order))))
                    .collect(),
                PALETTE[1],
            );
            order.style = SeriesStyle::Dashed;
            order.right_axis = true;
            let (title, y_scale) = match figure {
                Figure::Fig7 => (
                    "Fig. 7: Helmholtz threshold, Raman model, lambda = 0.9995, gamma = 1",
                    AxisScale::Linear,
                ),
                Figure::Fig8 => (
                    "Fig. 8: slip time p (half Helmholtz), lambda = 0.9995, gamma = 1",
                    AxisScale::Linear,
                ),
                _ => (
                    "Fig. 13: Helmholtz threshold with torsion, gamma = 0.9",
                    AxisScale::Log10,
                ),
            };
            LinePlot {
                title: title.into(),
                x_label: "beta = p / (p + q)".into(),
                y_label: "alpha = zeta / epsilon".into(),
                y_scale,
                right_label: Some("subharmonic order".into()),
                series: vec![threshold, order],
            }
        }
    }
}

fn run_sweep(
    figure: Figure,
    csv: Option<&std::path::Path>,
    png: Option<&std::path::Path>,
) -> Result<String, Box<dyn Error>> {
    let rows = sweep_rows(figure)?;
    let table = sweep_csv(&rows);
    let mut report = String::new();
    match csv {
        Some(path) => {
            std::fs::write(path, &table)
                .map_err(|error| format!("--csv `{}`: {error}", path.display()))?;
            writeln!(report, "wrote {} ({} cases)", path.display(), rows.len())?;
        }
        None if png.is_none() => report.push_str(&table),
        None => {}
    }
    if let Some(path) = png {
        plot::line_plot(path, &sweep_plot(figure, &rows))?;
        writeln!(report, "wrote {}", path.display())?;
    }
    Ok(report)
}

/// Preset keys (one `key = value` per line, `#` starts a comment):
///
/// - `p`, `q` — bridge-side and finger-side round trips in analysis steps; or `beta` with
///   `steps` (p = round(β·steps), q = steps − p);
/// - `lambda` — termination reflection magnitude (0, 1]; `sigma` (optional) — the three-tap
///   rounded corner of eq. 22 with taps −[σ, λ, σ];
/// - `gamma` (optional, default 1) — sticking reflection magnitude [0, 1];
/// - `friction_slope` — k = dμ/dv at the operating point, s/m;
/// - `bow_force` — F_b, N; `admittance` — Y₀ = 1/Z₀, s/kg;
/// - `slip` (optional) — slipping steps per period (compact steps, default p).
const PRESET_KEYS: [&str; 11] = [
    "p",
    "q",
    "beta",
    "steps",
    "lambda",
    "sigma",
    "gamma",
    "friction_slope",
    "bow_force",
    "admittance",
    "slip",
];

fn parse_preset(text: &str) -> Result<BowedSetting, String> {
    let mut values = std::collections::BTreeMap::new();
    for (index, line) in text.lines().enumerate() {
        let line_number = index + 1;
        let content = line.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let Some((key, value)) = content.split_once('=') else {
            return Err(format!(
                "line {line_number}: expected `key = value`, got `{content}`"
            ));
        };
        let key = key.trim();
        if !PRESET_KEYS.contains(&key) {
            return Err(format!(
                "line {line_number}: unknown key `{key}`, expected one of {}",
                PRESET_KEYS.join(", ")
            ));
        }
        let value: f64 = value.trim().parse().map_err(|_| {
            format!(
                "line {line_number}: `{key}` = `{}` is not a number",
                value.trim()
            )
        })?;
        if !value.is_finite() {
            return Err(format!("line {line_number}: `{key}` must be finite"));
        }
        if values.insert(key.to_string(), value).is_some() {
            return Err(format!("line {line_number}: `{key}` is given twice"));
        }
    }
    let get = |key: &str| values.get(key).copied();
    let need = |key: &str, range: &str, valid: &dyn Fn(f64) -> bool| -> Result<f64, String> {
        let value = get(key).ok_or_else(|| format!("missing key `{key}` ({range})"))?;
        if valid(value) {
            Ok(value)
        } else {
            Err(format!(
                "`{key}` = {value} is out of range, expected {range}"
            ))
        }
    };
    let whole = |key: &str, value: f64| -> Result<usize, String> {
        if value.fract() == 0.0 && (1.0..=MAX_SEGMENTS as f64).contains(&value) {
            Ok(value as usize)
        } else {
            Err(format!(
                "`{key}` = {value} must be a whole number from 1 to {MAX_SEGMENTS}"
            ))
        }
    };
    let (p, q) = match (get("p"), get("q"), get("beta"), get("steps")) {
        (Some(p), Some(q), None, None) => (whole("p", p)?, whole("q", q)?),
        (None, None, Some(beta), Some(steps)) => {
            let steps = whole("steps", steps)?;
            if !(beta > 0.0 && beta < 1.0) {
                return Err(format!(
                    "`beta` = {beta} is out of range, expected 0 < beta < 1"
                ));
            }
            let p = (beta * steps as f64).round() as usize;
            if p == 0 || p >= steps {
                return Err(format!(
                    "`beta` = {beta} with `steps` = {steps} leaves no step on one side; use more steps"
                ));
            }
            (p, steps - p)
        }
        _ => {
            return Err(
                "give either `p` and `q`, or `beta` and `steps` (not both, not one alone)".into(),
            )
        }
    };
    let lambda = need("lambda", "0 < lambda <= 1", &|v| v > 0.0 && v <= 1.0)?;
    let gamma = get("gamma").unwrap_or(1.0);
    if !(0.0..=1.0).contains(&gamma) {
        return Err(format!(
            "`gamma` = {gamma} is out of range, expected 0 to 1"
        ));
    }
    let friction_slope = need("friction_slope", "a number in s/m", &|v| v.is_finite())?;
    let bow_force = need("bow_force", "a positive force in N", &|v| v > 0.0)?;
    let admittance = need("admittance", "a positive admittance in s/kg", &|v| v > 0.0)?;
    let (bridge, finger) = match get("sigma") {
        Some(sigma) => {
            if !(0.0..=1.0).contains(&sigma) {
                return Err(format!(
                    "`sigma` = {sigma} is out of range, expected 0 to 1"
                ));
            }
            if p < 2 || q < 2 {
                return Err("`sigma` needs p and q of at least 2".into());
            }
            (
                ReflectionFunction::three_tap(p, lambda, sigma),
                ReflectionFunction::three_tap(q, lambda, sigma),
            )
        }
        None => (
            ReflectionFunction::raman(p, lambda),
            ReflectionFunction::raman(q, lambda),
        ),
    };
    let slip_steps = match get("slip") {
        None => None,
        Some(slip) if slip.fract() == 0.0 && slip >= 0.0 && slip <= (p + q) as f64 => {
            Some(slip as usize)
        }
        Some(slip) => {
            return Err(format!(
                "`slip` = {slip} must be a whole number from 0 to p + q = {}",
                p + q
            ))
        }
    };
    Ok(BowedSetting {
        p,
        q,
        bridge_reflection: bridge.map_err(|error| error.to_string())?,
        finger_reflection: finger.map_err(|error| error.to_string())?,
        sticking_gamma: gamma,
        friction_slope_s_per_m: friction_slope,
        bow_force_n: bow_force,
        admittance_s_per_kg: admittance,
        slip_steps,
    })
}

fn margin_json(margin: &StabilityMargin) -> String {
    format!(
        "{{\"zeta\": {}, \"spectral_radius\": {}, \"stable\": {}, \"zeta_c\": {}, \
         \"critical_bow_force\": {}, \"bow_force_margin\": {}, \"least_stable\": {}}}\n",
        json_number(margin.zeta),
        json_number(margin.spectral_radius),
        margin.stable,
        json_number(margin.zeta_critical.unwrap_or(f64::NAN)),
        json_number(margin.critical_bow_force_n.unwrap_or(f64::NAN)),
        json_number(margin.bow_force_margin),
        eigenvalue_json(&margin.least_stable)
    )
}

fn margin_text(setting: &BowedSetting, margin: &StabilityMargin) -> String {
    let verdict = if margin.stable { "STABLE" } else { "UNSTABLE" };
    let critical = margin
        .critical_bow_force_n
        .map_or("none".to_string(), |force| format!("{force:.6} N"));
    format!(
        "beta = {}/{} = {:.4}, bow force {} N: zeta = {:.6}, growth per period {:.6} \
         (order {}) -> {verdict}\ncritical bow force {critical}, margin F_crit/F_b = {:.4}\n",
        setting.p,
        setting.p + setting.q,
        setting.p as f64 / (setting.p + setting.q) as f64,
        setting.bow_force_n,
        margin.zeta,
        margin.spectral_radius,
        margin.least_stable.subharmonic_order,
        margin.bow_force_margin
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The command of a command line, or the error clap or the checks would print.
    fn parse(line: &str) -> Result<Command, String> {
        let words = std::iter::once("stability").chain(line.split_whitespace());
        let args = StabilityArgs::try_parse_from(words).map_err(|error| error.to_string())?;
        command(args)
    }

    fn error_of(text: &str) -> String {
        parse(text).unwrap_err()
    }

    #[test]
    fn missing_required_option_is_named() {
        let error = error_of("--q 3 --lambda 0.99 --gamma 1");
        assert!(
            error.contains("required") && error.contains("--p <P>"),
            "{error}"
        );
        assert!(parse("--sweep fig7").is_ok());
        assert!(parse("--preset x.toml --json").is_ok());
    }

    #[test]
    fn out_of_range_values_are_named_with_their_range() {
        let error = error_of("--p 2 --q 3 --lambda 1.5 --gamma 1");
        assert!(
            error.contains("--lambda") && error.contains("to 1"),
            "{error}"
        );
        let error =
            error_of("--p 2 --q 3 --lambda 0.99 --gamma 1 --slip 11 --formulation spacetime");
        assert!(
            error.contains("--slip") && error.contains("0 to 10"),
            "{error}"
        );
        let error = error_of("--p 2 --q 3 --lambda 0.99 --gamma 1 --slip 6");
        assert!(error.contains("0 to 5"), "{error}");
    }

    #[test]
    fn bad_choices_and_combinations_are_rejected() {
        let error = error_of("--sweep fig9");
        assert!(error.contains("fig7, fig8, fig13, fig10"), "{error}");
        let error = error_of("--p 2 --q 3 --lambda 0.9 --gamma 1 --formulation matrix");
        assert!(error.contains("spacetime, compact"), "{error}");
        let error =
            error_of("--p 6 --q 16 --lambda 0.9 --gamma 1 --sigma 0.05 --formulation spacetime");
        assert!(error.contains("--sigma"), "{error}");
        let error = error_of("--p 1 --q 3 --lambda 0.9 --gamma 1 --sigma 0.05");
        assert!(
            error.contains("--p") && error.contains("at least 2"),
            "{error}"
        );
        let error = error_of("--p 2 --q 3 --lambda 0.9 --gamma 1 --zeta-c 3");
        assert!(error.contains("--zeta-c"), "{error}");
        let error = error_of("--sweep fig7 --p 3");
        assert!(error.contains("--p"), "{error}");
        let error = error_of("--p 2 --q 3 --lambda 0.9 --gamma 1 --csv out.csv");
        assert!(error.contains("--sweep"), "{error}");
    }

    #[test]
    fn table_i_as_json() {
        let command =
            parse("--p 2 --q 3 --lambda 0.99 --gamma 1 --zeta 0.01 --formulation spacetime --json")
                .unwrap();
        let output = execute(&command).unwrap();
        assert_eq!(output.lines().count(), 1);
        assert!(output.starts_with("{\"zeta_c\": 0.0122070079"), "{output}");
        assert!(output.contains("\"alpha\": 1.22070079"), "{output}");
        assert_eq!(
            output.matches("\"abs\"").count(),
            11,
            "10 eigenvalues + critical"
        );
        // Sorted by decreasing modulus: the first listed is 0.9964 (Table I).
        let first = output.split("\"eigenvalues\": [{\"abs\": ").nth(1).unwrap();
        assert!(first.starts_with("0.9964"), "{first}");
    }

    #[test]
    fn instrument_presets_are_checked_across_the_string() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let violin = root.join("presets/bowed-violin.toml");
        let text = std::fs::read_to_string(&violin).unwrap();
        let report = engine_preset_report(&text, &violin, false).unwrap();
        assert_eq!(
            report.lines().count(),
            1 + preset_notes(BowedStringKind::ViolinA).len()
        );
        assert!(report.contains("STABLE"), "{report}");
        let tanpura = root.join("presets/classic.toml");
        let text = std::fs::read_to_string(&tanpura).unwrap();
        assert!(engine_preset_report(&text, &tanpura, false).is_err());
    }

    #[test]
    fn preset_errors_name_the_key() {
        let base = "p = 2\nq = 5\nlambda = 0.99\ngamma = 0.9\nfriction_slope = 0.01\n\
                    bow_force = 2\nadmittance = 2\n";
        assert!(parse_preset(base).is_ok());
        let error = parse_preset(&base.replace("bow_force = 2", "bow_force = -1")).unwrap_err();
        assert!(error.contains("bow_force"), "{error}");
        let error = parse_preset(&format!("{base}bow_speed = 3\n")).unwrap_err();
        assert!(
            error.contains("line 8") && error.contains("bow_speed"),
            "{error}"
        );
        let error = parse_preset(&base.replace("q = 5\n", "")).unwrap_err();
        assert!(error.contains("`beta` and `steps`"), "{error}");
        let error = parse_preset(&base.replace("lambda = 0.99", "lambda = lots")).unwrap_err();
        assert!(
            error.contains("`lambda`") && error.contains("not a number"),
            "{error}"
        );
    }

    #[test]
    fn preset_margin_of_the_section_2_5_string() {
        let stable = "beta = 0.2857142857\nsteps = 7\nlambda = 0.99\ngamma = 0.9\n\
                      friction_slope = 0.01\nbow_force = 1.5  # N\nadmittance = 2\n";
        let setting = parse_preset(stable).unwrap();
        assert_eq!((setting.p, setting.q), (2, 5));
        let margin = stability_margin(&setting).unwrap();
        assert!(margin.stable);
        let json = margin_json(&margin);
        assert!(json.contains("\"stable\": true"), "{json}");
        assert!(json.contains("\"critical_bow_force\": 1.721"), "{json}");
    }
}
