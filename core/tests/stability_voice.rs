//! Woodhouse's linear analysis applied to the bowed voice's own settings
//! (`stability::voice_link`), checked against what the time-domain voice does.
//!
//! `bowed_schelleng.rs` measures, for the violin-A voice at 220 Hz and v_b = 0.1 m/s, the largest
//! bow force that keeps Helmholtz motion: 0.246 N at β = 0.2, 0.624 N at β = 0.1 and 1.130 N at
//! β = 0.05. Only the first lies well below Schelleng's F_max (−29 %, against −10 % and −18 %).
//! The analysis explains why: at β = 0.2 the Helmholtz motion turns linearly unstable at a force
//! near the measured limit, while at β = 0.1 and 0.05 it stays stable far above the measured
//! limits, which are therefore the sticking limits Schelleng's formula describes.

use javari_core::bowed::StringConstants;
use javari_core::stability::{voice_stability_margin, VoiceSetting};

fn critical_force_n(beta: f64) -> f64 {
    let setting =
        VoiceSetting::with_default_friction(StringConstants::violin_a(), 220.0, beta, 0.1, 0.1);
    voice_stability_margin(&setting)
        .unwrap()
        .critical_bow_force_n
        .expect("a falling friction curve has a threshold")
}

#[test]
fn analysis_predicts_the_voice_helmholtz_limit_at_beta_0_2() {
    let measured_limit_n = 0.246;
    let critical = critical_force_n(0.2);
    assert!(
        (critical - measured_limit_n).abs() <= 0.2 * measured_limit_n,
        "critical {critical} N against the measured limit {measured_limit_n} N"
    );
    // The margin changes side at the critical force.
    let margin = |force: f64| {
        voice_stability_margin(&VoiceSetting::with_default_friction(
            StringConstants::violin_a(),
            220.0,
            0.2,
            force,
            0.1,
        ))
        .unwrap()
    };
    assert!(margin(0.9 * critical).stable);
    assert!(!margin(1.1 * critical).stable);
}

#[test]
fn at_smaller_beta_the_measured_limits_are_sticking_limits_not_instabilities() {
    for (beta, measured_limit_n) in [(0.1, 0.624), (0.05, 1.130)] {
        let critical = critical_force_n(beta);
        assert!(
            critical > 1.5 * measured_limit_n,
            "β = {beta}: critical {critical} N against the measured limit {measured_limit_n} N"
        );
    }
}
