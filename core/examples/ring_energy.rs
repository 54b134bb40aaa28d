//! How long the plucked string rings: the vibration energy above the rest state (J) at 0, 0.1,
//! 0.25, 0.5 and 1 s after the bench's pluck, for the seed's string (untuned, lossy, f64) on the
//! seed's FD scheme at N = 200 (4×), 400 (8×) and 800 (16×), and on the modal scheme with the
//! tiers' kept modes alone and with the truncated modes' static flexibility (the continuous
//! string's rest state). `cargo run --release -p javari-core --example ring_energy` (a few
//! seconds). The table of `docs/modal-tanpura.md` section 9, "How long the plucked string rings".

use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::fd::{FdString, FdStringConfig};
use javari_core::tanpura::modal::{ModalString, ModalStringConfig};

const OUTPUT_RATE_HZ: f64 = 44_100.0;
const TIMES_S: [f64; 5] = [0.0, 0.1, 0.25, 0.5, 1.0];

/// The vibration energies at [`TIMES_S`] of `string`, stepped `steps_per_second` times per
/// second by `step`, as `energy` reads them.
fn energies<S>(
    string: &mut S,
    steps_per_second: f64,
    step: impl Fn(&mut S),
    energy: impl Fn(&S) -> f64,
) -> String {
    let mut done = 0usize;
    let mut row = Vec::new();
    for seconds in TIMES_S {
        while (done as f64) < seconds * steps_per_second {
            step(string);
            done += 1;
        }
        row.push(format!("{:.3e}", energy(string)));
    }
    row.join("  ")
}

fn main() {
    println!("seconds after the pluck: {TIMES_S:?}");
    for (intervals, oversampling) in [(200, 4), (400, 8), (800, 16)] {
        let mut string = FdString::new(FdStringConfig {
            intervals,
            time_step_s: 1.0 / (OUTPUT_RATE_HZ * oversampling as f64),
            ..FdStringConfig::REFERENCE
        });
        string.pluck(&Pluck::default());
        let row = energies(
            &mut string,
            OUTPUT_RATE_HZ * oversampling as f64,
            FdString::step,
            FdString::vibration_energy_j,
        );
        println!("FD N = {intervals} at {oversampling}x: {row}");
    }
    for (name, static_flexibility) in [("kept modes only", false), ("static flexibility", true)] {
        let mut string = ModalString::<f64>::new(ModalStringConfig {
            static_flexibility,
            ..ModalStringConfig::REFERENCE
        });
        string.pluck(&Pluck::default());
        let row = energies(
            &mut string,
            OUTPUT_RATE_HZ,
            ModalString::step,
            ModalString::vibration_energy_j,
        );
        println!("modal, {name}: {row}");
    }
}
