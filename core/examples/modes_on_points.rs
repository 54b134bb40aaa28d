//! Which part of a modal string carries the jawari's detail: its modes or its contact points.
//! `cargo run --release -p javari-core --example modes_on_points -- MEASURE SPEC…`
//! (`docs/performance.md`, stop 62). A SPEC is `live` or `fine` (the tiers as shipped), or
//! `B/T` (the live tier's continuous modes on bridge points every B mm and thread points every
//! T mm) or `B/T/g` (the reference grid's modes, the fine tier's, on those points), each
//! rendered by `analysis::refined::modal_variant_pluck` and tuned by linearisation. MEASURE:
//!
//! - `one-string`: the bench's one-string scene (3 s) against the reference tier's voice, on the
//!   bench's three measures (ten partials' cents, third-octave distance, formant course), with the
//!   fastest of three renders' real-time factor (tuning included; compare within one run);
//! - `precursor`: the seed's precursor on the default pluck (`analysis::precursor`, as the
//!   signature test folds it): a quarter period's share of the band above 10 f₀ and 40 f₀ over
//!   0.1–0.5 s and their leads on the main pulse, with and without the bridge beyond the thread;
//! - `grid`: the bench's 180 plucks of the playing range against the reference tuned the same
//!   way (`analysis::listening::compare`), worst and median (minutes on two cores).

use javari_core::analysis::listening::{compare, one_string_errors, ListeningDifference};
use javari_core::analysis::playing_range::{full_grid, GridPoint, NOTE_SECONDS};
use javari_core::analysis::precursor::fold_precursor;
use javari_core::analysis::refined::{
    grid_pluck, grid_render_linearised, modal_variant_pluck, ModalVariant,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use rayon::prelude::*;
use std::time::Instant;

const RATE: f64 = 44_100.0;
const ONE_STRING_SECONDS: f64 = 3.0;

/// A string to measure: a tier as shipped, or a modal variant of one.
#[derive(Debug, Clone)]
enum Spec {
    Tier(Quality),
    Variant {
        label: String,
        quality: Quality,
        variant: ModalVariant,
    },
}

impl Spec {
    fn parse(text: &str) -> Spec {
        if let Some(quality) = Quality::from_name(text) {
            return Spec::Tier(quality);
        }
        let parts: Vec<&str> = text.split('/').collect();
        let millimetres = |index: usize| -> f64 {
            parts
                .get(index)
                .and_then(|part| part.parse().ok())
                .unwrap_or_else(|| panic!("{text}: B/T or B/T/g, spacings in mm"))
        };
        let grid_modes = parts.get(2) == Some(&"g");
        Spec::Variant {
            label: text.to_owned(),
            // The grid modes are the fine tier's; the continuous ones the live tier's.
            quality: if grid_modes {
                Quality::Fine
            } else {
                Quality::Live
            },
            variant: ModalVariant {
                bridge_point_spacing_m: Some(millimetres(0) * 1e-3),
                thread_point_spacing_m: Some(millimetres(1) * 1e-3),
                grid_modes,
                ..ModalVariant::default()
            },
        }
    }

    fn label(&self) -> String {
        match self {
            Spec::Tier(quality) => quality.name().to_owned(),
            Spec::Variant { label, .. } => label.clone(),
        }
    }

    /// The nut force of `pluck` on `settings`' string (its tier replaced by this spec's).
    fn render(&self, settings: &VoiceSettings, pluck: &Pluck, seconds: f64) -> Vec<f64> {
        match self {
            Spec::Tier(quality) => {
                let settings = VoiceSettings {
                    quality: *quality,
                    ..*settings
                };
                let mut voice = TanpuraVoice::new(&settings, RATE);
                voice.pluck(pluck);
                (0..(seconds * RATE).round() as usize)
                    .map(|_| f64::from(voice.next_sample()))
                    .collect()
            }
            Spec::Variant {
                quality, variant, ..
            } => {
                let settings = VoiceSettings {
                    quality: *quality,
                    ..*settings
                };
                modal_variant_pluck(&settings, variant, pluck, seconds, RATE)
                    .expect("a modal string that tunes")
            }
        }
    }

    /// `point` of the playing-range grid, tuned by linearisation.
    fn render_point(&self, point: &GridPoint) -> Vec<f64> {
        match self {
            Spec::Tier(quality) => grid_render_linearised(*quality, point, RATE, 0),
            Spec::Variant { quality, .. } => {
                let (settings, pluck) = grid_pluck(*quality, point);
                self.render(&settings, &pluck, NOTE_SECONDS)
            }
        }
    }
}

fn one_string(specs: &[Spec]) {
    let settings = VoiceSettings::default();
    let reference =
        Spec::Tier(Quality::Reference).render(&settings, &Pluck::default(), ONE_STRING_SECONDS);
    let f0 = settings.fundamental_hz;
    for spec in specs {
        let mut fastest = f64::INFINITY;
        let mut output = Vec::new();
        for _ in 0..3 {
            let started = Instant::now();
            output = spec.render(&settings, &Pluck::default(), ONE_STRING_SECONDS);
            fastest = fastest.min(started.elapsed().as_secs_f64());
        }
        let (cents_error, distance, formant) = one_string_errors(&output, f0, &reference, f0, RATE);
        println!(
            "{}: {:.1}x real time, {cents_error:.2} cents, {distance:.1} dB, formant {:.1} %",
            spec.label(),
            ONE_STRING_SECONDS / fastest,
            100.0 * formant
        );
    }
}

fn precursor(specs: &[Spec]) {
    for spec in specs {
        for bridge_beyond_thread in [true, false] {
            let settings = VoiceSettings {
                bridge_beyond_thread,
                ..VoiceSettings::default()
            };
            let force = spec.render(&settings, &Pluck::default(), 0.6);
            let f0 = settings.fundamental_hz;
            let fold = |above_f0: f64| {
                fold_precursor(
                    &force,
                    RATE,
                    f0,
                    10.0 * f0,
                    above_f0 * f0,
                    (0.1 * RATE) as usize,
                    (0.5 * RATE) as usize,
                )
            };
            let (held, highest) = (fold(10.0), fold(40.0));
            println!(
                "{}, bridge beyond the thread {bridge_beyond_thread}: above 10 f0 quarter {:.2} \
                 lead {:.2}; above 40 f0 quarter {:.2} lead {:.2}",
                spec.label(),
                held.packet_share,
                held.lead_periods,
                highest.packet_share,
                highest.lead_periods
            );
        }
    }
}

fn grid(specs: &[Spec]) {
    let points = full_grid();
    let reference = Spec::Tier(Quality::Reference);
    let references: Vec<Vec<f64>> = points
        .par_iter()
        .map(|point| reference.render_point(point))
        .collect();
    for spec in specs {
        let differences: Vec<(GridPoint, ListeningDifference)> = points
            .par_iter()
            .zip(&references)
            .map(|(point, reference)| {
                let output = spec.render_point(point);
                (
                    *point,
                    compare(&output, reference, RATE, point.nominal_hz()),
                )
            })
            .collect();
        let spread = |measure: fn(&ListeningDifference) -> f64| {
            let mut values: Vec<(f64, &GridPoint)> = differences
                .iter()
                .map(|(point, difference)| (measure(difference), point))
                .collect();
            values.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (worst, at) = values[values.len() - 1];
            format!(
                "{worst:.2} ({}), median {:.2}",
                at.label(),
                values[values.len() / 2].0
            )
        };
        println!("{}:", spec.label());
        println!(
            "  sustained pitch, cents: {}",
            spread(|d| d.sustained_cents.abs())
        );
        println!("  band levels, dB: {}", spread(|d| d.band_level_db));
        println!(
            "  centroid course, %: {}",
            spread(|d| 100.0 * d.centroid_error)
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((measure, specs)) = args.split_first() else {
        eprintln!("usage: modes_on_points one-string|precursor|grid SPEC…");
        std::process::exit(2);
    };
    let specs: Vec<Spec> = specs.iter().map(|text| Spec::parse(text)).collect();
    match measure.as_str() {
        "one-string" => one_string(&specs),
        "precursor" => precursor(&specs),
        "grid" => grid(&specs),
        other => {
            eprintln!("unknown measure {other}: one-string, precursor or grid");
            std::process::exit(2);
        }
    }
}
