//! Stick/slip sequences of the underlying periodic motion (seed 001, section 2.3).
//!
//! The only role of the periodic solution in the linear analysis of a friction-curve model with a
//! constant slope is the order of sticking and slipping steps at the bow (section 2.4). With a
//! curved friction curve each slipping step carries its own ζ; [`ContactPattern::bow_reflections`]
//! gives the uniform case and callers may pass any per-step sequence to the models.

use super::StabilityError;

/// The bow–string contact of the underlying motion during one time step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BowContact {
    /// Slipping: the bow transmits `1 + ζ` and reflects `ζ` (eq. 2–4).
    Slipping,
    /// Sticking: the bow transmits `1 − γ` and reflects `−γ` (eq. 5–7).
    Sticking,
}

/// The contact states of one period, in time order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ContactPattern {
    steps: Vec<BowContact>,
}

impl ContactPattern {
    /// Any sequence of contact states; it must not be empty.
    pub fn new(steps: Vec<BowContact>) -> Result<Self, StabilityError> {
        if steps.is_empty() {
            return Err(StabilityError::InvalidParameter(
                "contact pattern: a period needs at least one step".into(),
            ));
        }
        Ok(Self { steps })
    }

    /// One slip per period: `slip_steps` slipping steps, then sticking until `period_steps`.
    pub fn single_slip(period_steps: usize, slip_steps: usize) -> Result<Self, StabilityError> {
        if period_steps == 0 || slip_steps > period_steps {
            return Err(StabilityError::InvalidParameter(format!(
                "slip steps: {slip_steps} must be from 0 to the period, {period_steps} steps"
            )));
        }
        let steps = (0..period_steps)
            .map(|step| {
                if step < slip_steps {
                    BowContact::Slipping
                } else {
                    BowContact::Sticking
                }
            })
            .collect();
        Ok(Self { steps })
    }

    /// Helmholtz motion in the space-time formulation: 2p slipping then 2q sticking (eq. 15).
    pub fn helmholtz_spacetime(p: usize, q: usize) -> Result<Self, StabilityError> {
        Self::single_slip(2 * (p + q), 2 * p)
    }

    /// Helmholtz motion in the compact formulation: p slipping then q sticking steps.
    pub fn helmholtz_compact(p: usize, q: usize) -> Result<Self, StabilityError> {
        Self::single_slip(p + q, p)
    }

    /// The contact states in time order.
    pub fn steps(&self) -> &[BowContact] {
        &self.steps
    }

    /// Number of slipping steps per period.
    pub fn slip_steps(&self) -> usize {
        self.steps
            .iter()
            .filter(|contact| **contact == BowContact::Slipping)
            .count()
    }

    /// Fraction of the period spent slipping (the denominator of eq. 17).
    pub fn slipping_fraction(&self) -> f64 {
        self.slip_steps() as f64 / self.steps.len() as f64
    }

    /// The bow reflection coefficient of every step: ζ while slipping, −γ while sticking.
    pub fn bow_reflections(&self, zeta: f64, gamma: f64) -> Vec<f64> {
        let mut reflections = vec![0.0; self.steps.len()];
        self.fill_bow_reflections(zeta, gamma, &mut reflections);
        reflections
    }

    /// [`Self::bow_reflections`] into a caller's buffer of the pattern's length.
    pub fn fill_bow_reflections(&self, zeta: f64, gamma: f64, reflections: &mut [f64]) {
        for (reflection, contact) in reflections.iter_mut().zip(&self.steps) {
            *reflection = match contact {
                BowContact::Slipping => zeta,
                BowContact::Sticking => -gamma,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn helmholtz_patterns_slip_for_the_fraction_beta() {
        let spacetime = ContactPattern::helmholtz_spacetime(2, 3).unwrap();
        assert_eq!(spacetime.steps().len(), 10);
        assert_eq!(spacetime.slip_steps(), 4);
        let compact = ContactPattern::helmholtz_compact(2, 3).unwrap();
        assert_eq!(compact.slip_steps(), 2);
        assert!((compact.slipping_fraction() - 0.4).abs() < 1e-15);
        assert_eq!(
            compact.bow_reflections(0.01, 0.9),
            vec![0.01, 0.01, -0.9, -0.9, -0.9]
        );
    }

    #[test]
    fn slip_longer_than_the_period_is_rejected() {
        assert!(ContactPattern::single_slip(5, 6).is_err());
        assert!(ContactPattern::new(Vec::new()).is_err());
    }
}
