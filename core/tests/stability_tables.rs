//! Reproduction of the numbers printed in Woodhouse, "On the stability of bowed string motion"
//! (seed 001): Tables I–IV, eq. 13 and the thresholds of section 2.5, plus the time-domain
//! cross-check of Fig. 14. Where the printed numbers cannot be reproduced by a consistent reading,
//! the computed values are pinned here and `docs/stability.md` gives the evidence.

use javari_core::stability::pattern::BowContact;
use javari_core::stability::spectrum::Eigenvalue;
use javari_core::stability::{
    bow_force_from_zeta, zeta_linear_approximation, CompactModel, ContactPattern, PeriodicMotion,
    RamanTransient, RamanTransientConfig, SpaceTimeModel, ThresholdSearch, TransferModel,
};

/// True when `value` rounds to `printed` at `decimals` decimals.
fn rounds_to(value: f64, printed: f64, decimals: i32) -> bool {
    let scale = 10f64.powi(decimals);
    (value * scale).round() == (printed * scale).round()
}

fn threshold_zeta<M: TransferModel>(motion: &PeriodicMotion<M>) -> f64 {
    ThresholdSearch::default()
        .run(motion)
        .unwrap()
        .crossing()
        .expect("a crossing")
        .zeta
}

/// Matches computed eigenvalues to printed (modulus, phase/2π) rows one to one, greedily by
/// modulus then phase; returns the printed rows left unmatched.
fn unmatched_rows(
    computed: &[Eigenvalue],
    printed: &[(f64, f64)],
    decimals: i32,
) -> Vec<(f64, f64)> {
    let mut used = vec![false; computed.len()];
    let mut missing = Vec::new();
    for &(modulus, phase) in printed {
        let found = computed.iter().enumerate().position(|(index, eigenvalue)| {
            !used[index]
                && rounds_to(eigenvalue.modulus, modulus, decimals)
                && (modulus < 1e-3 || rounds_to(eigenvalue.phase_over_2pi, phase, decimals))
        });
        match found {
            Some(index) => used[index] = true,
            None => missing.push((modulus, phase)),
        }
    }
    missing
}

fn table_i_motion_spacetime() -> PeriodicMotion<SpaceTimeModel> {
    PeriodicMotion::new(
        SpaceTimeModel::new(2, 3, 0.99).unwrap(),
        ContactPattern::helmholtz_spacetime(2, 3).unwrap(),
        1.0,
    )
    .unwrap()
}

fn table_i_motion_compact() -> PeriodicMotion<CompactModel> {
    PeriodicMotion::new(
        CompactModel::raman(2, 3, 0.99).unwrap(),
        ContactPattern::helmholtz_compact(2, 3).unwrap(),
        1.0,
    )
    .unwrap()
}

/// Table I: p = 2, q = 3, λ = 0.99, ζ = 0.01, γ = 1 (modulus, phase/2π, order).
const TABLE_I: [(f64, f64, u32); 10] = [
    (0.9801, 0.0, 1),
    (0.9801, 0.0, 1),
    (0.9866, 0.3333, 3),
    (0.9866, -0.3333, 3),
    (0.9866, 0.3333, 3),
    (0.9866, -0.3333, 3),
    (0.9899, 0.5000, 2),
    (0.9899, 0.5000, 2),
    (0.9964, 0.0, 1),
    (0.9964, 0.0, 1),
];

#[test]
fn table_i_to_four_decimals_in_both_formulations() {
    let spacetime = table_i_motion_spacetime().spectrum(0.01).unwrap();
    assert_eq!(spacetime.len(), 10);
    let printed: Vec<(f64, f64)> = TABLE_I.iter().map(|row| (row.0, row.1)).collect();
    assert_eq!(unmatched_rows(&spacetime, &printed, 4), vec![]);
    for &(modulus, phase, order) in &TABLE_I {
        assert!(spacetime
            .iter()
            .any(|eigenvalue| rounds_to(eigenvalue.modulus, modulus, 4)
                && rounds_to(eigenvalue.phase_over_2pi, phase, 4)
                && eigenvalue.subharmonic_order == order));
    }
    // The compact formulation holds one copy of each repeated pair (section 3.1).
    let compact = table_i_motion_compact().spectrum(0.01).unwrap();
    assert_eq!(compact.len(), 5);
    let once = [
        (0.9801, 0.0),
        (0.9866, 0.3333),
        (0.9866, -0.3333),
        (0.9899, 0.5000),
        (0.9964, 0.0),
    ];
    assert_eq!(unmatched_rows(&compact, &once, 4), vec![]);
}

#[test]
fn table_i_critical_zeta_is_0_0122_in_both_formulations() {
    let spacetime = ThresholdSearch::default()
        .run(&table_i_motion_spacetime())
        .unwrap();
    let threshold = spacetime.crossing().unwrap();
    assert!(rounds_to(threshold.zeta, 0.0122, 4), "{}", threshold.zeta);
    assert!((threshold.critical.modulus - 1.0).abs() < 1e-9);
    // "the eigenvalue closest to the unit circle corresponds to an order-one unsubharmonic".
    assert_eq!(threshold.critical.subharmonic_order, 1);
    assert!(rounds_to(threshold.alpha(0.99), 1.22, 2));
    let compact = threshold_zeta(&table_i_motion_compact());
    assert!((compact - threshold.zeta).abs() < 1e-10);
    // Pinned to the search tolerance: ζ_c = 0.012207007957…
    assert!((threshold.zeta - 0.012_207_007_957).abs() < 1e-10);
}

#[test]
fn equation_13_for_beta_one_over_n() {
    let lambda = 0.9995;
    // Our α for n = 2 … 8, pinned (docs/stability.md lists them beside eq. 13).
    let computed = [
        1.00075, 2.00250, 2.00250, 2.76845, 3.00526, 3.69005, 4.00902,
    ];
    for n in 2..=8usize {
        let motion = PeriodicMotion::new(
            SpaceTimeModel::new(1, n - 1, lambda).unwrap(),
            ContactPattern::helmholtz_spacetime(1, n - 1).unwrap(),
            1.0,
        )
        .unwrap();
        let outcome = ThresholdSearch::default().run(&motion).unwrap();
        let threshold = outcome.crossing().unwrap();
        let n_real = n as f64;
        let closed_form = if n % 2 == 0 {
            n_real / 2.0
        } else {
            n_real / (1.0 - (std::f64::consts::PI * (n_real - 1.0) / n_real).cos())
        };
        let alpha = threshold.alpha(lambda);
        assert!(
            (alpha - computed[n - 2]).abs() < 5e-6,
            "n = {n}: α = {alpha}"
        );
        assert!(
            (alpha / closed_form - 1.0).abs() < 0.01,
            "n = {n}: α = {alpha}, eq. 13 gives {closed_form}"
        );
        // n even: octave subharmonic; n odd: n-th subharmonic (section 2.2).
        let expected_order = if n % 2 == 0 { 2 } else { n as u32 };
        assert_eq!(
            threshold.critical.subharmonic_order, expected_order,
            "n = {n}"
        );
    }
}

#[test]
fn table_ii_to_four_decimals() {
    let motion = PeriodicMotion::new(
        CompactModel::raman(2, 5, 1.0).unwrap(),
        ContactPattern::helmholtz_compact(2, 5).unwrap(),
        0.9,
    )
    .unwrap();
    let computed = motion.spectrum(0.01).unwrap();
    let printed = [
        (0.8040, 0.5000),
        (0.8040, 0.2479),
        (0.8040, -0.2479),
        (0.8053, 0.3321),
        (0.8053, -0.3321),
        (1.0000, 0.0),
        (1.0116, 0.0),
    ];
    assert_eq!(computed.len(), printed.len());
    assert_eq!(unmatched_rows(&computed, &printed, 4), vec![]);
    // The space-time formulation gives every one of them twice.
    let spacetime = PeriodicMotion::new(
        SpaceTimeModel::new(2, 5, 1.0).unwrap(),
        ContactPattern::helmholtz_spacetime(2, 5).unwrap(),
        0.9,
    )
    .unwrap()
    .spectrum(0.01)
    .unwrap();
    let twice: Vec<(f64, f64)> = printed.iter().flat_map(|row| [*row, *row]).collect();
    assert_eq!(unmatched_rows(&spacetime, &twice, 4), vec![]);
}

/// Table III as printed (modulus, phase/2π), γ = 1 and γ = 0.6.
const TABLE_III_GAMMA_1: [(f64, f64); 24] = [
    (1.001, 0.0),
    (0.968, 0.334),
    (0.968, -0.334),
    (0.964, 0.0),
    (0.911, 0.0),
    (0.910, 0.500),
    (0.890, 0.0),
    (0.871, 0.0),
    (0.871, 0.334),
    (0.871, -0.334),
    (0.781, 0.0),
    (0.758, 0.334),
    (0.758, -0.334),
    (0.743, 0.0),
    (0.728, 0.0),
    (0.727, 0.500),
    (0.701, 0.0),
    (0.679, 0.0),
    (0.675, 0.334),
    (0.675, -0.334),
    (0.640, 0.0),
    (0.000, 0.0),
    (0.000, 0.500),
    (0.000, 0.500),
];

const TABLE_III_GAMMA_0_6: [(f64, f64); 24] = [
    (1.002, 0.0),
    (0.965, 0.0),
    (0.912, 0.0),
    (0.890, 0.0),
    (0.872, 0.0),
    (0.785, 0.0),
    (0.743, 0.0),
    (0.729, 0.0),
    (0.702, 0.0),
    (0.678, 0.0),
    (0.640, 0.0),
    (0.193, 0.266),
    (0.193, 0.266),
    (0.183, 0.500),
    (0.174, 0.266),
    (0.174, 0.266),
    (0.151, 0.266),
    (0.151, -0.266),
    (0.146, 0.500),
    (0.135, 0.266),
    (0.135, -0.266),
    (0.000, 0.0),
    (0.000, 0.0),
    (0.000, 0.500),
];

fn table_iii_spectrum(slip_steps: usize, gamma: f64) -> Vec<Eigenvalue> {
    PeriodicMotion::new(
        CompactModel::three_tap(6, 16, 0.90, 0.05).unwrap(),
        ContactPattern::single_slip(22, slip_steps).unwrap(),
        gamma,
    )
    .unwrap()
    .spectrum(0.01)
    .unwrap()
}

/// Table III is reproduced with 12 slipping steps per period (2p), not the p = 6 its caption
/// states; the printed rows left over are explained in `docs/stability.md`.
#[test]
fn table_iii_reproduced_with_twelve_slipping_steps() {
    let gamma_1 = table_iii_spectrum(12, 1.0);
    assert_eq!(gamma_1.len(), 24);
    // Rows whose printed sign of phase is a misprint for a conjugate pair are compared by |phase|.
    let fold = |rows: &[(f64, f64)]| -> Vec<(f64, f64)> {
        rows.iter().map(|&(m, p)| (m, p.abs())).collect()
    };
    let folded = |spectrum: &[Eigenvalue]| -> Vec<Eigenvalue> {
        spectrum
            .iter()
            .map(|e| Eigenvalue::from_complex(e.re, e.im.abs()))
            .collect()
    };
    // γ = 1: every printed row but four matches to the printed three decimals. Pinned leftovers:
    // 1.001 (the unstable unsubharmonic; computed 1.00088, prints 1.001 ✓ but see below),
    // 0.968 ±0.334 (computed phase 0.33346 → 0.333), 0.743 (computed 0.74249 → 0.742),
    // 0.679 (computed 0.67788 → 0.678), and one 0.000 where we find the exactly neutral 1.000.
    let missing = unmatched_rows(&folded(&gamma_1), &fold(&TABLE_III_GAMMA_1), 3);
    assert_eq!(
        missing,
        vec![
            (0.968, 0.334),
            (0.968, 0.334),
            (0.743, 0.0),
            (0.679, 0.0),
            (0.000, 0.5)
        ]
    );
    let near = |modulus: f64, phase: f64| {
        gamma_1
            .iter()
            .any(|e| (e.modulus - modulus).abs() < 5e-5 && (e.phase_over_2pi - phase).abs() < 5e-5)
    };
    assert!(near(0.96798, 0.33346) && near(0.96798, -0.33346));
    assert!(near(0.74249, 0.0) && near(0.67788, 0.0));
    assert!(near(1.00088, 0.0));
    // The extra eigenvalue: exactly 1, the bow-transparent pattern L_j = c, R_j = −c that any
    // reflection functions of unit area (λ + 2σ = 1, eq. 23) carry unchanged.
    assert!(gamma_1.iter().any(|e| (e.modulus - 1.0).abs() < 1e-12));

    // γ = 0.6: every printed row matches to three decimals except the 0.193 and 0.135 pairs,
    // whose computed phases ±0.26547 and ±0.26548 round to 0.265 (printed 0.266, 3e-5 from the
    // rounding boundary), and one 0.000 that our exactly neutral eigenvalue 1.000 replaces.
    let gamma_06 = table_iii_spectrum(12, 0.6);
    let missing = unmatched_rows(&folded(&gamma_06), &fold(&TABLE_III_GAMMA_0_6), 3);
    assert_eq!(
        missing,
        vec![
            (0.193, 0.266),
            (0.193, 0.266),
            (0.135, 0.266),
            (0.135, 0.266),
            (0.000, 0.5)
        ]
    );
    let near_06 = |modulus: f64, phase: f64| {
        gamma_06
            .iter()
            .any(|e| (e.modulus - modulus).abs() < 5e-5 && (e.phase_over_2pi - phase).abs() < 5e-5)
    };
    assert!(near_06(0.19327, 0.26547) && near_06(0.13473, -0.26548));
    assert!(near_06(1.00162, 0.0));
    assert!(gamma_06.iter().any(|e| (e.modulus - 1.0).abs() < 1e-12));

    // Evidence that the caption's slip time p = 6 is not what was computed: with 6 slipping
    // steps fourth-subharmonic phases (≈ 1/4) appear, which Table III does not contain, and
    // the unstable unsubharmonic 1.001 is absent.
    let caption_reading = table_iii_spectrum(6, 1.0);
    assert!(caption_reading
        .iter()
        .any(|e| e.modulus > 0.5 && e.subharmonic_order == 4));
    assert!(caption_reading[0].modulus < 1.0 + 1e-12);
    assert!(unmatched_rows(&folded(&caption_reading), &fold(&TABLE_III_GAMMA_1), 3).len() > 10);
}

/// Table IV as printed: rows slip time 2..=10, columns p:q = 3:19 … 8:14.
// 2.718 below is a printed ratio, not Euler's number.
#[allow(clippy::approx_constant)]
const TABLE_IV: [[f64; 6]; 9] = [
    [1.867, 2.842, 2.614, 3.132, 2.347, 2.861],
    [2.721, 3.119, 2.057, 3.074, 2.368, 2.935],
    [2.687, 2.874, 2.282, 2.236, 2.414, 2.500],
    [2.593, 2.718, 2.583, 2.459, 2.451, 2.402],
    [2.588, 2.616, 2.563, 2.617, 2.386, 2.465],
    [2.563, 2.579, 2.584, 2.663, 2.523, 2.541],
    [2.550, 2.557, 2.586, 2.595, 2.547, 2.561],
    [2.546, 2.548, 2.560, 2.586, 2.556, 2.576],
    [2.539, 2.537, 2.545, 2.549, 2.591, 2.589],
];

/// Our ratios, pinned (4 decimals): the reproduction of Table IV.
const TABLE_IV_COMPUTED: [[f64; 6]; 9] = [
    [1.8674, 2.8422, 2.6146, 3.1318, 2.2435, 2.8627],
    [2.6319, 3.1186, 2.0560, 3.0474, 2.3678, 2.9353],
    [2.6871, 2.8754, 2.2819, 2.2348, 2.4116, 2.4992],
    [2.5932, 2.7181, 2.5851, 2.4538, 2.4473, 2.4016],
    [2.5893, 2.6160, 2.5499, 2.6192, 2.3827, 2.4632],
    [2.5633, 2.5788, 2.5845, 2.6625, 2.5208, 2.5394],
    [2.5503, 2.5563, 2.5861, 2.5955, 2.5456, 2.5592],
    [2.5458, 2.5479, 2.5611, 2.5666, 2.5539, 2.5722],
    [2.5392, 2.5370, 2.5446, 2.5493, 2.5905, 2.5894],
];

#[test]
fn table_iv_threshold_ratios() {
    const P_Q: [(usize, usize); 6] = [(3, 19), (4, 18), (5, 17), (6, 16), (7, 15), (8, 14)];
    let threshold = |p: usize, q: usize, lambda: f64, sigma: f64, slip: usize| {
        threshold_zeta(
            &PeriodicMotion::new(
                CompactModel::three_tap(p, q, lambda, sigma).unwrap(),
                ContactPattern::single_slip(p + q, slip).unwrap(),
                1.0,
            )
            .unwrap(),
        )
    };
    let mut exact = 0;
    let mut within_0_005 = 0;
    let mut outliers = Vec::new();
    for (row, slip) in (2..=10usize).enumerate() {
        for (column, &(p, q)) in P_Q.iter().enumerate() {
            let ratio = threshold(p, q, 0.90, 0.05, slip) / threshold(p, q, 0.96, 0.02, slip);
            let pinned = TABLE_IV_COMPUTED[row][column];
            assert!(
                (ratio - pinned).abs() < 5e-5,
                "slip {slip}, {p}:{q}: {ratio} vs pinned {pinned}"
            );
            let printed = TABLE_IV[row][column];
            if rounds_to(ratio, printed, 3) {
                exact += 1;
            } else if (ratio - printed).abs() < 0.005 {
                within_0_005 += 1;
            } else {
                outliers.push((slip, p, q));
            }
        }
    }
    // 27 of 54 entries agree to the printed three decimals and 21 more within 0.005; the six
    // outliers below have a single, well-resolved crossing in both models (docs/stability.md).
    assert_eq!((exact, within_0_005), (27, 21), "outliers {outliers:?}");
    assert_eq!(
        outliers,
        vec![
            (2, 7, 15),
            (3, 3, 19),
            (3, 6, 16),
            (5, 6, 16),
            (6, 5, 17),
            (9, 6, 16)
        ]
    );
}

fn section_2_5_motion(slip_steps: usize) -> PeriodicMotion<CompactModel> {
    PeriodicMotion::new(
        CompactModel::raman(2, 5, 0.99).unwrap(),
        ContactPattern::single_slip(7, slip_steps).unwrap(),
        0.9,
    )
    .unwrap()
}

/// Section 2.5: thresholds 1.75 (Helmholtz) and 77.2 (one slip per period). Both come from
/// the proportional form of eq. 3, ζ = k F_b Y₀/2 with k = 0.01 and Y₀ = 2, i.e. ζ = 0.01 F_b;
/// the exact form ζ = k F_b Y₀/(2 − k F_b Y₀) gives 1.7216 and 43.56.
#[test]
fn section_2_5_thresholds_use_zeta_proportional_to_bow_force() {
    let (slope, admittance) = (0.01, 2.0);
    let helmholtz = threshold_zeta(&section_2_5_motion(2));
    let one_slip = threshold_zeta(&section_2_5_motion(1));
    let proportional = |zeta: f64| zeta / zeta_linear_approximation(slope, 1.0, admittance);
    assert!(rounds_to(proportional(helmholtz), 1.75, 2), "{helmholtz}");
    assert!(rounds_to(proportional(one_slip), 77.2, 1), "{one_slip}");
    let exact_helmholtz = bow_force_from_zeta(helmholtz, slope, admittance);
    let exact_one_slip = bow_force_from_zeta(one_slip, slope, admittance);
    assert!(rounds_to(exact_helmholtz, 1.7216, 4), "{exact_helmholtz}");
    assert!(rounds_to(exact_one_slip, 43.56, 2), "{exact_one_slip}");
    // The space-time formulation agrees when its steps are halved: 4 and 2 slipping steps.
    let spacetime = |slip: usize| {
        threshold_zeta(
            &PeriodicMotion::new(
                SpaceTimeModel::new(2, 5, 0.99).unwrap(),
                ContactPattern::single_slip(14, slip).unwrap(),
                0.9,
            )
            .unwrap(),
        )
    };
    assert!((spacetime(4) - helmholtz).abs() < 1e-10);
    assert!((spacetime(2) - one_slip).abs() < 1e-10);
}

/// An odd number N of space-time slipping steps splits as ⌈N/2⌉ and ⌊N/2⌋ compact ones: the
/// space-time spectrum is the union of the two compact spectra (module docs).
#[test]
fn spacetime_spectrum_is_the_union_of_two_compact_spectra() {
    let (p, q, lambda, zeta, gamma) = (3, 8, 0.98, 0.02, 0.85);
    for slip in [3usize, 5, 6] {
        let spacetime = PeriodicMotion::new(
            SpaceTimeModel::new(p, q, lambda).unwrap(),
            ContactPattern::single_slip(2 * (p + q), slip).unwrap(),
            gamma,
        )
        .unwrap()
        .spectrum(zeta)
        .unwrap();
        let mut union = Vec::new();
        for half in [slip.div_ceil(2), slip / 2] {
            union.extend(
                PeriodicMotion::new(
                    CompactModel::raman(p, q, lambda).unwrap(),
                    ContactPattern::single_slip(p + q, half).unwrap(),
                    gamma,
                )
                .unwrap()
                .spectrum(zeta)
                .unwrap(),
            );
        }
        let rows: Vec<(f64, f64)> = union
            .iter()
            .map(|e| (e.modulus, e.phase_over_2pi))
            .collect();
        assert_eq!(unmatched_rows(&spacetime, &rows, 8), vec![], "slip {slip}");
    }
}

/// The bow speed of the transient runs. The seed does not give it; with v_b = 8 m/s the
/// Helmholtz motion of this model exists for 1.0 ≲ F_b ≲ 34.4 N (tested below), so F_b = 2.0 is
/// inside the playable range and 77.2 is beyond the maximum bow force, as the seed says.
const BOW_VELOCITY_M_S: f64 = 8.0;

struct TransientRun {
    /// ln ‖x − x*‖ at the start of every period.
    log_deviation: Vec<f64>,
    /// Slipping steps in every period.
    slips: Vec<usize>,
    /// Largest change of the state over the final period.
    final_period_change: f64,
}

fn run_transient(bow_force_n: f64, periods: usize) -> TransientRun {
    let pattern = ContactPattern::helmholtz_compact(2, 5).unwrap();
    let config = RamanTransientConfig::section_2_5(bow_force_n, BOW_VELOCITY_M_S);
    let mut string = RamanTransient::new(config).unwrap();
    let orbit = string.periodic_orbit(&pattern).unwrap();
    assert!(string.orbit_is_consistent(&orbit, &pattern));
    // "A Helmholtz motion with a very small level of superimposed perturbation".
    let start: Vec<f64> = orbit
        .iter()
        .enumerate()
        .map(|(index, value)| value + 1e-9 * (1.7 * index as f64).sin())
        .collect();
    string.set_state(&start, BowContact::Sticking);
    let mut run = TransientRun {
        log_deviation: Vec::with_capacity(periods),
        slips: Vec::with_capacity(periods),
        final_period_change: 0.0,
    };
    let mut previous = start.clone();
    for _ in 0..periods {
        let deviation: f64 = string
            .state()
            .iter()
            .zip(&orbit)
            .map(|(x, x_star)| (x - x_star) * (x - x_star))
            .sum::<f64>()
            .sqrt();
        run.log_deviation.push(deviation.ln());
        previous.copy_from_slice(string.state());
        let slips = (0..7)
            .filter(|_| string.step().contact == BowContact::Slipping)
            .count();
        run.slips.push(slips);
    }
    run.final_period_change = string
        .state()
        .iter()
        .zip(&previous)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    run
}

/// Least-squares slope of `values` against their index over `range`.
fn slope(values: &[f64], range: std::ops::Range<usize>) -> f64 {
    let count = range.len() as f64;
    let mean_index = (range.start + range.end - 1) as f64 / 2.0;
    let mean_value = values[range.clone()].iter().sum::<f64>() / count;
    let (mut covariance, mut variance) = (0.0, 0.0);
    for index in range {
        let offset = index as f64 - mean_index;
        covariance += offset * (values[index] - mean_value);
        variance += offset * offset;
    }
    covariance / variance
}

/// Fig. 14: at F_b = 2.0 the perturbation grows at the rate of the leading eigenvalue (the
/// "between-the-raindrops" unsubharmonic), the Helmholtz motion gives way, and the string settles
/// on one slip per period.
#[test]
fn transient_at_bow_force_2_leaves_helmholtz_and_settles_on_one_slip() {
    let run = run_transient(2.0, 12_000);
    let config = RamanTransientConfig::section_2_5(2.0, BOW_VELOCITY_M_S);
    let leading = section_2_5_motion(2).spectrum(config.zeta()).unwrap()[0];
    assert_eq!(leading.subharmonic_order, 1);
    assert!(leading.modulus > 1.0);
    // Periods 2000–4000: the perturbation is still small (≈ 1e-9 e^{13} ≈ 1e-3 of the motion)
    // and the subdominant modes have died out.
    let measured_growth = slope(&run.log_deviation, 2000..4000).exp();
    assert!(
        (measured_growth - leading.modulus).abs() < 1e-6,
        "measured {measured_growth}, eigenvalue {}",
        leading.modulus
    );
    // The proportional ζ = 0.01 F_b = 0.02 would predict a visibly different rate.
    let proportional = section_2_5_motion(2).spectral_radius(0.02).unwrap();
    assert!(
        (measured_growth - proportional).abs() > 100.0 * (measured_growth - leading.modulus).abs()
    );

    let left_helmholtz = run.slips.iter().position(|&slips| slips != 2).unwrap();
    assert!((7680..=7690).contains(&left_helmholtz), "{left_helmholtz}");
    assert!(run.slips[11_000..].iter().all(|&slips| slips == 1));
    assert!(
        run.final_period_change < 1e-9,
        "{}",
        run.final_period_change
    );
}

/// The simulation's own threshold lies where the exact ζ(F_b) puts it (1.7216), below the
/// seed's 1.75: at F_b = 1.70 the perturbation decays, at 1.74 it grows.
#[test]
fn transient_threshold_brackets_the_exact_zeta_relation() {
    let decaying = run_transient(1.70, 3000);
    assert!(slope(&decaying.log_deviation, 1000..3000) < 0.0);
    assert!(decaying.slips.iter().all(|&slips| slips == 2));
    let growing = run_transient(1.74, 3000);
    assert!(slope(&growing.log_deviation, 1000..3000) > 0.0);
}

/// With this bow speed the Helmholtz motion exists at F_b = 2.0 but not at 77.2 (beyond the
/// maximum bow force), and the one-slip motion of Fig. 14d is a periodic solution at 2.0.
#[test]
fn playable_range_of_the_transient_model() {
    let helmholtz = ContactPattern::helmholtz_compact(2, 5).unwrap();
    let one_slip = ContactPattern::single_slip(7, 1).unwrap();
    let exists = |force: f64, pattern: &ContactPattern| {
        let string =
            RamanTransient::new(RamanTransientConfig::section_2_5(force, BOW_VELOCITY_M_S))
                .unwrap();
        let orbit = string.periodic_orbit(pattern).unwrap();
        string.orbit_is_consistent(&orbit, pattern)
    };
    assert!(exists(2.0, &helmholtz));
    assert!(exists(2.0, &one_slip));
    assert!(exists(1.01, &helmholtz) && !exists(0.98, &helmholtz));
    assert!(exists(34.0, &helmholtz) && !exists(34.6, &helmholtz));
    assert!(!exists(77.2, &helmholtz));
}

/// Fig. 9: halving the slip time (Fig. 8, eq. 16) never lowers the Helmholtz threshold of Fig. 7
/// and raises it by "rather more than a factor of two" at most. Checked on p = 1, 2 (all q) and on
/// β = 0.4, where the full sweep (`cargo xtask stability --sweep fig7|fig8`) finds the maximum.
#[test]
fn fig_9_halving_the_slip_time_never_lowers_the_threshold() {
    let lambda = 0.9995;
    let ratio = |p: usize, q: usize| {
        let helmholtz = threshold_zeta(
            &PeriodicMotion::new(
                CompactModel::raman(p, q, lambda).unwrap(),
                ContactPattern::helmholtz_compact(p, q).unwrap(),
                1.0,
            )
            .unwrap(),
        );
        let half_slip = threshold_zeta(
            &PeriodicMotion::new(
                SpaceTimeModel::new(p, q, lambda).unwrap(),
                ContactPattern::single_slip(2 * (p + q), p).unwrap(),
                1.0,
            )
            .unwrap(),
        );
        half_slip / helmholtz
    };
    let mut unchanged = 0;
    for p in 1..=2 {
        for q in p..=20 {
            let value = ratio(p, q);
            assert!(value > 1.0 - 1e-7, "p = {p}, q = {q}: ratio {value}");
            if value < 1.0 + 1e-7 {
                unchanged += 1;
            }
        }
    }
    assert!(unchanged > 0);
    assert!((ratio(6, 9) - 2.3051).abs() < 5e-5);
}
