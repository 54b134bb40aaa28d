//! Times the whole Fig. 7 sweep of seed 001: Helmholtz thresholds of Raman's model for
//! p = 1 … 10, q = p … 20 (155 cases), λ = 0.9995, γ = 1, in both state-vector formulations.
//!
//! Run with `cargo bench -p javari-core --bench stability`. Prints wall time per sweep (best of
//! a few repetitions) and per case; nothing is asserted about speed.

use javari_core::stability::{
    CompactModel, ContactPattern, PeriodicMotion, SpaceTimeModel, ThresholdSearch, TransferModel,
};
use std::hint::black_box;
use std::time::Instant;

const LAMBDA: f64 = 0.9995;

fn cases() -> Vec<(usize, usize)> {
    (1..=10)
        .flat_map(|p| (p..=20).map(move |q| (p, q)))
        .collect()
}

fn sweep<M: TransferModel>(build: impl Fn(usize, usize) -> PeriodicMotion<M>) -> (f64, usize) {
    let search = ThresholdSearch::default();
    let mut alpha_sum = 0.0;
    let mut evaluations = 0;
    for (p, q) in cases() {
        let outcome = search.run(&build(p, q)).expect("valid case");
        let threshold = outcome
            .crossing()
            .expect("every Fig. 7 case has a threshold");
        alpha_sum += threshold.alpha(LAMBDA);
        evaluations += threshold.evaluations;
    }
    (alpha_sum, evaluations)
}

fn time<M: TransferModel>(name: &str, build: impl Fn(usize, usize) -> PeriodicMotion<M> + Copy) {
    let mut best = f64::INFINITY;
    let mut evaluations = 0;
    for _ in 0..3 {
        let start = Instant::now();
        let (alpha_sum, count) = sweep(build);
        black_box(alpha_sum);
        best = best.min(start.elapsed().as_secs_f64());
        evaluations = count;
    }
    let cases = cases().len();
    println!(
        "fig7 sweep, {name:<9}: {cases} cases in {:.3} s ({:.2} ms per case, {evaluations} \
         eigenvalue problems, {:.1} µs each)",
        best,
        1e3 * best / cases as f64,
        1e6 * best / evaluations as f64
    );
}

fn main() {
    assert_eq!(cases().len(), 155);
    time("compact", |p, q| {
        PeriodicMotion::new(
            CompactModel::raman(p, q, LAMBDA).unwrap(),
            ContactPattern::helmholtz_compact(p, q).unwrap(),
            1.0,
        )
        .unwrap()
    });
    time("spacetime", |p, q| {
        PeriodicMotion::new(
            SpaceTimeModel::new(p, q, LAMBDA).unwrap(),
            ContactPattern::helmholtz_spacetime(p, q).unwrap(),
            1.0,
        )
        .unwrap()
    });
}
