use javari_core::excitation::Pluck;
use javari_core::tanpura_string::{TanpuraString, TanpuraStringConfig};
use std::time::Instant;
fn main() {
    let lossless = std::env::args().any(|a| a == "lossless");
    let mut config = TanpuraStringConfig::REFERENCE;
    config.track_energy = true;
    if lossless {
        config = config.lossless();
    }
    let mut s = TanpuraString::new(config);
    println!(
        "static failures {} rest nut {} rest bridge {} restE {}",
        s.static_solve_failures(),
        s.rest_nut_force_n(),
        s.rest_bridge_force_n(),
        s.rest_energy_j()
    );
    // penetration at rest
    let y = s.rest_displacement_m().to_vec();
    let b = s.bridge_grid();
    let mut maxpen: f64 = 0.0;
    let mut ncontact = 0;
    for i in 0..b.len() {
        let g = b.heights_m()[i] - b.interpolate(&y, i);
        if g > 0.0 {
            ncontact += 1;
        }
        maxpen = maxpen.max(g);
    }
    println!("bridge contact points {ncontact} max pen {maxpen:e}");
    let t = s.thread_grid();
    let mut maxpen: f64 = 0.0;
    let mut ncontact = 0;
    for i in 0..t.len() {
        let g = t.heights_m()[i] - t.interpolate(&y, i);
        if g > 0.0 {
            ncontact += 1;
        }
        maxpen = maxpen.max(g);
    }
    println!(
        "thread contact points {ncontact}/{} max pen {maxpen:e}",
        t.len()
    );
    s.pluck(&Pluck::default());
    println!(
        "after pluck static failures {} E {} ext {}",
        s.static_solve_failures(),
        s.energy_j(),
        s.external_work_j()
    );
    let e0 = s.energy_j();
    let start = Instant::now();
    let steps = 176400;
    let mut maxdev: f64 = 0.0;
    for k in 0..steps {
        s.step();
        let dev = (s.energy_j() + s.cumulative_losses_j() - e0) / e0;
        maxdev = maxdev.max(dev.abs());
        if k % 17640 == 0 {
            println!(
                "t={:.2} E={:.9e} loss={:.3e} dev={:.2e} nut={:.4} bridge={:.4} pen={:.2e} it={}",
                k as f64 / 176400.0,
                s.energy_j(),
                s.cumulative_losses_j(),
                dev,
                s.nut_force_n(),
                s.bridge_force_n(),
                s.max_penetration_m(),
                s.newton_stats().last_iterations
            );
        }
    }
    let el = start.elapsed().as_secs_f64();
    let st = s.newton_stats();
    println!("elapsed {el:.2}s  rtf {:.2}  maxdev {maxdev:.2e} mean it {:.2} max it {} caps {} nocontact {}", steps as f64/176400.0/el, st.mean_iterations(), st.max_iterations, st.cap_hits, st.steps_without_contact);
}
