//! Where the string starts to rest on the bridge's crest, and how a pluck there sounds, on the
//! reference tier's grid and on finer ones: `cargo run --release -p javari-core --example
//! crest_threshold [KEY…] [pluck=M]` (keys 49–54 and the bench's default pluck at 0.35 m unless
//! given; about a minute on two cores for six keys).
//!
//! The playing-range grid's worst plucks (README, issue 15) all lie at keys 48–54, where the
//! reference tier's string at rest just touches the bridge's crest, 7 mm past the thread. Whether
//! it touches, and whether a pluck lifts it off for the whole sustain window, is decided by
//! fractions of a micrometre of static deflection. This example asks whether the reference's own
//! grid resolves them, by the seed's physical parameters as they are (no tuning per scheme) at the
//! tension of each key (the seed's tension scaled by (f_key / f_seed)², f_seed the reference grid's
//! linearised fundamental):
//!
//! 1. At rest, the deepest bridge gap (positive: the string lies that far into the crest), µm: the
//!    seed's FD grid (N = 200, the reference tier) and N = 400 and 800; the modal string at the live
//!    tier's 1 mm bridge points with its kept modes only, with two residual modes, and with the
//!    whole string's static compliance (the closed-form Green's function, `static_flexibility`), at
//!    1 mm and at 0.25 mm points.
//! 2. Plucked as the bench plucks, at MIDI velocities 40, 80 and 127, for a grid note's length
//!    (1.6 s; FD through the tiers' decimator): the sustained pitch (0.3–1.5 s, the grid's
//!    measure) in cents from the same string's pitch at velocity 1 (its small-amplitude pitch),
//!    on the FD scheme at N = 200 (4× oversampled, the reference), 400 (8×) and 800 (16×), and on
//!    the modal scheme (f64) at 1 mm points with the kept modes only (the live tier) and with two
//!    residual modes, and at 0.25 mm points with two residual modes. A string that a pluck lifts
//!    off the crest sounds about 10 cents flat of its small-amplitude pitch.
//! 3. The same renders against N = 800 on the playing-range grid's measures
//!    (`listening::compare`), worst over velocities 1, 40, 80 and 127: sustained pitch, band
//!    levels, centroid course.
//!
//! The FD grids refine the string and the time step; the barrier's points stay the seed's (every
//! 0.18 mm on the bridge, 0.15 mm on the thread). The figures are quoted in `docs/modal-tanpura.md`, section 9; the static part is asserted by
//! `core/tests/tanpura_crest_threshold.rs`.

use javari_core::analysis::cents;
use javari_core::analysis::listening::{compare, sustained_pitch_hz};
use javari_core::analysis::playing_range::NOTE_SECONDS;
use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::ModalString;
#[path = "support/schemes.rs"]
mod schemes;
use schemes::{on_all_cores, Scheme, OUTPUT_RATE_HZ};

/// The keys asked by default: those whose string starts to rest on the crest (section 9).
const DEFAULT_KEYS: [u8; 6] = [49, 50, 51, 52, 53, 54];
const VELOCITIES: [u8; 4] = [1, 40, 80, 127];
/// The index of N = 800 at 16× among the plucked schemes: the yardstick of part 3.
const FINE: usize = 2;

/// The deepest bridge gap of `scheme`'s string at rest at `tension_n`, µm (positive: into the
/// crest).
fn deepest_rest_gap_um(scheme: Scheme, tension_n: f64) -> f64 {
    let deepest = |gaps: &mut dyn Iterator<Item = f64>| gaps.fold(f64::MIN, f64::max) * 1e6;
    match scheme {
        Scheme::Fd(intervals, oversampling) => {
            let string = FdString::new(Scheme::fd_config(intervals, oversampling, Some(tension_n)));
            let grid = string.bridge_grid();
            deepest(
                &mut (0..grid.len())
                    .map(|i| grid.heights_m()[i] - grid.interpolate(string.displacement_m(), i)),
            )
        }
        Scheme::Modal(spacing, residual, flexibility) => {
            let string: ModalString<f64> = ModalString::new(Scheme::modal_config(
                spacing,
                residual,
                flexibility,
                Some(tension_n),
            ));
            let bridge = string.bridge_point_count();
            deepest(&mut string.gaps_m()[..bridge].iter().copied())
        }
    }
}

fn main() {
    let arguments: Vec<String> = std::env::args().skip(1).collect();
    let mut keys: Vec<u8> = arguments
        .iter()
        .filter_map(|key| key.parse().ok())
        .collect();
    if keys.is_empty() {
        keys = DEFAULT_KEYS.to_vec();
    }
    let keys = &keys[..];
    let pluck_position_m = arguments
        .iter()
        .find_map(|argument| argument.strip_prefix("pluck=")?.parse::<f64>().ok())
        .unwrap_or(Pluck::default().position_m);
    let seed_tension = FdStringConfig::REFERENCE.string.tension_n;
    let seed_hz = FdString::new(FdStringConfig::REFERENCE).linearised_fundamental_hz();
    let tension_of = |key: u8| seed_tension * (note_to_hz(key) / seed_hz).powi(2);
    println!(
        "The seed's string at the tension of each key (seed: {seed_tension:.2} N, {seed_hz:.2} Hz \
         on the reference grid)"
    );

    let static_schemes = [
        Scheme::Fd(200, 4),
        Scheme::Fd(400, 8),
        Scheme::Fd(800, 16),
        Scheme::Modal(1e-3, 0, false),
        Scheme::Modal(1e-3, 2, false),
        Scheme::Modal(1e-3, 0, true),
        Scheme::Modal(0.25e-3, 0, true),
    ];
    println!("\n1. At rest: the deepest bridge gap, µm (positive: into the crest)");
    print!("| scheme |");
    for &key in keys {
        print!(" key {key} |");
    }
    println!();
    for scheme in static_schemes {
        print!("| {} |", scheme.name());
        for &key in keys {
            print!(" {:+.2} |", deepest_rest_gap_um(scheme, tension_of(key)));
        }
        println!();
    }

    let dynamic_schemes = [
        Scheme::Fd(200, 4),
        Scheme::Fd(400, 8),
        Scheme::Fd(800, 16),
        Scheme::Modal(1e-3, 0, false),
        Scheme::Modal(1e-3, 2, false),
        Scheme::Modal(0.25e-3, 2, false),
    ];
    // Every (scheme, key) on the machine's cores, the slowest first; each renders its four
    // velocities.
    let mut jobs: Vec<(usize, usize)> = (0..dynamic_schemes.len())
        .flat_map(|s| (0..keys.len()).map(move |k| (s, k)))
        .collect();
    jobs.sort_by_key(|&(s, _)| usize::from(s != FINE));
    let forces = on_all_cores(&jobs, |&(s, k)| {
        let (scheme, key) = (dynamic_schemes[s], keys[k]);
        VELOCITIES
            .iter()
            .map(|&velocity| {
                scheme.pluck_nut_force(
                    Some(tension_of(key)),
                    f64::from(velocity) / 127.0,
                    pluck_position_m,
                    NOTE_SECONDS,
                )
            })
            .collect::<Vec<Vec<f64>>>()
    });
    let mut renders = vec![vec![Vec::new(); keys.len()]; dynamic_schemes.len()];
    for (&(s, k), forces) in jobs.iter().zip(forces) {
        renders[s][k] = forces;
    }
    let header = || {
        print!("| scheme |");
        for &key in keys {
            print!(" key {key} |");
        }
        println!();
    };

    println!(
        "\n2. Plucked: the sustained pitch at velocities {:?}, cents from the pitch at velocity 1",
        &VELOCITIES[1..]
    );
    header();
    for (scheme, row) in dynamic_schemes.iter().zip(&renders) {
        print!("| {} |", scheme.name());
        for (&key, forces) in keys.iter().zip(row) {
            let pitch = |force: &[f64]| sustained_pitch_hz(force, OUTPUT_RATE_HZ, note_to_hz(key));
            let soft = pitch(&forces[0]);
            let listed: Vec<String> = forces[1..]
                .iter()
                .map(|force| format!("{:+.1}", cents(pitch(force), soft)))
                .collect();
            print!(" {} |", listed.join(" "));
        }
        println!();
    }

    println!(
        "\n3. Against N = 800 at 16x, the playing-range grid's measures, worst over velocities \
         {VELOCITIES:?}: sustained pitch (cents) / 1/6-octave band levels (dB RMS) / centroid \
         course (%)"
    );
    header();
    for (scheme, row) in dynamic_schemes.iter().zip(&renders) {
        print!("| {} |", scheme.name());
        for (k, forces) in row.iter().enumerate() {
            let (mut pitch, mut bands, mut centroid) = (0.0f64, 0.0f64, 0.0f64);
            for (force, fine) in forces.iter().zip(&renders[FINE][k]) {
                let difference = compare(force, fine, OUTPUT_RATE_HZ, note_to_hz(keys[k]));
                pitch = pitch.max(difference.sustained_cents.abs());
                bands = bands.max(difference.band_level_db);
                centroid = centroid.max(100.0 * difference.centroid_error);
            }
            print!(" {pitch:.1} / {bands:.1} / {centroid:.0} |");
        }
        println!();
    }
}
