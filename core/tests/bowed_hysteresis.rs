//! Hysteresis at the bow in the running voice (issue 4; `bowed-model.md`): where the string's
//! line meets the friction curve three times, the branch the contact was on decides. In
//! Helmholtz motion this happens every period: before release (sticking is held although a
//! sliding intersection already exists) and, some periods, before capture (slipping is held
//! although sticking has become possible).

mod bowed_common;
use bowed_common::*;
use javari_core::bowed::{BowPoint, BowedVoice, ContactState, FrictionLaw};

#[test]
fn three_intersections_occur_each_period_and_the_branch_memory_decides() {
    let controls = Controls::violin(0.1, 0.35);
    let mut voice = violin_string(&controls);
    let total = (controls.sample_rate_hz * 1.0) as usize;
    let mut previous = ContactState::Sticking;
    let mut ambiguous_samples = 0usize;
    let mut would_differ_without_memory = 0usize;
    let mut held_slipping = 0usize;
    let line = 2.0 * voice.wave_impedance_n_s_m();
    let law = *voice.friction();
    for i in 0..total {
        voice.next_sample();
        let solution = voice.last_bow_point();
        if i > total / 2 && solution.intersections == 3 {
            ambiguous_samples += 1;
            // The branch memory at work: the state is the previous sample's.
            assert_eq!(solution.state, previous, "sample {i}");
            // The free velocity this sample, recovered from the line: v_h = v − f/(2Z₀).
            let free = solution.velocity_m_s - solution.friction_force_n / line;
            // A solver that had been on the other branch picks the other intersection.
            let mut other = BowPoint::new();
            other.set_state(match previous {
                ContactState::Sticking => ContactState::Slipping,
                ContactState::Slipping => ContactState::Sticking,
            });
            let alternative = other.solve(
                &law,
                line,
                free,
                controls.bow_velocity_m_s,
                controls.bow_force_n,
            );
            assert_ne!(alternative.state, solution.state);
            assert!((alternative.velocity_m_s - solution.velocity_m_s).abs() > 1e-3);
            if previous == ContactState::Slipping {
                // Still slipping although sticking would hold: |f_stick| ≤ μ_s F_b.
                let stick_force = line * (controls.bow_velocity_m_s - free);
                assert!(stick_force.abs() <= law.static_coefficient() * controls.bow_force_n);
                held_slipping += 1;
            }
            would_differ_without_memory += 1;
        }
        previous = solution.state;
    }
    let periods = 0.5 * controls.sample_rate_hz / controls.period_samples();
    println!(
        "{ambiguous_samples} samples with three intersections over {periods:.0} periods, {held_slipping} of them held slipping"
    );
    // Both directions of the memory show: sticking held while a sliding intersection already
    // exists (before release), and slipping held while sticking is already possible (before
    // capture).
    assert!(held_slipping > 0 && held_slipping < ambiguous_samples);
    assert!(
        ambiguous_samples as f64 >= periods - 2.0,
        "too few ambiguous samples: {ambiguous_samples}"
    );
    assert_eq!(would_differ_without_memory, ambiguous_samples);
}
