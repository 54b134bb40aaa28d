//! Linear ramps that carry a continuous setting from its old value to a new target.
//!
//! A ramp moves in a fixed number of steps, so the time it takes does not depend on the size of
//! the jump, and it lands exactly on the target (the last step assigns it) so that a settled ramp
//! compares equal to its target and no further work is triggered.

/// A linear ramp of one value, advanced one step at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    current: f64,
    target: f64,
    increment: f64,
    steps_left: u32,
    steps_per_ramp: u32,
}

impl Ramp {
    /// A settled ramp at `value` whose future changes take `steps_per_ramp` steps (at least 1).
    pub fn new(value: f64, steps_per_ramp: u32) -> Self {
        Self {
            current: value,
            target: value,
            increment: 0.0,
            steps_left: 0,
            steps_per_ramp: steps_per_ramp.max(1),
        }
    }

    /// Starts a ramp towards `target` from wherever the value is now. A target equal to the
    /// current one changes nothing.
    pub fn set_target(&mut self, target: f64) {
        if target == self.target {
            return;
        }
        self.target = target;
        self.steps_left = self.steps_per_ramp;
        self.increment = (target - self.current) / f64::from(self.steps_per_ramp);
    }

    /// Jumps to `value` at once (no ramp), e.g. on reset.
    pub fn jump_to(&mut self, value: f64) {
        self.current = value;
        self.target = value;
        self.steps_left = 0;
        self.increment = 0.0;
    }

    /// Advances one step and returns the new value.
    pub fn step(&mut self) -> f64 {
        if self.steps_left > 0 {
            self.steps_left -= 1;
            self.current = if self.steps_left == 0 {
                self.target
            } else {
                self.current + self.increment
            };
        }
        self.current
    }

    pub fn value(&self) -> f64 {
        self.current
    }

    pub fn target(&self) -> f64 {
        self.target
    }

    /// True while the value still moves.
    pub fn is_ramping(&self) -> bool {
        self.steps_left > 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_reaches_the_target_exactly_in_the_given_steps() {
        let mut ramp = Ramp::new(0.0, 4);
        ramp.set_target(1.0);
        let values: Vec<f64> = (0..5).map(|_| ramp.step()).collect();
        assert_eq!(values, vec![0.25, 0.5, 0.75, 1.0, 1.0]);
        assert!(!ramp.is_ramping());
    }

    #[test]
    fn retargeting_mid_ramp_starts_from_the_current_value() {
        let mut ramp = Ramp::new(0.0, 2);
        ramp.set_target(4.0);
        assert_eq!(ramp.step(), 2.0);
        ramp.set_target(0.0);
        assert_eq!(ramp.step(), 1.0);
        assert_eq!(ramp.step(), 0.0);
    }

    #[test]
    fn jump_settles_immediately() {
        let mut ramp = Ramp::new(3.0, 100);
        ramp.set_target(5.0);
        ramp.jump_to(-1.0);
        assert_eq!(ramp.step(), -1.0);
        assert!(!ramp.is_ramping());
    }
}
