//! The bow-point solve of the McIntyre–Schumacher–Woodhouse model, once per sample
//! (`shared/notes/bowed-model.md`, "Rounded-corner model"; Woodhouse 1993, Fig. 2).
//!
//! The string seen from the bow is a dashpot of impedance 2Z₀ driven by the incoming waves:
//!
//! ```text
//!     v = v_h + f / (2Z₀)        ⇔        f = 2Z₀ (v − v_h)        (the string's line)
//! ```
//!
//! and the friction law is a vertical segment at v = v_b (sticking, |f| ≤ μ_s F_b) plus two
//! falling sliding branches. The new (v, f) is an intersection of line and curve. With u_h =
//! v_h − v_b the free relative velocity:
//!
//! - sticking is possible while |2Z₀ u_h| ≤ μ_s F_b;
//! - sliding intersections lie on the side sign(u_h), at the slip speeds w solving the law's
//!   [`FrictionLaw::outer_slip_speed`] equation (a quadratic for the hyperbolic law).
//!
//! Up to three intersections exist (stick, and an outer and an inner sliding one). McIntyre,
//! Schumacher and Woodhouse's hysteresis rule picks among them: stay on the branch the contact
//! was on (sticking, or the outer sliding intersection) until that intersection disappears, then
//! jump to the one that remains. The inner sliding intersection is unstable and never chosen.

use super::friction::FrictionLaw;

/// Which branch of the friction curve the bow–string contact is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactState {
    /// String moves with the bow, v = v_b.
    Sticking,
    /// String slides under the bow on the outer sliding intersection.
    Slipping,
}

/// One sample's solution at the bow point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BowPointSolution {
    /// String velocity at the bow point, m/s.
    pub velocity_m_s: f64,
    /// Friction force of the bow on the string, N.
    pub friction_force_n: f64,
    /// Branch chosen this sample.
    pub state: ContactState,
    /// Number of intersections of line and friction curve this sample (1 to 3): 3 is where
    /// hysteresis decides.
    pub intersections: u8,
}

/// The bow-point solver with its branch memory (the hysteresis state).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BowPoint {
    state: ContactState,
}

impl Default for BowPoint {
    fn default() -> Self {
        Self::new()
    }
}

impl BowPoint {
    /// A contact that starts sticking: a bow set down on a string at rest holds it.
    pub fn new() -> Self {
        Self {
            state: ContactState::Sticking,
        }
    }

    /// Forget the branch memory (back to sticking).
    pub fn reset(&mut self) {
        self.state = ContactState::Sticking;
    }

    /// The branch the last solve ended on.
    pub fn state(&self) -> ContactState {
        self.state
    }

    /// Force the branch memory, for tests and for a voice that restores a saved state.
    pub fn set_state(&mut self, state: ContactState) {
        self.state = state;
    }

    /// Intersect the string's line f = 2Z₀ (v − v_h) with the friction curve of `law` at bow
    /// normal force `bow_force_n` (N, ≥ 0) and bow velocity `bow_velocity_m_s`, with hysteresis.
    ///
    /// `string_admittance_line_n_s_m` is 2Z₀ (N s/m). Never panics; every branch returns finite
    /// values for finite inputs.
    #[inline(always)]
    pub fn solve<F: FrictionLaw + ?Sized>(
        &mut self,
        law: &F,
        line_slope_n_s_m: f64,
        free_velocity_m_s: f64,
        bow_velocity_m_s: f64,
        bow_force_n: f64,
    ) -> BowPointSolution {
        let a = line_slope_n_s_m;
        if bow_force_n.is_nan() || bow_force_n <= 0.0 {
            // Bow lifted: no contact, no force, the string moves freely. The branch memory is
            // kept for when the bow comes down again.
            return BowPointSolution {
                velocity_m_s: free_velocity_m_s,
                friction_force_n: 0.0,
                state: ContactState::Slipping,
                intersections: 1,
            };
        }
        let free_relative_m_s = free_velocity_m_s - bow_velocity_m_s;
        let sticking_force_n = -a * free_relative_m_s;
        let sticking_limit_n = law.static_coefficient() * bow_force_n;
        let can_stick = sticking_force_n.abs() <= sticking_limit_n;

        let free_slip_speed = free_relative_m_s.abs();
        let slip_direction = if free_relative_m_s < 0.0 { -1.0 } else { 1.0 };

        // An inner (unstable) intersection exists exactly when stick and an outer sliding
        // intersection coexist: the line crosses the falling branch twice on its way from the
        // outer root back to the vertical segment.
        if self.state == ContactState::Sticking && can_stick {
            // Stuck and able to stay stuck: the branch memory keeps it there whatever the
            // sliding branch does (most of the period in Helmholtz motion). Only whether an
            // outer intersection exists is needed, for the count, not where it is, so the
            // solve's square root and division are skipped.
            let has_outer_slip = law.has_outer_slip(a, free_slip_speed, bow_force_n);
            return BowPointSolution {
                velocity_m_s: bow_velocity_m_s,
                friction_force_n: sticking_force_n,
                state: ContactState::Sticking,
                intersections: if has_outer_slip { 3 } else { 1 },
            };
        }
        let outer_slip = law.outer_slip_speed(a, free_slip_speed, bow_force_n);
        let intersections = match (can_stick, outer_slip.is_some()) {
            (true, true) => 3,
            _ => 1,
        };

        let stick = BowPointSolution {
            velocity_m_s: bow_velocity_m_s,
            friction_force_n: sticking_force_n,
            state: ContactState::Sticking,
            intersections,
        };
        let slip = |slip_speed: f64| {
            let relative = slip_direction * slip_speed;
            BowPointSolution {
                velocity_m_s: bow_velocity_m_s + relative,
                friction_force_n: a * (relative - free_relative_m_s),
                state: ContactState::Slipping,
                intersections,
            }
        };

        let solution = match (self.state, can_stick, outer_slip) {
            (ContactState::Sticking, true, _) => stick,
            (ContactState::Slipping, _, Some(w)) => slip(w),
            (_, true, None) => stick,
            (ContactState::Sticking, false, Some(w)) => slip(w),
            (_, false, None) => {
                // Geometrically impossible for a falling law with μ ≥ 0 (the line always meets
                // the curve), but a user law could be pathological: hold the force at the
                // sticking limit so the result stays finite and passive. (max/min, not clamp:
                // clamp panics when a pathological law makes the limit NaN or negative.)
                let force = sticking_force_n
                    .min(sticking_limit_n)
                    .max(-sticking_limit_n);
                BowPointSolution {
                    velocity_m_s: free_velocity_m_s + force / a,
                    friction_force_n: force,
                    state: ContactState::Slipping,
                    intersections,
                }
            }
        };
        self.state = solution.state;
        solution
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bowed::friction::HyperbolicFriction;

    const LINE: f64 = 0.4; // 2Z₀ in N s/m
    const BOW_FORCE: f64 = 1.0;
    const BOW_VELOCITY: f64 = 0.2;

    #[test]
    fn sticking_holds_the_string_at_bow_velocity() {
        let law = HyperbolicFriction::default();
        let mut bow = BowPoint::new();
        // u_h = −0.5: f = 0.4·0.5 = 0.2 N ≤ 0.8 N.
        let s = bow.solve(&law, LINE, BOW_VELOCITY - 0.5, BOW_VELOCITY, BOW_FORCE);
        assert_eq!(s.state, ContactState::Sticking);
        assert_eq!(s.velocity_m_s, BOW_VELOCITY);
        assert!((s.friction_force_n - 0.2).abs() < 1e-15);
    }

    #[test]
    fn breakaway_beyond_the_sticking_limit() {
        let law = HyperbolicFriction::default();
        let mut bow = BowPoint::new();
        // u_h = −2.5: sticking would need 1.0 N > 0.8 N, so the string slips backwards.
        let s = bow.solve(&law, LINE, BOW_VELOCITY - 2.5, BOW_VELOCITY, BOW_FORCE);
        assert_eq!(s.state, ContactState::Slipping);
        let u = s.velocity_m_s - BOW_VELOCITY;
        assert!(u < 0.0);
        // On the line and on the curve.
        let (f_curve, _) = law.sliding_force(u, BOW_FORCE);
        assert!((s.friction_force_n - f_curve).abs() < 1e-12);
        assert!(
            (s.friction_force_n - LINE * (s.velocity_m_s - (BOW_VELOCITY - 2.5))).abs() < 1e-12
        );
    }

    #[test]
    fn three_intersections_keep_the_branch_the_contact_was_on() {
        // x = 1.5 (hand-worked in friction.rs): sticking needs 0.6 N ≤ 0.8 N and the outer
        // sliding root is (0.26 + √0.0356)/0.8 = 0.5609 m/s: three intersections.
        let law = HyperbolicFriction::default();
        let free = BOW_VELOCITY - 1.5;
        let mut from_stick = BowPoint::new();
        let a = from_stick.solve(&law, LINE, free, BOW_VELOCITY, BOW_FORCE);
        assert_eq!(a.intersections, 3);
        assert_eq!(a.state, ContactState::Sticking);
        assert_eq!(a.velocity_m_s, BOW_VELOCITY);

        let mut from_slip = BowPoint::new();
        from_slip.set_state(ContactState::Slipping);
        let b = from_slip.solve(&law, LINE, free, BOW_VELOCITY, BOW_FORCE);
        assert_eq!(b.intersections, 3);
        assert_eq!(b.state, ContactState::Slipping);
        let expected_slip = (0.26 + 0.0356_f64.sqrt()) / 0.8;
        assert!((b.velocity_m_s - (BOW_VELOCITY - expected_slip)).abs() < 1e-14);
    }

    #[test]
    fn hysteresis_loop_of_a_slow_sweep() {
        // Sweep the free slip speed x up to 3 m/s and back. Going up, the contact sticks until
        // 2Z₀x exceeds μ_s F_b, at x = 2.0 exactly. Coming down, it slides until the sliding
        // quadratic's discriminant vanishes (solved below): between the two, three intersections
        // exist and the branch memory alone decides.
        let law = HyperbolicFriction::default();
        let mut bow = BowPoint::new();
        let steps = 30_000;
        let top = 3.0;
        let mut release_at = None;
        let mut capture_at = None;
        let mut previous = ContactState::Sticking;
        for i in 0..=2 * steps {
            let x = if i <= steps {
                top * i as f64 / steps as f64
            } else {
                top * (2 * steps - i) as f64 / steps as f64
            };
            let s = bow.solve(&law, LINE, BOW_VELOCITY - x, BOW_VELOCITY, BOW_FORCE);
            if previous == ContactState::Sticking && s.state == ContactState::Slipping {
                release_at.get_or_insert(x);
            }
            if previous == ContactState::Slipping && s.state == ContactState::Sticking {
                capture_at.get_or_insert(x);
            }
            previous = s.state;
        }
        let release = release_at.unwrap();
        let capture = capture_at.unwrap();
        let dx = top / steps as f64;
        assert!((release - 2.0).abs() <= 1.5 * dx, "release at {release}");
        // Discriminant zero: 0.16x² − 0.272x + 0.1156 − 0.128 + 0.064x = 0
        // ⇔ 0.16x² − 0.208x − 0.0124 = 0, larger root.
        let capture_expected = (0.208 + (0.208f64 * 0.208 + 4.0 * 0.16 * 0.0124).sqrt()) / 0.32;
        assert!(
            (capture - capture_expected).abs() <= 1.5 * dx,
            "capture at {capture} vs {capture_expected}"
        );
        // The loop is open: capture well below release (three intersections in between).
        assert!(capture < release - 0.5);
    }
}
