//! Friction laws of the bow–string contact (`shared/notes/bowed-model.md`, "Friction law";
//! Woodhouse 1993, Fig. 2 and eq. 1).
//!
//! Sign convention used throughout the bowed voice: `relative_velocity_m_s` is u = v − v_b, the
//! string velocity at the bow minus the bow velocity, and the friction force is the force the bow
//! exerts on the string. While sliding it opposes the relative motion:
//!
//! ```text
//!     f(u) = −sign(u) · F_b · μ(|u|)
//! ```
//!
//! The note writes the same law as f = F_b μ(v − v_b) with an odd μ; here μ is the (positive)
//! coefficient magnitude as a function of slip speed w = |u|, and the sign is explicit.
//!
//! A law returns its value and its slope together (house style 4). It also answers the one
//! question the bow-point solve asks of it: where does the straight line of the string,
//! f = 2Z₀(v − v_h), meet the sliding branch, farthest from the bow velocity?

/// A sliding-friction law μ(w), w = slip speed |v − v_b| in m/s, for a falling friction curve.
pub trait FrictionLaw {
    /// Limit of sticking friction μ_s: the bow holds the string while |f| ≤ μ_s F_b.
    fn static_coefficient(&self) -> f64;

    /// Asymptotic sliding coefficient μ_d (μ at high slip speed), used by Schelleng's bounds.
    fn dynamic_coefficient(&self) -> f64;

    /// Sliding coefficient μ(w) and its derivative dμ/dw (1/(m/s)) at slip speed w ≥ 0 m/s.
    fn sliding_coefficient(&self, slip_speed_m_s: f64) -> (f64, f64);

    /// Friction force on the string (N) while sliding at relative velocity u = v − v_b, and its
    /// slope df/du (N s/m). This is the slope k F_b of Woodhouse's eq. (1) seen from the string.
    fn sliding_force(&self, relative_velocity_m_s: f64, bow_force_n: f64) -> (f64, f64) {
        let (mu, dmu_dw) = self.sliding_coefficient(relative_velocity_m_s.abs());
        let direction = if relative_velocity_m_s < 0.0 {
            -1.0
        } else {
            1.0
        };
        // d/du[−sign(u) F μ(|u|)] = −F μ'(|u|) since d|u|/du = sign(u) and sign(u)² = 1.
        (-direction * bow_force_n * mu, -bow_force_n * dmu_dw)
    }

    /// The largest slip speed w > 0 where the string's line meets the sliding branch on the side
    /// of the free relative velocity, or `None` when the line misses that branch.
    ///
    /// With x = |v_h − v_b| (the slip speed the string would have without friction) and
    /// a = 2Z₀ (N s/m), the intersection solves g(w) = a (w − x) + F_b μ(w) = 0. Every root lies
    /// in (0, x] because μ ≥ 0. The outermost root is the stable sliding intersection; an inner
    /// one (when two exist) is the unstable middle intersection that hysteresis never selects.
    ///
    /// The default is [`outer_slip_speed_by_newton`]; laws with a closed form override it.
    fn outer_slip_speed(
        &self,
        line_slope_n_s_m: f64,
        free_slip_speed_m_s: f64,
        bow_force_n: f64,
    ) -> Option<f64> {
        outer_slip_speed_by_newton(self, line_slope_n_s_m, free_slip_speed_m_s, bow_force_n)
    }

    /// Whether [`Self::outer_slip_speed`] is `Some`, for a sticking contact that stays stuck and
    /// needs only the count of intersections, not the slip speed. Laws with a cheaper test than
    /// solving override it.
    fn has_outer_slip(
        &self,
        line_slope_n_s_m: f64,
        free_slip_speed_m_s: f64,
        bow_force_n: f64,
    ) -> bool {
        self.outer_slip_speed(line_slope_n_s_m, free_slip_speed_m_s, bow_force_n)
            .is_some()
    }
}

/// Iteration cap of [`outer_slip_speed_by_newton`].
pub const SLIP_NEWTON_MAX_ITERATIONS: usize = 60;

/// Outermost root of g(w) = a (w − x) + F_b μ(w) by Newton's method started at w = x.
///
/// Residual g(w); Jacobian g'(w) = a + F_b μ'(w). Started at w = x, where g(x) = F_b μ(x) ≥ 0,
/// Newton on a convex g (a falling, convex μ: hyperbolic, exponential) decreases monotonically
/// onto the largest root and never crosses it. Stops when the step is below 1e-13 · max(x, 1e-9)
/// m/s. Returns `None` when g' ≤ 0 at an iterate (the minimum of g lies above zero: no sliding
/// intersection) or when an iterate leaves (0, x]. If the cap of
/// [`SLIP_NEWTON_MAX_ITERATIONS`] is hit, the last iterate is returned: it lies on the correct
/// side of the root, so the force it gives is finite and close.
pub fn outer_slip_speed_by_newton<F: FrictionLaw + ?Sized>(
    law: &F,
    line_slope_n_s_m: f64,
    free_slip_speed_m_s: f64,
    bow_force_n: f64,
) -> Option<f64> {
    let a = line_slope_n_s_m;
    let x = free_slip_speed_m_s;
    if x.is_nan() || x <= 0.0 {
        return None;
    }
    let tolerance = 1e-13 * x.max(1e-9);
    let mut w = x;
    for _ in 0..SLIP_NEWTON_MAX_ITERATIONS {
        let (mu, dmu_dw) = law.sliding_coefficient(w);
        let residual = a * (w - x) + bow_force_n * mu;
        let jacobian = a + bow_force_n * dmu_dw;
        if residual == 0.0 {
            return Some(w);
        }
        if jacobian.is_nan() || jacobian <= 0.0 {
            return None;
        }
        let step = residual / jacobian;
        w -= step;
        if w.is_nan() || w <= 0.0 {
            return None;
        }
        if step.abs() <= tolerance {
            return Some(w);
        }
    }
    Some(w)
}

/// The hyperbolic falling friction curve of the note:
/// μ(w) = μ_d + (μ_s − μ_d) v₀ / (v₀ + w).
///
/// Its sliding intersection with the string's line is a quadratic, solved in closed form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HyperbolicFriction {
    /// μ_s, limit of sticking friction (dimensionless, > μ_d).
    pub static_coefficient: f64,
    /// μ_d, the sliding coefficient at high slip speed (dimensionless, ≥ 0).
    pub dynamic_coefficient: f64,
    /// v₀ > 0, slip speed (m/s) over which μ falls from μ_s towards μ_d.
    pub decay_velocity_m_s: f64,
}

impl Default for HyperbolicFriction {
    /// Rosin on gut/steel as in the note: μ_s = 0.8, μ_d = 0.3, v₀ = 0.1 m/s.
    fn default() -> Self {
        Self {
            static_coefficient: 0.8,
            dynamic_coefficient: 0.3,
            decay_velocity_m_s: 0.1,
        }
    }
}

impl FrictionLaw for HyperbolicFriction {
    fn static_coefficient(&self) -> f64 {
        self.static_coefficient
    }

    fn dynamic_coefficient(&self) -> f64 {
        self.dynamic_coefficient
    }

    fn sliding_coefficient(&self, slip_speed_m_s: f64) -> (f64, f64) {
        let v0 = self.decay_velocity_m_s;
        let fall = self.static_coefficient - self.dynamic_coefficient;
        let denominator = v0 + slip_speed_m_s;
        (
            self.dynamic_coefficient + fall * v0 / denominator,
            -fall * v0 / (denominator * denominator),
        )
    }

    /// Multiplying a (w − x) + F_b [μ_d + (μ_s − μ_d) v₀/(v₀ + w)] = 0 by (v₀ + w):
    ///
    /// ```text
    ///     a w² + [a (v₀ − x) + F_b μ_d] w + v₀ (F_b μ_s − a x) = 0
    /// ```
    ///
    /// The larger root is the outer intersection; it is taken in the cancellation-free form.
    fn outer_slip_speed(
        &self,
        line_slope_n_s_m: f64,
        free_slip_speed_m_s: f64,
        bow_force_n: f64,
    ) -> Option<f64> {
        let a = line_slope_n_s_m;
        let x = free_slip_speed_m_s;
        if x.is_nan() || x <= 0.0 {
            return None;
        }
        let v0 = self.decay_velocity_m_s;
        let b = a * (v0 - x) + bow_force_n * self.dynamic_coefficient;
        let c = v0 * (bow_force_n * self.static_coefficient - a * x);
        let discriminant = b * b - 4.0 * a * c;
        if discriminant < 0.0 {
            return None;
        }
        let root = discriminant.sqrt();
        let outer = if b < 0.0 {
            (-b + root) / (2.0 * a)
        } else {
            // −b + √D would cancel; the product of the roots is c/a.
            let inner_denominator = -b - root;
            if inner_denominator == 0.0 {
                return None;
            }
            2.0 * c / inner_denominator
        };
        if outer > 0.0 {
            Some(outer)
        } else {
            None
        }
    }

    /// The quadratic's sign pattern, without its square root or division: with a > 0 and a
    /// real root, the larger root is positive when b < 0 (−b + √D > 0) or else when c < 0 (the
    /// roots then have opposite signs). The sign argument needs the quotients in
    /// [`Self::outer_slip_speed`] not to underflow, so a, |b| and |c| must lie in [1e−150, 1e150]
    /// (they are of order 0.01 to 100 for real strings); outside that, it solves.
    #[inline]
    fn has_outer_slip(
        &self,
        line_slope_n_s_m: f64,
        free_slip_speed_m_s: f64,
        bow_force_n: f64,
    ) -> bool {
        let a = line_slope_n_s_m;
        let x = free_slip_speed_m_s;
        if x.is_nan() || x <= 0.0 {
            return false;
        }
        let v0 = self.decay_velocity_m_s;
        let b = a * (v0 - x) + bow_force_n * self.dynamic_coefficient;
        let c = v0 * (bow_force_n * self.static_coefficient - a * x);
        // `&` and `|`, not `&&` and `||`: flags combined without a branch each.
        let moderate = |value: f64| {
            let magnitude = value.abs();
            (1e-150..=1e150).contains(&magnitude)
        };
        if !((a > 0.0) & moderate(a) & moderate(b) & moderate(c)) {
            return self.outer_slip_speed(a, x, bow_force_n).is_some();
        }
        let discriminant = b * b - 4.0 * a * c;
        (discriminant >= 0.0) & ((b < 0.0) | (c < 0.0))
    }
}

/// An exponential falling curve, μ(w) = μ_d + (μ_s − μ_d) exp(−w / v₀): a second law to show
/// the trait is swappable. It has no closed-form intersection and uses the default Newton.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExponentialFriction {
    /// μ_s, limit of sticking friction (dimensionless).
    pub static_coefficient: f64,
    /// μ_d, the asymptotic sliding coefficient (dimensionless).
    pub dynamic_coefficient: f64,
    /// v₀ > 0, decay velocity (m/s).
    pub decay_velocity_m_s: f64,
}

impl Default for ExponentialFriction {
    fn default() -> Self {
        Self {
            static_coefficient: 0.8,
            dynamic_coefficient: 0.3,
            decay_velocity_m_s: 0.1,
        }
    }
}

impl FrictionLaw for ExponentialFriction {
    fn static_coefficient(&self) -> f64 {
        self.static_coefficient
    }

    fn dynamic_coefficient(&self) -> f64 {
        self.dynamic_coefficient
    }

    fn sliding_coefficient(&self, slip_speed_m_s: f64) -> (f64, f64) {
        let fall = self.static_coefficient - self.dynamic_coefficient;
        let decay = (-slip_speed_m_s / self.decay_velocity_m_s).exp();
        (
            self.dynamic_coefficient + fall * decay,
            -fall * decay / self.decay_velocity_m_s,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hyperbolic_coefficient_by_hand() {
        let law = HyperbolicFriction::default();
        // w = 0: μ = μ_s; slope −(μ_s − μ_d)/v₀ = −5 per m/s.
        let (mu, slope) = law.sliding_coefficient(0.0);
        assert!((mu - 0.8).abs() < 1e-15);
        assert!((slope + 5.0).abs() < 1e-13);
        // w = v₀: μ = 0.3 + 0.5/2 = 0.55; slope = −0.5·0.1/0.04 = −1.25.
        let (mu, slope) = law.sliding_coefficient(0.1);
        assert!((mu - 0.55).abs() < 1e-15);
        assert!((slope + 1.25).abs() < 1e-13);
    }

    #[test]
    fn sliding_force_opposes_relative_motion_and_slope_is_its_derivative() {
        let law = HyperbolicFriction::default();
        let bow_force_n = 2.0;
        for &u in &[-0.7, -0.05, 0.05, 0.3] {
            let (f, df) = law.sliding_force(u, bow_force_n);
            assert!(f * u < 0.0, "friction must oppose slip, u = {u}, f = {f}");
            let h = 1e-6;
            let numeric = (law.sliding_force(u + h, bow_force_n).0
                - law.sliding_force(u - h, bow_force_n).0)
                / (2.0 * h);
            assert!((numeric - df).abs() < 1e-6 * df.abs().max(1.0));
            // A falling curve gives df/du > 0: the "negative resistance" of Woodhouse eq. (2).
            assert!(df > 0.0);
        }
    }

    #[test]
    fn hyperbolic_quadratic_roots_by_hand() {
        // a = 0.4, F_b = 1, x = 1.5: b = 0.4·(0.1 − 1.5) + 0.3 = −0.26, c = 0.1·(0.8 − 0.6) = 0.02,
        // D = 0.0676 − 0.032 = 0.0356: roots (0.26 ± √0.0356)/0.8.
        let law = HyperbolicFriction::default();
        let outer = law.outer_slip_speed(0.4, 1.5, 1.0).unwrap();
        let expected = (0.26 + 0.0356_f64.sqrt()) / 0.8;
        assert!((outer - expected).abs() < 1e-14, "{outer} vs {expected}");
        // The root lies on the curve: a (w − x) + F μ(w) = 0.
        let (mu, _) = law.sliding_coefficient(outer);
        assert!((0.4 * (outer - 1.5) + mu).abs() < 1e-14);
        // No bow force: the string slides freely at its own velocity, w = x.
        let free = law.outer_slip_speed(0.4, 0.7, 0.0).unwrap();
        assert!((free - 0.7).abs() < 1e-15);
        // A line that passes above the curve: no sliding intersection (b > 0, c > 0).
        assert_eq!(law.outer_slip_speed(0.4, 0.5, 1.0), None);
    }

    #[test]
    fn newton_reference_agrees_with_closed_form() {
        let law = HyperbolicFriction::default();
        for &a in &[0.05, 0.35, 1.5, 20.0] {
            for &force in &[0.0, 0.01, 0.3, 2.0, 40.0] {
                for &x in &[1e-4, 0.02, 0.3, 1.2, 5.0] {
                    let closed = law.outer_slip_speed(a, x, force);
                    let newton = outer_slip_speed_by_newton(&law, a, x, force);
                    match (closed, newton) {
                        (Some(c), Some(n)) => {
                            assert!(
                                (c - n).abs() <= 1e-9 * x,
                                "a={a} F={force} x={x}: {c} vs {n}"
                            )
                        }
                        (None, None) => {}
                        other => panic!("a={a} F={force} x={x}: {other:?}"),
                    }
                }
            }
        }
    }

    #[test]
    fn existence_test_agrees_with_the_solve() {
        let law = HyperbolicFriction::default();
        let values = [
            0.0, 1e-200, 1e-12, 1e-4, 0.02, 0.1, 0.3, 0.5, 1.2, 2.0, 5.0, 40.0, 1e12, 1e200,
        ];
        let mut seen = [0usize; 2];
        for &a in &values[1..] {
            for &force in &values {
                for &x in &values {
                    let solved = law.outer_slip_speed(a, x, force).is_some();
                    assert_eq!(
                        law.has_outer_slip(a, x, force),
                        solved,
                        "a={a} F={force} x={x}"
                    );
                    seen[solved as usize] += 1;
                }
            }
        }
        // Across the tangency, where the discriminant crosses zero (x ≈ 1.357 for a = 0.4 and
        // F_b = 1, the capture point of the hysteresis test in bow_point.rs).
        for i in 0..20_000 {
            let x = 1.0 + 1e-4 * i as f64;
            let solved = law.outer_slip_speed(0.4, x, 1.0).is_some();
            assert_eq!(law.has_outer_slip(0.4, x, 1.0), solved, "x={x}");
            seen[solved as usize] += 1;
        }
        assert!(seen[0] > 100 && seen[1] > 100, "{seen:?}");
    }

    #[test]
    fn exponential_law_uses_newton_and_lands_on_the_curve() {
        let law = ExponentialFriction::default();
        let w = law.outer_slip_speed(0.4, 3.0, 1.0).unwrap();
        let (mu, _) = law.sliding_coefficient(w);
        assert!((0.4 * (w - 3.0) + mu).abs() < 1e-12);
        assert!(w > 0.0 && w <= 3.0);
    }
}
