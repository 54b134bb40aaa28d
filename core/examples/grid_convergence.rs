//! How far the reference tier's own partials move when its grid is refined, against the distance
//! between the modal and reference tiers: `cargo run --release --example grid_convergence`.
//!
//! Renders the seed's string (its physical parameters as they are, no tuning per tier) plucked as
//! in the bench, 2 s, on the FD scheme at the seed's grid (N = 200, 4× oversampling) and refined
//! (N = 400 at 8× and 16×), and on the modal scheme at the live tier's point spacing and four times
//! finer (and at the live spacing without the truncated modes' static flexibility); prints the first ten partials (0.5–2 s, the bench's measure) in cents against the seed
//! grid. Then the rest states behind the difference between the schemes: each one's linearised
//! fundamental and the end of its rest contact (thread only, or thread and bridge crest). About a
//! minute on one core.

use javari_core::analysis::{cents, peak_frequency_hz};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::{ModalString, ModalStringConfig};

const SECONDS: f64 = 2.0;
const OUTPUT_RATE_HZ: f64 = 44_100.0;

/// Block means of `factor` samples: enough of a low-pass for partials below 2 kHz.
fn decimate(signal: &[f64], factor: usize) -> Vec<f64> {
    signal
        .chunks_exact(factor)
        .map(|block| block.iter().sum::<f64>() / factor as f64)
        .collect()
}

/// The first ten partials from 0.5 s on, as the bench measures them.
fn partials(output: &[f64], fundamental_hz: f64) -> Vec<f64> {
    let start = (0.5 * OUTPUT_RATE_HZ) as usize;
    (1..=10)
        .map(|n| {
            let expected = n as f64 * fundamental_hz;
            peak_frequency_hz(
                &output[start..],
                OUTPUT_RATE_HZ,
                expected * 0.97,
                expected * 1.03,
            )
        })
        .collect()
}

fn finite_difference(intervals: usize, oversampling: usize) -> Vec<f64> {
    let config = FdStringConfig {
        intervals,
        time_step_s: 1.0 / (OUTPUT_RATE_HZ * oversampling as f64),
        ..FdStringConfig::REFERENCE
    };
    let mut string = FdString::new(config);
    string.pluck(&Pluck::default());
    let steps = (SECONDS * OUTPUT_RATE_HZ) as usize * oversampling;
    let nut: Vec<f64> = (0..steps)
        .map(|_| {
            string.step();
            string.nut_force_n()
        })
        .collect();
    decimate(&nut, oversampling)
}

fn modal(bridge_spacing_m: f64, static_flexibility: bool) -> Vec<f64> {
    let config = ModalStringConfig {
        bridge_point_spacing_m: bridge_spacing_m,
        thread_point_spacing_m: 0.5 * bridge_spacing_m,
        static_flexibility,
        ..ModalStringConfig::REFERENCE
    };
    let mut string: ModalString<f64> = ModalString::new(config);
    string.pluck(&Pluck::default());
    (0..(SECONDS * OUTPUT_RATE_HZ) as usize)
        .map(|_| {
            string.step();
            string.nut_force_n()
        })
        .collect()
}

fn main() {
    let renders = [
        ("FD N = 200, 4x (the reference)", finite_difference(200, 4)),
        ("FD N = 400, 8x", finite_difference(400, 8)),
        ("FD N = 400, 16x", finite_difference(400, 16)),
        ("modal, live points, static flex.", modal(1e-3, true)),
        ("modal, 0.25 mm, static flex.", modal(0.25e-3, true)),
        ("modal, live (kept modes only)", modal(1e-3, false)),
    ];
    let start = (0.5 * OUTPUT_RATE_HZ) as usize;
    let fundamental = peak_frequency_hz(&renders[0].1[start..], OUTPUT_RATE_HZ, 120.0, 260.0);
    let reference = partials(&renders[0].1, fundamental);
    println!("f0 = {fundamental:.3} Hz; partials 1-10 in cents against the seed's grid:");
    for (name, output) in &renders {
        let offsets: Vec<f64> = partials(output, fundamental)
            .iter()
            .zip(&reference)
            .map(|(partial, reference)| cents(*partial, *reference))
            .collect();
        let worst = offsets.iter().fold(0.0f64, |m, c| m.max(c.abs()));
        let spread = offsets.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - offsets.iter().cloned().fold(f64::INFINITY, f64::min);
        let listed: Vec<String> = offsets.iter().map(|c| format!("{c:+.2}")).collect();
        println!(
            "{name:32} worst {worst:6.2}  spread {spread:5.2}  {}",
            listed.join(" ")
        );
    }
    println!("rest states: linearised fundamental, end of the rest contact");
    for intervals in [200, 400] {
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
