//! A bounded Newton iteration: settings, statistics and the loop itself.
//!
//! The tanpura step solves `F(s) = 0` (seed 000, eq. 22) with the residual
//!
//! ```text
//! F(s) = A s + 2(D yⁿ − d_b − qⁿ) − Σ_barriers I* f̃(I s),   A = (1 + γΔt/2) I + (1 + 2η/Δt) D
//! ```
//!
//! and the Jacobian `J = A + Σ I* C I` (eq. 24), symmetric positive definite. Each iteration
//! solves `J δ = F(s)` and sets `s ← s − δ`. It stops when `‖δ‖∞ ≤ tolerance` (metres): Newton
//! converges quadratically on this piecewise-smooth but C¹ residual, so the remaining error is
//! far below the last update. When `max_iterations` updates have been made without meeting the
//! tolerance, the step completes with the last iterate, the cap hit is counted, and nothing
//! panics: the audio thread carries on and the statistics tell the user.

/// Tolerance and cap of the bounded Newton iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonSettings {
    /// Stop when the largest update component is at most this, m.
    pub tolerance_m: f64,
    /// Most updates per time step (≥ 1).
    pub max_iterations: u32,
}

impl NewtonSettings {
    /// The reference configuration: an update of 1e-13 m is at the level of round-off for
    /// millimetre displacements, so the energy balance holds to round-off. The cap leaves
    /// room for the stiffest contact (k_b = 1e12 N/m² needs up to 13 updates at this grid).
    pub const REFERENCE: NewtonSettings = NewtonSettings {
        tolerance_m: 1e-13,
        max_iterations: 30,
    };
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self::REFERENCE
    }
}

/// Running statistics of the Newton iteration over many steps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NewtonStats {
    /// Time steps taken.
    pub steps: u64,
    /// Steps solved by the linear predictor alone (no barrier point near contact).
    pub steps_without_contact: u64,
    /// Newton updates made in total.
    pub iterations: u64,
    /// The most updates any step needed.
    pub max_iterations: u32,
    /// Steps that ended at the cap without meeting the tolerance.
    pub cap_hits: u64,
    /// Updates made in the last step.
    pub last_iterations: u32,
    /// Steps whose condensed solve was redone with every barrier point, because the accepted
    /// step reached farther than the candidate margin (`fd/mod.rs`).
    pub redone_steps: u64,
}

impl NewtonStats {
    /// No steps yet (the `Default`, usable in constants).
    pub const ZERO: NewtonStats = NewtonStats {
        steps: 0,
        steps_without_contact: 0,
        iterations: 0,
        max_iterations: 0,
        cap_hits: 0,
        last_iterations: 0,
        redone_steps: 0,
    };

    /// Mean Newton updates per time step.
    pub fn mean_iterations(&self) -> f64 {
        if self.steps == 0 {
            0.0
        } else {
            self.iterations as f64 / self.steps as f64
        }
    }

    /// Records one step that needed `iterations` updates and did or did not converge.
    pub fn record(&mut self, iterations: u32, converged: bool) {
        self.steps += 1;
        self.iterations += iterations as u64;
        self.max_iterations = self.max_iterations.max(iterations);
        self.last_iterations = iterations;
        if iterations == 0 {
            self.steps_without_contact += 1;
        }
        if !converged {
            self.cap_hits += 1;
        }
    }

    /// Adds another string's statistics (for an instrument of several strings).
    pub fn merge(&mut self, other: &NewtonStats) {
        self.steps += other.steps;
        self.steps_without_contact += other.steps_without_contact;
        self.iterations += other.iterations;
        self.max_iterations = self.max_iterations.max(other.max_iterations);
        self.cap_hits += other.cap_hits;
        self.last_iterations = self.last_iterations.max(other.last_iterations);
        self.redone_steps += other.redone_steps;
    }
}

/// A nonlinear system that can take one Newton update of its own unknowns.
pub trait NewtonSystem {
    /// Evaluates the residual and Jacobian at the current iterate, solves `J δ = F` and applies
    /// `s ← s − δ`. Returns `‖δ‖∞`, or `None` when the Jacobian could not be factorised (the
    /// iterate is then left unchanged).
    fn newton_update(&mut self) -> Option<f64>;
}

/// Runs at most `settings.max_iterations` updates. Returns `(updates made, converged)`.
pub fn solve_bounded(system: &mut impl NewtonSystem, settings: &NewtonSettings) -> (u32, bool) {
    let cap = settings.max_iterations.max(1);
    for iteration in 1..=cap {
        match system.newton_update() {
            Some(update) if update <= settings.tolerance_m => return (iteration, true),
            Some(update) if update.is_finite() => {}
            // A non-finite update or a failed factorisation cannot improve: stop here.
            _ => return (iteration, false),
        }
    }
    (cap, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scalar test system: s³ + s − 10 = 0 (root 2).
    struct Cubic {
        s: f64,
    }

    impl NewtonSystem for Cubic {
        fn newton_update(&mut self) -> Option<f64> {
            let residual = self.s * self.s * self.s + self.s - 10.0;
            let slope = 3.0 * self.s * self.s + 1.0;
            let delta = residual / slope;
            self.s -= delta;
            Some(delta.abs())
        }
    }

    #[test]
    fn converges_quadratically_to_the_root() {
        let mut system = Cubic { s: 1.5 };
        let settings = NewtonSettings {
            tolerance_m: 1e-14,
            max_iterations: 20,
        };
        let (iterations, converged) = solve_bounded(&mut system, &settings);
        assert!(converged);
        assert!(iterations <= 6, "{iterations}");
        assert!((system.s - 2.0).abs() < 1e-15);
    }

    #[test]
    fn cap_hit_keeps_the_last_iterate_and_reports() {
        let mut system = Cubic { s: 1.0 };
        let settings = NewtonSettings {
            tolerance_m: 1e-14,
            max_iterations: 2,
        };
        let (iterations, converged) = solve_bounded(&mut system, &settings);
        assert_eq!((iterations, converged), (2, false));
        assert!(system.s.is_finite() && system.s != 1.0);
        let mut stats = NewtonStats::default();
        stats.record(iterations, converged);
        stats.record(0, true);
        assert_eq!(stats.cap_hits, 1);
        assert_eq!(stats.steps_without_contact, 1);
        assert_eq!(stats.mean_iterations(), 1.0);
    }
}
