//! Times the whole Fig. 7 sweep of seed 001: Helmholtz thresholds of Raman's model for
//! p = 1 … 10, q = p … 20 (155 cases), λ = 0.9995, γ = 1, in both state-vector formulations.
//!
//! Run with `cargo bench -p javari-core --bench stability` (divan: time per sweep, and cases per
//! second as its throughput); nothing is asserted about speed.

use divan::counter::ItemsCount;
use divan::Bencher;
use javari_core::stability::{
    CompactModel, ContactPattern, PeriodicMotion, SpaceTimeModel, ThresholdSearch, TransferModel,
};

const LAMBDA: f64 = 0.9995;

fn main() {
    assert_eq!(cases().len(), 155);
    divan::main();
}

fn cases() -> Vec<(usize, usize)> {
    (1..=10)
        .flat_map(|p| (p..=20).map(move |q| (p, q)))
        .collect()
}

/// The sum of the thresholds α over the sweep (every case must have one).
fn sweep<M: TransferModel>(build: impl Fn(usize, usize) -> PeriodicMotion<M>) -> f64 {
    let search = ThresholdSearch::default();
    cases()
        .into_iter()
        .map(|(p, q)| {
            let outcome = search.run(&build(p, q)).expect("valid case");
            let threshold = outcome
                .crossing()
                .expect("every Fig. 7 case has a threshold");
            threshold.alpha(LAMBDA)
        })
        .sum()
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn fig7_sweep_compact(bencher: Bencher) {
    bencher.counter(ItemsCount::new(cases().len())).bench(|| {
        sweep(|p, q| {
            PeriodicMotion::new(
                CompactModel::raman(p, q, LAMBDA).unwrap(),
                ContactPattern::helmholtz_compact(p, q).unwrap(),
                1.0,
            )
            .unwrap()
        })
    });
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn fig7_sweep_spacetime(bencher: Bencher) {
    bencher.counter(ItemsCount::new(cases().len())).bench(|| {
        sweep(|p, q| {
            PeriodicMotion::new(
                SpaceTimeModel::new(p, q, LAMBDA).unwrap(),
                ContactPattern::helmholtz_spacetime(p, q).unwrap(),
                1.0,
            )
            .unwrap()
        })
    });
}
