use javari_core::excitation::Pluck;
use javari_core::tanpura_string::{TanpuraString, TanpuraStringConfig};
fn main() {
    let mut s = TanpuraString::new(TanpuraStringConfig::REFERENCE);
    s.pluck(&Pluck::default());
    let t = std::time::Instant::now();
    for _ in 0..176400 {
        s.step();
    }
    println!(
        "rtf {:.2} mean it {:.2}",
        1.0 / t.elapsed().as_secs_f64(),
        s.newton_stats().mean_iterations()
    );
}
