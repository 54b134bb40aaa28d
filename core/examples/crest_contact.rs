//! Why the live tier is brighter than the reference late in a note: the bridge crest's contact in
//! the two schemes. `cargo run --release --example crest_contact` (about twenty seconds).
//!
//! 1. The seed's string at rest and plucked as in the bench (its physical parameters as they are,
//!    no tuning per scheme), 3 s, on the FD scheme at the seed's grid and on the modal scheme at
//!    the live tier's point spacing, with the kept modes alone (as the tiers run) and with two
//!    residual modes (`ModalStringConfig::residual_modes`): the deepest bridge gap at rest
//!    (positive: the string lies on the bridge), then per half second the string's landings on the bridge per second (a step
//!    with some bridge point in contact after one with none: an impact, which radiates a broad
//!    band) and the share of steps with some bridge point in contact.
//! 2. The bench's one-string scene at the live and reference tiers (each tuned as the plugin
//!    tunes it): the spectrum's median and loudest bin between 4 and 16 kHz at five times after
//!    the pluck (8192-sample Hann frames, dB of the output's power), and the live tier's
//!    third-octave levels above 1 kHz against the reference's, as the bench's spectral distance
//!    measures them.
//! 3. The seed's string at rest with 0 to 8 residual modes and bridge points 1 to 0.25 mm apart:
//!    the deepest bridge gap, the points on the crest, and the time of a change of configuration
//!    (the thread moved; best of 20).
//!
//! The figures are quoted in `docs/modal-tanpura.md`, section 8; the contrast of part 1 (the kept
//! modes alone strike the crest to the end, residual modes settle on it) is asserted by
//! `core/tests/tanpura_modal.rs`.

use javari_core::analysis::{power_spectrum, third_octave_edges_hz, third_octave_levels_db};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::{ModalString, ModalStringConfig};
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};

const SECONDS: f64 = 3.0;
const WINDOW_S: f64 = 0.5;

/// Counts, per window, the string's landings on the bridge (a step with some bridge point in
/// contact after a step with none: an impact) and the steps with some point in contact.
#[derive(Default)]
struct Census {
    was_in_contact: bool,
    landings: usize,
    steps_in_contact: usize,
}

impl Census {
    fn record(&mut self, mut gaps_m: impl Iterator<Item = f64>) {
        let in_contact = gaps_m.any(|gap| gap > 0.0);
        self.landings += usize::from(in_contact && !self.was_in_contact);
        self.steps_in_contact += usize::from(in_contact);
        self.was_in_contact = in_contact;
    }

    /// "landings per second, share of steps in contact" for a window of `steps` steps, and resets.
    fn report(&mut self, steps: usize) -> String {
        let line = format!(
            "{:5.0} /s, {:5.1} %",
            self.landings as f64 / WINDOW_S,
            100.0 * self.steps_in_contact as f64 / steps as f64
        );
        self.landings = 0;
        self.steps_in_contact = 0;
        line
    }
}

fn contact_census() {
    let mut fd = FdString::new(FdStringConfig::REFERENCE);
    let grid = fd.bridge_grid().clone();
    let fd_gaps = |string: &FdString| -> Vec<f64> {
        (0..grid.len())
            .map(|i| grid.heights_m()[i] - grid.interpolate(string.displacement_m(), i))
            .collect()
    };
    // The kept modes alone (the tiers' setting) and with two residual modes.
    let mut modal = [0, 2].map(|residual_modes| {
        ModalString::<f32>::new(ModalStringConfig {
            residual_modes,
            ..ModalStringConfig::REFERENCE
        })
    });
    let bridge = modal[0].bridge_point_count();
    let deepest = |gaps: &[f64]| gaps.iter().cloned().fold(f64::MIN, f64::max) * 1e6;
    println!("The seed's string, plucked as in the bench: contact on the bridge");
    println!(
        "at rest, deepest bridge gap (positive: on the crest): FD {:+.1} µm, modal {:+.1} µm, \
         modal with residual modes {:+.1} µm",
        deepest(&fd_gaps(&fd)),
        deepest(&modal[0].gaps_m()[..bridge]),
        deepest(&modal[1].gaps_m()[..bridge])
    );
    fd.pluck(&Pluck::default());
    for string in &mut modal {
        string.pluck(&Pluck::default());
    }
    let fd_window = (WINDOW_S / fd.config().time_step_s).round() as usize;
    let modal_window = (WINDOW_S / modal[0].config().time_step_s).round() as usize;
    let mut fd_census = Census::default();
    let mut modal_census = [Census::default(), Census::default()];
    println!(
        "| window | FD (seed grid, 176.4 kHz) | modal (live spacing, 44.1 kHz) | \
         modal, two residual modes |"
    );
    println!("|---|---|---|---|");
    let windows = (SECONDS / WINDOW_S).round() as usize;
    for window in 0..windows {
        for _ in 0..fd_window {
            fd.step();
            fd_census.record(fd_gaps(&fd).into_iter());
        }
        for (string, census) in modal.iter_mut().zip(&mut modal_census) {
            for _ in 0..modal_window {
                string.step();
                census.record(string.gaps_m()[..bridge].iter().copied());
            }
        }
        println!(
            "| {:.1}–{:.1} s | {} | {} | {} |",
            window as f64 * WINDOW_S,
            (window + 1) as f64 * WINDOW_S,
            fd_census.report(fd_window),
            modal_census[0].report(modal_window),
            modal_census[1].report(modal_window)
        );
    }
}

fn one_string(quality: Quality) -> Vec<f64> {
    let settings = VoiceSettings {
        quality,
        ..VoiceSettings::default()
    };
    let mut voice = TanpuraVoice::new(&settings, 44_100.0);
    voice.pluck(&Pluck::default());
    let mut output = vec![0.0f32; (SECONDS * 44_100.0) as usize / 64 * 64];
    for block in output.chunks_mut(64) {
        voice.process(block);
    }
    output.iter().map(|&x| f64::from(x)).collect()
}

fn high_band() {
    const FRAME: usize = 8192;
    let bin_hz = 44_100.0 / FRAME as f64;
    let renders = [one_string(Quality::Reference), one_string(Quality::Live)];
    println!();
    println!("The bench's one-string scene: 4–16 kHz, median / loudest bin (dB)");
    println!("| frame from | reference | live |");
    println!("|---|---|---|");
    for start_s in [0.3, 1.0, 1.5, 2.0, 2.5] {
        let start = (start_s * 44_100.0) as usize;
        let cells: Vec<String> = renders
            .iter()
            .map(|output| {
                let spectrum = power_spectrum(output, start, FRAME, FRAME);
                let band = &spectrum[(4_000.0 / bin_hz) as usize..(16_000.0 / bin_hz) as usize];
                let mut levels: Vec<f64> = band
                    .iter()
                    .map(|power| 10.0 * (power + 1e-30).log10())
                    .collect();
                levels.sort_by(f64::total_cmp);
                format!(
                    "{:.1} / {:.1}",
                    levels[levels.len() / 2],
                    levels[levels.len() - 1]
                )
            })
            .collect();
        println!("| {start_s:.1} s | {} | {} |", cells[0], cells[1]);
    }
}

/// The bench's third-octave band levels (`analysis::third_octave_levels_db`): the bands' lower
/// edges and the levels per frame.
fn band_levels(output: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
    (
        third_octave_edges_hz(),
        third_octave_levels_db(output, 44_100.0),
    )
}

/// The live tier's third-octave levels above 1 kHz against the reference's, averaged over the
/// frames where the reference's band lies within 60 dB of its loudest (the bench's rule).
fn band_differences() {
    let (edges, reference) = band_levels(&one_string(Quality::Reference));
    let (_, live) = band_levels(&one_string(Quality::Live));
    println!();
    println!(
        "The bench's one-string scene: live minus reference, third-octave bands, mean over 3 s"
    );
    println!("| band from | difference | frames counted |");
    println!("|---|---|---|");
    for (band, low) in edges.iter().enumerate().take(edges.len() - 1) {
        if *low < 1_000.0 {
            continue;
        }
        let (mut sum, mut count) = (0.0, 0);
        for (mine, theirs) in live.iter().zip(&reference) {
            let floor = theirs.iter().cloned().fold(f64::MIN, f64::max) - 60.0;
            if theirs[band] > floor {
                sum += mine[band].max(floor) - theirs[band];
                count += 1;
            }
        }
        if count > 0 {
            println!("| {low:.0} Hz | {:+.1} dB | {count} |", sum / count as f64);
        }
    }
}

/// The rest contact on the crest with 0 to 8 residual modes and bridge points 2 to 0.25 mm apart,
/// and what a change of configuration (the thread moved by 0.1 mm and back) costs with them.
fn residual_modes_at_rest() {
    println!();
    println!("Residual modes: the seed's string at rest on the crest");
    println!("| bridge points | residual modes | deepest bridge gap | points on the crest | set_config |");
    println!("|---|---|---|---|---|");
    for spacing_m in [2e-3, 1e-3, 0.5e-3, 0.25e-3] {
        for residual_modes in [0, 1, 2, 4, 8] {
            let config = ModalStringConfig {
                residual_modes,
                bridge_point_spacing_m: spacing_m,
                ..ModalStringConfig::REFERENCE
            };
            let mut string = ModalString::<f32>::new(config);
            let bridge = string.bridge_point_count();
            let gaps = &string.gaps_m()[..bridge];
            let deepest = gaps.iter().cloned().fold(f64::MIN, f64::max);
            let touching = gaps.iter().filter(|&&gap| gap > 0.0).count();
            // Best of 20 changes of the thread's position, each followed by one step.
            let mut fastest = f64::MAX;
            for change in 0..20 {
                let mut moved = config;
                if let Some(thread) = moved.thread.as_mut() {
                    thread.position_m += if change % 2 == 0 { 1e-4 } else { 0.0 };
                }
                let start = std::time::Instant::now();
                string.set_config(moved);
                fastest = fastest.min(start.elapsed().as_secs_f64());
                string.step();
            }
            println!(
                "| {:.2} mm | {residual_modes} | {:+.2} µm | {touching} | {:.0} µs |",
                spacing_m * 1e3,
                deepest * 1e6,
                fastest * 1e6
            );
        }
    }
}

fn main() {
    contact_census();
    high_band();
    band_differences();
    residual_modes_at_rest();
}
