//! The bench's one-string scene, partial by partial: each tier's first ten partials against the
//! reference tier's, in cents, with the three tunings a string can have: the linearised tuning
//! the bench's scene uses (`TanpuraVoice::new`), the as-played tuning the plugin and `render`
//! use by default (velocities 40 and 110 centred, `tanpura/as_played.rs`), and the as-played
//! tuning at the scene's own pluck (velocity 127). `cargo run --release -p javari-core --example
//! one_string_partials` (about a minute). Prints first each tier's sustained pitch (0.3–1.5 s)
//! as the pluck's velocity grows (linearised tuning); then, per tuning and tier, the calibration
//! offset, the fundamental, the third-octave distance to the reference (dB) and the cents of each
//! partial (`analysis::first_partials_hz`, the bench's measure, 0.5–3 s); then, with the
//! linearised tuning, every tier's partials and the seed's scheme's at N = 400 (8×) against
//! N = 800 (16×, `analysis::refined`), at the scene's pluck (velocity 127) and barely plucked
//! (velocity 1), with the live tier's string with two residual modes (`docs/modal-tanpura.md`,
//! section 8) at the output rate and at two and four times it. `-- bridge=1mm` sets those
//! residual-mode rows' bridge points 1 mm apart (the live tier's until stop 29) instead of the
//! tier's 2 mm.

use javari_core::analysis::refined::{modal_variant_pluck, refined_reference_pluck, ModalVariant};
use javari_core::analysis::{cents, first_partials_hz, third_octave_distance_db};
use javari_core::tanpura::as_played::{
    as_played_offset_cents, sustained_pitch_of_pluck_hz, NOTE_VELOCITIES,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};

const SAMPLE_RATE: f64 = 44_100.0;
const SECONDS: f64 = 3.0;
const BLOCK: usize = 64;
const PARTIALS: usize = 10;

/// How the scene's string is tuned.
#[derive(Clone, Copy)]
enum Tuning {
    Linearised,
    AsPlayed([f64; 2]),
}

impl Tuning {
    fn name(self) -> &'static str {
        match self {
            Tuning::Linearised => "linearised (the bench's scene)",
            Tuning::AsPlayed(velocities) if velocities == NOTE_VELOCITIES => {
                "as played, velocities 40 and 110 (the plugin's default)"
            }
            Tuning::AsPlayed(_) => "as played at the scene's pluck (velocity 127)",
        }
    }
}

/// The scene's pluck at `velocity` (0–1).
fn pluck_at(velocity: f64) -> Pluck {
    let pluck = Pluck::default();
    Pluck {
        amplitude_m: pluck.amplitude_m * velocity,
        ..pluck
    }
}

/// One tier's render of the scene: the offset its tuning found (cents) and the output.
fn render(quality: Quality, tuning: Tuning) -> (f64, Vec<f64>) {
    render_at(quality, tuning, 1.0)
}

/// [`render`] with the pluck at `velocity` (0–1).
fn render_at(quality: Quality, tuning: Tuning, velocity: f64) -> (f64, Vec<f64>) {
    let nominal = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let offset = match tuning {
        Tuning::Linearised => 0.0,
        Tuning::AsPlayed(velocities) => {
            as_played_offset_cents(&nominal, &Pluck::default(), velocities, SAMPLE_RATE)
        }
    };
    let settings = VoiceSettings {
        fundamental_hz: nominal.fundamental_hz * (offset / 1200.0).exp2(),
        ..nominal
    };
    let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
    voice.pluck(&pluck_at(velocity));
    let blocks = (SECONDS * SAMPLE_RATE) as usize / BLOCK;
    let mut output = Vec::with_capacity(blocks * BLOCK);
    let mut block = [0.0f32; BLOCK];
    for _ in 0..blocks {
        voice.process(&mut block);
        output.extend(block.iter().map(|&sample| f64::from(sample)));
    }
    (offset, output)
}

/// The bridge point spacing of the residual-mode rows, from an argument `bridge=<mm>mm`, or the
/// tier's.
fn bridge_point_spacing_m() -> Option<f64> {
    std::env::args().skip(1).find_map(|argument| {
        let millimetres = argument.strip_prefix("bridge=")?.strip_suffix("mm")?;
        let spacing: f64 = millimetres
            .parse()
            .unwrap_or_else(|_| panic!("`{argument}`: expected bridge=<millimetres>mm"));
        assert!(spacing > 0.0, "`{argument}`: the spacing must be positive");
        Some(spacing * 1e-3)
    })
}

fn main() {
    let nominal_hz = VoiceSettings::default().fundamental_hz;
    let bridge_point_spacing_m = bridge_point_spacing_m();
    println!("sustained pitch (0.3-1.5 s), linearised tuning, cents from the note, velocities 1 40 80 110 127");
    for quality in Quality::ALL.into_iter().rev() {
        let settings = VoiceSettings {
            quality,
            ..VoiceSettings::default()
        };
        let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
        let row: Vec<String> = [1.0, 40.0, 80.0, 110.0, 127.0]
            .iter()
            .map(|velocity| {
                let pitch = sustained_pitch_of_pluck_hz(
                    &mut voice,
                    nominal_hz,
                    nominal_hz,
                    &Pluck::default(),
                    velocity / 127.0,
                    SAMPLE_RATE,
                );
                format!("{:+.2}", cents(pitch, nominal_hz))
            })
            .collect();
        println!("  {:<9} | {}", quality.name(), row.join(" "));
    }
    for tuning in [
        Tuning::Linearised,
        Tuning::AsPlayed(NOTE_VELOCITIES),
        Tuning::AsPlayed([1.0, 1.0]),
    ] {
        println!("{}", tuning.name());
        let (reference_offset, reference) = render(Quality::Reference, tuning);
        let reference_partials = first_partials_hz(&reference, SAMPLE_RATE, nominal_hz, PARTIALS);
        for quality in Quality::ALL.into_iter().rev() {
            let (offset, output) = if quality == Quality::Reference {
                (reference_offset, reference.clone())
            } else {
                render(quality, tuning)
            };
            let partials = first_partials_hz(&output, SAMPLE_RATE, nominal_hz, PARTIALS);
            let deviations: Vec<String> = partials
                .iter()
                .zip(&reference_partials)
                .map(|(mine, theirs)| format!("{:+.2}", cents(*mine, *theirs)))
                .collect();
            println!(
                "  {:<9} offset {:+7.3} cents, f1 {:.3} Hz, distance {:5.2} dB | {}",
                quality.name(),
                offset,
                partials[0],
                third_octave_distance_db(&output, &reference, SAMPLE_RATE),
                deviations.join(" ")
            );
        }
    }
    for velocity in [127, 1] {
        let pluck = pluck_at(f64::from(velocity) / 127.0);
        let refined = |refinement| {
            refined_reference_pluck(
                &VoiceSettings::default(),
                refinement,
                &pluck,
                SECONDS,
                SAMPLE_RATE,
            )
            .expect("the reference tier is an FD tier")
            .output
        };
        let yardstick = first_partials_hz(&refined(4), SAMPLE_RATE, nominal_hz, PARTIALS);
        println!("against N = 800 at 16x, linearised tuning, velocity {velocity}");
        let mut rows = vec![("N = 400, 8x", refined(2))];
        for quality in Quality::ALL.into_iter().rev() {
            rows.push((
                quality.name(),
                render_at(quality, Tuning::Linearised, f64::from(velocity) / 127.0).1,
            ));
        }
        let against_yardstick = |output: &[f64], rate: f64| -> String {
            first_partials_hz(output, rate, nominal_hz, PARTIALS)
                .iter()
                .zip(&yardstick)
                .map(|(mine, theirs)| format!("{:+.2}", cents(*mine, *theirs)))
                .collect::<Vec<_>>()
                .join(" ")
        };
        for (name, output) in rows {
            println!("  {name:<11} | {}", against_yardstick(&output, SAMPLE_RATE));
        }
        let live = VoiceSettings {
            quality: Quality::Live,
            ..VoiceSettings::default()
        };
        for residual_modes in [0, 2] {
            for rate_factor in [1.0, 2.0, 4.0] {
                let rate = SAMPLE_RATE * rate_factor;
                let variant = ModalVariant {
                    residual_modes,
                    bridge_point_spacing_m,
                    ..ModalVariant::default()
                };
                let output = modal_variant_pluck(&live, &variant, &pluck, SECONDS, rate)
                    .expect("the live tier is modal");
                println!(
                    "  live, {residual_modes} residual modes, {rate_factor}x rate | {}",
                    against_yardstick(&output, rate)
                );
            }
        }
    }
}
