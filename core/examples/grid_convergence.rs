//! How far the reference tier's own output moves when its grid is refined, against the distance
//! between the modal and reference tiers: `cargo run --release --example grid_convergence`
//! (about a minute on two cores).
//!
//! Renders the seed's string (its physical parameters as they are, no tuning per scheme) plucked
//! as in the bench, 3 s of its nut force (the seed's signal) at 44.1 kHz, on the FD scheme at the
//! seed's grid (N = 200, 4× oversampling, the reference tier) and refined (N = 400 at 8× and 16×,
//! N = 800 at 16×), each brought to 44.1 kHz by the tiers' Kaiser decimator, and on the modal
//! scheme at the live tier's point spacing (kept modes only, as the tier runs) and, at 1 mm and
//! 0.25 mm points, with the static flexibility and with two residual modes. Each render is measured as the bench
//! measures its one-string scene (`javari_core::analysis`): the largest cents error of the first
//! ten partials (0.5 s on), the third-octave spectral distance and the centroid course's error,
//! against the seed's grid (what the bench reports), against N = 400 at 16× and against N = 800 at
//! 16×. Then the
//! rest states behind the difference between the schemes: each one's linearised fundamental and
//! the end of its rest contact (thread only, or thread and bridge crest). The FD grids refine the
//! string and the time step; the barrier's points stay the seed's (every 0.18 mm on the bridge,
//! 0.15 mm on the thread).

use javari_core::analysis::listening::{centroid_course_error, centroid_course_hz};
use javari_core::analysis::{
    cents, first_partials_hz, peak_frequency_hz, third_octave_distance_db,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::{ModalString, ModalStringConfig};
#[path = "support/schemes.rs"]
mod schemes;
use schemes::{on_all_cores, Scheme, OUTPUT_RATE_HZ};

const SECONDS: f64 = 3.0;

/// The bench's three one-string measures of `output` against `reference` (fundamental
/// `fundamental_hz` for both: the strings are the same, untuned).
fn measures(output: &[f64], reference: &[f64], fundamental_hz: f64) -> (f64, f64, f64) {
    let partials = |signal: &[f64]| first_partials_hz(signal, OUTPUT_RATE_HZ, fundamental_hz, 10);
    let worst_cents = partials(output)
        .iter()
        .zip(&partials(reference))
        .map(|(a, b)| cents(*a, *b).abs())
        .fold(0.0, f64::max);
    let distance = third_octave_distance_db(output, reference, OUTPUT_RATE_HZ);
    let course = |signal: &[f64]| centroid_course_hz(signal, OUTPUT_RATE_HZ, fundamental_hz);
    let formant = centroid_course_error(&course(output), &course(reference));
    (worst_cents, distance, 100.0 * formant)
}

fn main() {
    let schemes = [
        Scheme::Fd(200, 4),
        Scheme::Fd(400, 8),
        Scheme::Fd(400, 16),
        Scheme::Fd(800, 16),
        Scheme::Modal(1e-3, 0, false),
        Scheme::Modal(1e-3, 0, true),
        Scheme::Modal(0.25e-3, 0, true),
        Scheme::Modal(1e-3, 2, false),
        Scheme::Modal(0.25e-3, 2, false),
    ];
    // The longest render (N = 800) first, so that the two cores finish together.
    let order = [3, 0, 1, 2, 4, 5, 6, 7, 8];
    let in_order = on_all_cores(&order, |&index| {
        schemes[index].pluck_nut_force(None, 1.0, Pluck::default().position_m, SECONDS)
    });
    let mut renders = vec![Vec::new(); schemes.len()];
    for (&index, output) in order.iter().zip(in_order) {
        renders[index] = output;
    }
    let start = (0.5 * OUTPUT_RATE_HZ) as usize;
    let fundamental = peak_frequency_hz(&renders[0][start..], OUTPUT_RATE_HZ, 120.0, 260.0);
    println!(
        "f0 = {fundamental:.3} Hz; the bench's measures (worst of 10 partials, cents / spectral \
         distance, dB / formant error, %)"
    );
    println!(
        "| scheme | against N = 200 (the reference) | against N = 400, 16x | against N = 800, 16x |"
    );
    println!("|---|---|---|---|");
    for (scheme, output) in schemes.iter().zip(&renders) {
        let (c, d, f) = measures(output, &renders[0], fundamental);
        let (c4, d4, f4) = measures(output, &renders[2], fundamental);
        let (c8, d8, f8) = measures(output, &renders[3], fundamental);
        println!(
            "| {} | {c:.2} / {d:.1} / {f:.1} | {c4:.2} / {d4:.1} / {f4:.1} | {c8:.2} / {d8:.1} / {f8:.1} |",
            scheme.name()
        );
    }

    println!("\nrest states: linearised fundamental, end of the rest contact");
    for intervals in [200, 400, 800] {
        let mut string = FdString::new(FdStringConfig {
            intervals,
            ..FdStringConfig::REFERENCE
        });
        let fundamental = string.linearised_fundamental_hz();
        let end = string.rest_contact_end_m().unwrap_or(f64::NAN);
        println!(
            "FD N = {intervals:3}: {fundamental:.3} Hz, {:.2} mm",
            end * 1e3
        );
    }
    for (spacing, static_flexibility) in [(1e-3, true), (0.25e-3, true), (1e-3, false)] {
        let mut string: ModalString<f64> = ModalString::new(ModalStringConfig {
            bridge_point_spacing_m: spacing,
            thread_point_spacing_m: 0.5 * spacing,
            static_flexibility,
            ..ModalStringConfig::REFERENCE
        });
        let fundamental = string.linearised_fundamental_hz();
        let end = string.rest_contact_end_m().unwrap_or(f64::NAN);
        let what = if static_flexibility {
            "with the static flexibility"
        } else {
            "kept modes only"
        };
        println!(
            "modal, {:.2} mm points, {what}: {fundamental:.3} Hz, {:.2} mm",
            spacing * 1e3,
            end * 1e3
        );
    }
}
