//! Time-domain simulation of Raman's model, the cross-check of seed 001, section 2.5 (Fig. 14).
//!
//! The string is Raman's: the bow sits p steps (round trip) from one end and q from the other,
//! each end reflects −λ, and the time step is the compact formulation's (section 3.1), so the
//! state is the same history of outgoing waves `[L_p, …, L₁, R₁, …, R_q]` and a perturbation of
//! a periodic motion evolves by exactly the transfer matrix of [`super::CompactModel::raman`].
//! Each step (`shared/notes/bowed-model.md`):
//!
//! - incoming `i_L = −λ L_p`, `i_R = −λ R_q`, `v_h = i_L + i_R`;
//! - the string velocity at the bow is `v = v_h + f Y₀/2`, and the outgoing waves are
//!   `L₁ = v − i_L`, `R₁ = v − i_R`;
//! - slipping: the friction law of eq. 20, `f = F_b (μ₀ + k v)` (μ₀ = 0.3, k = 0.01 s/m), solved
//!   in closed form `v = (v_h + F_b μ₀ Y₀/2)/(1 − F_b k Y₀/2)`; linearised, this bow reflects
//!   exactly ζ = k F_b Y₀/(2 − k F_b Y₀) (eq. 3);
//! - sticking, with the simple torsion model of section 2.1 (torsional waves radiated and never
//!   returned, admittance Y_t): the bow surface is held at the bow speed, `v + f Y_t/2 = v_b`, so
//!   `f = 2 (v_b − v_h)/(Y₀ + Y_t)` and a perturbation is transmitted with `1 − γ`,
//!   γ = Y₀/(Y₀ + Y_t) (eq. 5–7; γ = 1 is a rigid stick);
//! - hysteresis: a sticking string starts to slip when |f| would exceed the sticking limit
//!   μ_s F_b (μ_s = 0.8); a slipping string sticks again when the slipping solution would no
//!   longer move backwards relative to the bow (v ≥ v_b). Forward slipping (v > v_b) uses the
//!   mirror image of eq. 20 about v_b; it does not occur in the seed's runs.
//!
//! [`RamanTransient::periodic_orbit`] solves for the exact periodic motion with a prescribed
//! stick/slip pattern as the fixed point of the affine one-period map, `(I − M) x = b`, so the
//! run can start on the Helmholtz motion plus "a very small level of superimposed perturbation".

use super::pattern::{BowContact, ContactPattern};
use super::StabilityError;

/// Parameters of the section 2.5 run. Velocities in m/s, forces in N, admittance in s/kg.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RamanTransientConfig {
    /// Bridge-side round trip in steps.
    pub p: usize,
    /// Finger-side round trip in steps.
    pub q: usize,
    /// Termination reflection magnitude (the reflection is −λ), 0 < λ ≤ 1.
    pub lambda: f64,
    /// Sticking reflection magnitude γ, 0 < γ ≤ 1 (1: no torsion).
    pub gamma: f64,
    /// Transverse wave admittance Y₀.
    pub admittance_s_per_kg: f64,
    /// Bow normal force F_b.
    pub bow_force_n: f64,
    /// Bow velocity v_b (> 0).
    pub bow_velocity_m_s: f64,
    /// μ₀ of the slipping law f = F_b (μ₀ + k v).
    pub friction_intercept: f64,
    /// k of the slipping law, s/m.
    pub friction_slope_s_per_m: f64,
    /// Sticking limit μ_s: |f| ≤ μ_s F_b while sticking.
    pub sticking_limit: f64,
}

impl RamanTransientConfig {
    /// The seed's run (section 2.5): p = 2, q = 5, Y₀ = 2, λ = 0.99, γ = 0.9,
    /// f = F_b (0.3 + 0.01 v) while slipping, sticking limit 0.8 F_b. The seed does not give the
    /// bow speed; `bow_velocity_m_s` is the caller's choice (see the tests for the one used).
    pub fn section_2_5(bow_force_n: f64, bow_velocity_m_s: f64) -> Self {
        Self {
            p: 2,
            q: 5,
            lambda: 0.99,
            gamma: 0.9,
            admittance_s_per_kg: 2.0,
            bow_force_n,
            bow_velocity_m_s,
            friction_intercept: 0.3,
            friction_slope_s_per_m: 0.01,
            sticking_limit: 0.8,
        }
    }

    /// ζ of this run's slipping bow (eq. 3, exact).
    pub fn zeta(&self) -> f64 {
        let loop_gain = self.friction_slope_s_per_m * self.bow_force_n * self.admittance_s_per_kg;
        loop_gain / (2.0 - loop_gain)
    }

    fn validate(&self) -> Result<(), StabilityError> {
        let fail = |message: String| Err(StabilityError::InvalidParameter(message));
        if self.p == 0 || self.q == 0 {
            return fail(format!(
                "p and q: both must be at least 1 (got p = {}, q = {})",
                self.p, self.q
            ));
        }
        if !(self.lambda > 0.0 && self.lambda <= 1.0) {
            return fail(format!("lambda: {} must be in (0, 1]", self.lambda));
        }
        if !(self.gamma > 0.0 && self.gamma <= 1.0) {
            return fail(format!("gamma: {} must be in (0, 1]", self.gamma));
        }
        let loop_gain = self.friction_slope_s_per_m * self.bow_force_n * self.admittance_s_per_kg;
        if !(self.admittance_s_per_kg > 0.0
            && self.bow_force_n > 0.0
            && self.bow_velocity_m_s > 0.0
            && loop_gain < 2.0)
        {
            return fail(format!(
                "admittance, bow force and bow velocity must be positive and k F_b Y0 = \
                 {loop_gain} below 2"
            ));
        }
        Ok(())
    }
}

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransientStep {
    /// String velocity at the bow, m/s.
    pub velocity_m_s: f64,
    /// Friction force on the string, N.
    pub force_n: f64,
    /// Contact state during the step.
    pub contact: BowContact,
}

/// The time-domain Raman simulation.
#[derive(Debug, Clone)]
pub struct RamanTransient {
    config: RamanTransientConfig,
    /// `[L_p, …, L₁, R₁, …, R_q]`, as in the compact formulation.
    state: Vec<f64>,
    scratch: Vec<f64>,
    contact: BowContact,
    /// Direction of the current or last slip: true while the string slips backwards (v < v_b).
    slipping_backwards: bool,
    torsional_admittance_s_per_kg: f64,
}

impl RamanTransient {
    /// A string at rest, sticking to the bow.
    pub fn new(config: RamanTransientConfig) -> Result<Self, StabilityError> {
        config.validate()?;
        let size = config.p + config.q;
        Ok(Self {
            config,
            state: vec![0.0; size],
            scratch: vec![0.0; size],
            contact: BowContact::Sticking,
            slipping_backwards: true,
            // γ = Y₀/(Y₀ + Y_t)  ⇒  Y_t = Y₀ (1 − γ)/γ.
            torsional_admittance_s_per_kg: config.admittance_s_per_kg * (1.0 - config.gamma)
                / config.gamma,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &RamanTransientConfig {
        &self.config
    }

    /// The outgoing-wave history `[L_p, …, L₁, R₁, …, R_q]`, m/s.
    pub fn state(&self) -> &[f64] {
        &self.state
    }

    /// Replaces the state and the contact the next step starts from.
    /// A backward slip is assumed when `contact` is slipping.
    pub fn set_state(&mut self, state: &[f64], contact: BowContact) {
        self.state.copy_from_slice(state);
        self.contact = contact;
        self.slipping_backwards = true;
    }

    /// The contact state of the last step.
    pub fn contact(&self) -> BowContact {
        self.contact
    }

    fn incoming(&self) -> (f64, f64) {
        let lambda = self.config.lambda;
        (
            -lambda * self.state[0],
            -lambda * self.state[self.state.len() - 1],
        )
    }

    fn sticking_force(&self, history_velocity: f64) -> f64 {
        2.0 * (self.config.bow_velocity_m_s - history_velocity)
            / (self.config.admittance_s_per_kg + self.torsional_admittance_s_per_kg)
    }

    /// Slipping solution; `backwards` selects eq. 20 (v < v_b) or its mirror image (v > v_b).
    fn slipping_solution(&self, history_velocity: f64, backwards: bool) -> (f64, f64) {
        let config = &self.config;
        let half_admittance = 0.5 * config.admittance_s_per_kg;
        let force_scale = config.bow_force_n;
        let slope = config.friction_slope_s_per_m;
        // Backwards: f = F(μ₀ + k v). Forwards: f = −F(μ₀ + k (2 v_b − v)).
        let (constant, gain) = if backwards {
            (force_scale * config.friction_intercept, force_scale * slope)
        } else {
            (
                -force_scale * (config.friction_intercept + 2.0 * slope * config.bow_velocity_m_s),
                force_scale * slope,
            )
        };
        let velocity =
            (history_velocity + constant * half_admittance) / (1.0 - gain * half_admittance);
        (velocity, constant + gain * velocity)
    }

    fn advance(&mut self, velocity: f64, incoming: (f64, f64)) {
        let (incoming_left, incoming_right) = incoming;
        let p = self.config.p;
        let size = self.state.len();
        // Left history is stored oldest first: shift towards index 0, newest at p − 1.
        self.scratch[..p - 1].copy_from_slice(&self.state[1..p]);
        self.scratch[p - 1] = velocity - incoming_left;
        // Right history newest first: shift towards the end, newest at p.
        self.scratch[p] = velocity - incoming_right;
        self.scratch[p + 1..size].copy_from_slice(&self.state[p..size - 1]);
        std::mem::swap(&mut self.state, &mut self.scratch);
    }

    /// One step with the contact decided by the friction law and its hysteresis.
    pub fn step(&mut self) -> TransientStep {
        self.step_with(None)
    }

    /// One step with the contact imposed (slipping means slipping backwards, as in the
    /// Helmholtz motion): the affine map whose fixed point is a periodic motion.
    pub fn step_forced(&mut self, contact: BowContact) -> TransientStep {
        self.step_with(Some(contact))
    }

    fn step_with(&mut self, forced: Option<BowContact>) -> TransientStep {
        let incoming = self.incoming();
        let history_velocity = incoming.0 + incoming.1;
        let limit = self.config.sticking_limit * self.config.bow_force_n;
        let bow_velocity = self.config.bow_velocity_m_s;
        let sticking_force = self.sticking_force(history_velocity);
        // A slip that starts from sticking goes the way the bow is pulling.
        let fresh_slip_backwards = sticking_force > 0.0;
        let (force, contact, backwards) = match (forced, self.contact) {
            (Some(BowContact::Sticking), _) => (sticking_force, BowContact::Sticking, true),
            (Some(BowContact::Slipping), _) => {
                let (_, force) = self.slipping_solution(history_velocity, true);
                (force, BowContact::Slipping, true)
            }
            (None, BowContact::Sticking) if sticking_force.abs() <= limit => (
                sticking_force,
                BowContact::Sticking,
                self.slipping_backwards,
            ),
            (None, BowContact::Sticking) => {
                let (_, force) = self.slipping_solution(history_velocity, fresh_slip_backwards);
                (force, BowContact::Slipping, fresh_slip_backwards)
            }
            (None, BowContact::Slipping) => {
                // Keep slipping in the same direction while that solution exists; otherwise
                // stick, or slip the other way if sticking cannot hold.
                let backwards = self.slipping_backwards;
                let (velocity, force) = self.slipping_solution(history_velocity, backwards);
                let still_slipping = if backwards {
                    velocity < bow_velocity
                } else {
                    velocity > bow_velocity
                };
                if still_slipping {
                    (force, BowContact::Slipping, backwards)
                } else if sticking_force.abs() <= limit {
                    (sticking_force, BowContact::Sticking, backwards)
                } else {
                    let (_, force) = self.slipping_solution(history_velocity, fresh_slip_backwards);
                    (force, BowContact::Slipping, fresh_slip_backwards)
                }
            }
        };
        let velocity = history_velocity + force * 0.5 * self.config.admittance_s_per_kg;
        self.contact = contact;
        self.slipping_backwards = backwards;
        self.advance(velocity, incoming);
        TransientStep {
            velocity_m_s: velocity,
            force_n: force,
            contact,
        }
    }

    /// The state at the start of a period of the exactly periodic motion with the stick/slip
    /// `pattern` (slips backwards): the fixed point of the affine one-period map.
    pub fn periodic_orbit(&self, pattern: &ContactPattern) -> Result<Vec<f64>, StabilityError> {
        use faer::linalg::solvers::Solve;
        let size = self.state.len();
        let mut probe = self.clone();
        let mut run_period = |start: &[f64]| -> Vec<f64> {
            probe.set_state(start, BowContact::Sticking);
            for &contact in pattern.steps() {
                probe.step_forced(contact);
            }
            probe.state.clone()
        };
        let zero = vec![0.0; size];
        let offset = run_period(&zero);
        let mut unit = vec![0.0; size];
        let mut columns = Vec::with_capacity(size);
        for index in 0..size {
            unit.fill(0.0);
            unit[index] = 1.0;
            let image = run_period(&unit);
            columns.push(image);
        }
        // (I − M) x = b with M e_j = image_j − b.
        let system = faer::Mat::from_fn(size, size, |row, column| {
            let linear = columns[column][row] - offset[row];
            f64::from(u8::from(row == column)) - linear
        });
        let rhs = faer::Mat::from_fn(size, 1, |row, _| offset[row]);
        let solution = system.partial_piv_lu().solve(&rhs);
        let orbit: Vec<f64> = (0..size).map(|row| solution[(row, 0)]).collect();
        if orbit.iter().all(|value| value.is_finite()) {
            Ok(orbit)
        } else {
            Err(StabilityError::InvalidParameter(
                "periodic orbit: the one-period map has an eigenvalue 1, no unique orbit".into(),
            ))
        }
    }

    /// Runs one period freely from `orbit` and reports whether the friction law reproduces the
    /// pattern step by step (the periodic motion really is a solution of the model).
    pub fn orbit_is_consistent(&self, orbit: &[f64], pattern: &ContactPattern) -> bool {
        let mut probe = self.clone();
        let last = *pattern.steps().last().unwrap_or(&BowContact::Sticking);
        probe.set_state(orbit, last);
        pattern
            .steps()
            .iter()
            .all(|&contact| probe.step().contact == contact)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sticking_string_at_rest_is_pulled_along() {
        // From rest with no incoming waves the bow drags the string: f = 2 v_b/(Y₀ + Y_t).
        let config = RamanTransientConfig::section_2_5(50.0, 1.0);
        let mut string = RamanTransient::new(config).unwrap();
        let step = string.step();
        assert_eq!(step.contact, BowContact::Sticking);
        let torsional = 2.0 * (1.0 - 0.9) / 0.9;
        assert!((step.force_n - 2.0 / (2.0 + torsional)).abs() < 1e-15);
        // v = f Y₀/2 = (1 − γ)·0 + γ v_b: the transverse string lags the bow by the torsion.
        assert!((step.velocity_m_s - 0.9).abs() < 1e-15);
        // Newest outgoing waves: L₁ (index p − 1) and R₁ (index p), both v − 0.
        assert!((string.state()[1] - 0.9).abs() < 1e-15);
        assert!((string.state()[2] - 0.9).abs() < 1e-15);
    }

    #[test]
    fn slipping_solution_satisfies_the_friction_law_and_the_string() {
        let config = RamanTransientConfig::section_2_5(2.0, 1.0);
        let string = RamanTransient::new(config).unwrap();
        let history_velocity = -3.0;
        let (velocity, force) = string.slipping_solution(history_velocity, true);
        assert!((force - 2.0 * (0.3 + 0.01 * velocity)).abs() < 1e-14);
        assert!((velocity - (history_velocity + force)).abs() < 1e-14);
    }

    #[test]
    fn forced_periodic_orbit_is_a_fixed_point() {
        let config = RamanTransientConfig::section_2_5(2.0, 8.0);
        let string = RamanTransient::new(config).unwrap();
        let pattern = ContactPattern::helmholtz_compact(2, 5).unwrap();
        let orbit = string.periodic_orbit(&pattern).unwrap();
        let mut probe = string.clone();
        probe.set_state(&orbit, BowContact::Sticking);
        for &contact in pattern.steps() {
            probe.step_forced(contact);
        }
        for (after, before) in probe.state().iter().zip(&orbit) {
            assert!((after - before).abs() < 1e-9);
        }
    }

    #[test]
    fn invalid_configuration_is_rejected() {
        let mut config = RamanTransientConfig::section_2_5(2.0, 8.0);
        config.gamma = 0.0;
        assert!(RamanTransient::new(config)
            .unwrap_err()
            .to_string()
            .contains("gamma"));
    }
}
