use javari_core::excitation::Pluck;
use javari_core::tanpura_string::{SolverKind, TanpuraString, TanpuraStringConfig};
use std::time::Instant;
fn run(kind: SolverKind, lossless: bool, track: bool) -> Vec<f64> {
    let mut config = TanpuraStringConfig::REFERENCE;
    config.track_energy = track;
    config.solver = kind;
    if lossless {
        config = config.lossless();
    }
    let mut s = TanpuraString::new(config);
    s.pluck(&Pluck::default());
    let e0 = s.energy_j();
    let start = Instant::now();
    let steps = 176400;
    let mut out = Vec::with_capacity(steps);
    let mut maxdev: f64 = 0.0;
    for _ in 0..steps {
        s.step();
        out.push(s.nut_force_n());
        if track {
            let dev = (s.energy_j() + s.cumulative_losses_j() - e0) / e0;
            maxdev = maxdev.max(dev.abs());
        }
    }
    let el = start.elapsed().as_secs_f64();
    let st = s.newton_stats();
    println!("{kind:?} lossless {lossless} track {track}: rtf {:.2} maxdev {maxdev:.2e} mean it {:.2} max it {} caps {} nocontact {}", steps as f64/176400.0/el, st.mean_iterations(), st.max_iterations, st.cap_hits, st.steps_without_contact);
    out
}
fn main() {
    let a = run(SolverKind::FullNewton, true, true);
    let b = run(SolverKind::Condensed, true, true);
    for window in [100usize, 1000, 10000, 50000, 176400] {
        let d = a[..window]
            .iter()
            .zip(&b[..window])
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        println!("window {window}: max diff {d:e}");
    }
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    let peak = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    println!("max nut diff {diff:e} peak {peak}");
    run(SolverKind::Condensed, false, false);
}
