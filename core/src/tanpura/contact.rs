//! The Hunt–Crossley contact law, discretised in energy-stable mid-point form.
//!
//! Source: seed 000 (van Walstijn & Chatziioannou, ISMA 2014), eq. 1–4 and 18, restated in
//! `shared/notes/tanpura-model.md`. With exponent α = 1 and gap `u = y_barrier − y`, the force
//! density on the string is `F = k⌊u⌋(1 − r ∂y/∂t)`, derived from the potential
//! `V = k/2 ⌊u⌋²` as `F = −∂V/∂y + r ∂V/∂t` (eq. 3). The mid-point discretisation (eq. 4) is
//!
//! ```text
//! F^{n+½} = −[V(y^{n+1}) − V(y^n)] / (y^{n+1} − y^n) + r [V(y^{n+1}) − V(y^n)] / Δt.
//! ```
//!
//! In the scheme's scaled units (force density × Δt²/2ρA), with `a = u^n` the gap before the
//! step and `s` the step `ỹ^{n+1} − ỹ^n`, and `Φ(s) = ⌊a − s⌋² − ⌊a⌋²`,
//!
//! ```text
//! f̃(s) = −ξ Φ(s)/s + ψ Φ(s),    ξ = kΔt²/(4ρA),   ψ = k r Δt/(4ρA).
//! ```
//!
//! (The seed prints ξ and ψ with 2ρA; the factor ½ of `V` makes it 4ρA, as the note derives.)
//! The quotient `Φ/s` is evaluated in closed form for each contact case, so no division by a
//! vanishing `s` ever happens: staying in contact gives `s − 2a`, staying out gives 0, and the two
//! crossing cases divide by an `s` at least as large as the gap it crosses.
//!
//! Energy: `f̃ · s` splits into `−ξΦ` (the exact change of the scaled potential, so the lossless
//! scheme conserves energy) and `ψΦs ≤ 0` (dissipation, since Φ and s have opposite signs).

/// One barrier's contact law: `f̃(s) = −ξ Φ(s)/s + ψ Φ(s)`. In the FD scheme's scaled units
/// ([`HuntCrossley::scaled`]) or in newtons for a modal contact point
/// ([`HuntCrossley::for_point`]); the force is linear in ξ and ψ, so one evaluation serves both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HuntCrossley {
    /// Scaled: ξ = kΔt²/(4ρA), dimensionless per unit gap (k in N/m², Δt in s, ρA in kg/m).
    /// Per point: ξ = w k/2, N/m.
    pub xi: f64,
    /// Scaled: ψ = k r Δt/(4ρA), per metre (r in s/m). Per point: ψ = w k r/(2Δt), N/m².
    pub psi: f64,
}

/// The mid-point force at one barrier point and its derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactForce {
    /// f̃^{n+½}, scaled force density (metres: force density × Δt²/2ρA).
    pub force: f64,
    /// c = −∂f̃/∂s ≥ 0, the point's contribution to the Newton Jacobian (eq. 25).
    pub stiffness: f64,
    /// Φ = ⌊a − s⌋² − ⌊a⌋² in m²: the potential changes by ΔV = kΦ/2 over the step.
    pub squared_gap_change: f64,
}

impl HuntCrossley {
    /// Scales a physical law (stiffness per length `k` in N/m², damping `r` in s/m) to a scheme
    /// with time step `time_step_s` and linear density `linear_density_kg_m`.
    pub fn scaled(
        stiffness_n_m2: f64,
        damping_s_m: f64,
        time_step_s: f64,
        linear_density_kg_m: f64,
    ) -> Self {
        let xi = stiffness_n_m2 * time_step_s * time_step_s / (4.0 * linear_density_kg_m);
        let psi = stiffness_n_m2 * damping_s_m * time_step_s / (4.0 * linear_density_kg_m);
        Self { xi, psi }
    }

    /// The same law for one contact point of a modal tier that stands for a length `length_m` of
    /// its barrier, in newtons: `ξ = w k/2`, `ψ = w k r/(2Δt)`, so that the force is the point's
    /// whole mid-point force `F = w f` (eq. 4), and its derivative `−∂F/∂s` in N/m.
    pub fn for_point(
        stiffness_n_m2: f64,
        damping_s_m: f64,
        length_m: f64,
        time_step_s: f64,
    ) -> Self {
        let spring = stiffness_n_m2 * length_m;
        Self {
            xi: 0.5 * spring,
            psi: 0.5 * spring * damping_s_m / time_step_s,
        }
    }

    /// The mid-point force for gap `a` (before the step, metres, positive = penetrating) and
    /// step `s` of the string at that point (metres, positive = upwards, away from the barrier).
    #[inline]
    pub fn midpoint_force(&self, gap: f64, step: f64) -> ContactForce {
        let gap_after = gap - step;
        if gap > 0.0 && gap_after > 0.0 {
            // Stays in contact: Φ/s = s − 2a, d(Φ/s)/ds = 1, dΦ/ds = −2(a − s).
            let squared_gap_change = gap_after * gap_after - gap * gap;
            ContactForce {
                force: -self.xi * (step - 2.0 * gap) + self.psi * squared_gap_change,
                stiffness: self.xi + 2.0 * self.psi * gap_after,
                squared_gap_change,
            }
        } else if gap > 0.0 {
            // Leaves contact (s ≥ a > 0): Φ = −a², Φ/s = −a²/s, d(Φ/s)/ds = a²/s², dΦ/ds = 0.
            let squared_gap_change = -gap * gap;
            let quotient = squared_gap_change / step;
            ContactForce {
                force: -self.xi * quotient + self.psi * squared_gap_change,
                stiffness: self.xi * (gap / step) * (gap / step),
                squared_gap_change,
            }
        } else if gap_after > 0.0 {
            // Enters contact (s < a ≤ 0): Φ = (a − s)², Φ/s = (a − s)²/s,
            // d(Φ/s)/ds = −(a − s)(a + s)/s², dΦ/ds = −2(a − s).
            let squared_gap_change = gap_after * gap_after;
            let quotient = squared_gap_change / step;
            let quotient_slope = -gap_after * (gap + step) / (step * step);
            ContactForce {
                force: -self.xi * quotient + self.psi * squared_gap_change,
                stiffness: self.xi * quotient_slope + 2.0 * self.psi * gap_after,
                squared_gap_change,
            }
        } else {
            ContactForce {
                force: 0.0,
                stiffness: 0.0,
                squared_gap_change: 0.0,
            }
        }
    }

    /// The mid-point force with the damping taken linearly implicit, as the modal tiers use it:
    /// the conservative part is the seed's discrete gradient `−ξ Φ(s)/s` (eq. 4), the damping
    /// `−2ψ ⌊a⌋ s` uses the penetration before the step instead of the mid-point one (the seed's
    /// `ψ Φ(s) = −ψ (2a − s) s` while in contact; they differ by `ψ s²`, second order in Δt, in a
    /// term that is itself a fraction `r v` ≈ 0.5 % of the force). Its work `−2ψ⌊a⌋s²` is never
    /// positive, so the scheme stays dissipative; and while the point stays in contact (or out)
    /// the force is *linear* in s, so a step in which no point changes its contact case is solved
    /// exactly by one Newton update. `squared_gap_change` is Φ as before, for the energy.
    #[inline(always)]
    pub fn midpoint_force_linear_damping(&self, gap: f64, step: f64) -> ContactForce {
        let gap_after = gap - step;
        let damping = 2.0 * self.psi * gap.max(0.0);
        if gap > 0.0 && gap_after > 0.0 {
            ContactForce {
                force: self.xi * (2.0 * gap - step) - damping * step,
                stiffness: self.xi + damping,
                squared_gap_change: gap_after * gap_after - gap * gap,
            }
        } else if gap > 0.0 {
            // Leaves contact (s ≥ a > 0): Φ/s = −a²/s, d(Φ/s)/ds = a²/s².
            let squared_gap_change = -gap * gap;
            ContactForce {
                force: -self.xi * squared_gap_change / step - damping * step,
                stiffness: self.xi * (gap / step) * (gap / step) + damping,
                squared_gap_change,
            }
        } else if gap_after > 0.0 {
            // Enters contact (s < a ≤ 0): Φ/s = (a − s)²/s, no damping (a ≤ 0).
            let squared_gap_change = gap_after * gap_after;
            ContactForce {
                force: -self.xi * squared_gap_change / step,
                stiffness: -self.xi * gap_after * (gap + step) / (step * step),
                squared_gap_change,
            }
        } else {
            ContactForce {
                force: 0.0,
                stiffness: 0.0,
                squared_gap_change: 0.0,
            }
        }
    }

    /// The energy the linearly implicit damping dissipates over a step `s` from gap `a`, in the
    /// law's units times metres: `2ψ ⌊a⌋ s² ≥ 0`.
    #[inline(always)]
    pub fn linear_damping_loss(&self, gap: f64, step: f64) -> f64 {
        2.0 * self.psi * gap.max(0.0) * step * step
    }
}

/// The contact potential density `V = k/2 ⌊gap⌋²` in J/m (eq. 2 with α = 1, and eq. 9).
#[inline]
pub fn potential_density(stiffness_n_m2: f64, gap_m: f64) -> f64 {
    let penetration = gap_m.max(0.0);
    0.5 * stiffness_n_m2 * penetration * penetration
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAW: HuntCrossley = HuntCrossley { xi: 1.3, psi: 40.0 };

    /// The defining quotient, evaluated by brute force where s is not tiny.
    fn force_by_definition(law: &HuntCrossley, gap: f64, step: f64) -> f64 {
        let squared_gap_change = (gap - step).max(0.0).powi(2) - gap.max(0.0).powi(2);
        -law.xi * squared_gap_change / step + law.psi * squared_gap_change
    }

    #[test]
    fn closed_forms_match_the_defining_quotient_in_every_case() {
        let cases = [
            (2e-5, 1e-5),     // stays in
            (2e-5, -1e-5),    // stays in, moving deeper
            (2e-5, 3e-5),     // leaves
            (-1e-5, -3e-5),   // enters
            (-1e-5, 2e-5),    // stays out
            (-1e-5, -0.5e-5), // stays out, approaching
        ];
        for (gap, step) in cases {
            let closed = LAW.midpoint_force(gap, step).force;
            let defined = force_by_definition(&LAW, gap, step);
            assert!(
                (closed - defined).abs() <= 1e-12 * defined.abs().max(1e-12),
                "gap {gap} step {step}: {closed} vs {defined}"
            );
        }
    }

    #[test]
    fn static_contact_force_is_the_spring_force() {
        // With s = 0 and a > 0: f̃ = 2ξa, i.e. force density k·a in scaled units.
        let contact = LAW.midpoint_force(3e-6, 0.0);
        assert_eq!(contact.force, 2.0 * LAW.xi * 3e-6);
        assert_eq!(contact.stiffness, LAW.xi + 2.0 * LAW.psi * 3e-6);
    }

    #[test]
    fn jacobian_entry_is_minus_the_derivative_and_non_negative() {
        for &(gap, step) in &[
            (2e-5, 1e-5),
            (2e-5, 3e-5),
            (-1e-5, -3e-5),
            (2e-5, -4e-5),
            (-2e-6, 5e-6),
        ] {
            let h = 1e-12;
            let numerical = -(LAW.midpoint_force(gap, step + h).force
                - LAW.midpoint_force(gap, step - h).force)
                / (2.0 * h);
            let analytic = LAW.midpoint_force(gap, step).stiffness;
            assert!(analytic >= 0.0);
            assert!(
                (numerical - analytic).abs() <= 1e-5 * analytic.abs().max(1.0),
                "gap {gap} step {step}: numerical {numerical} analytic {analytic}"
            );
        }
    }

    #[test]
    fn force_is_continuous_across_the_case_boundaries() {
        let gap = 2e-5;
        let below = LAW.midpoint_force(gap, gap * (1.0 - 1e-12));
        let above = LAW.midpoint_force(gap, gap * (1.0 + 1e-12));
        assert!((below.force - above.force).abs() < 1e-15);
        assert!((below.stiffness - above.stiffness).abs() < 1e-9);
    }

    #[test]
    fn work_splits_into_potential_change_and_dissipation() {
        for &(gap, step) in &[(2e-5, 1e-5), (2e-5, 3e-5), (-1e-5, -3e-5), (1e-5, -2e-5)] {
            let contact = LAW.midpoint_force(gap, step);
            let conservative = -LAW.xi * contact.squared_gap_change;
            let dissipative = LAW.psi * contact.squared_gap_change * step;
            assert!(dissipative <= 0.0);
            let work = contact.force * step;
            assert!(
                (work - conservative - dissipative).abs() < 1e-24,
                "{gap} {step}"
            );
        }
    }

    #[test]
    fn linear_damping_keeps_the_conservative_part_and_dissipates() {
        for &(gap, step) in &[(2e-5, 1e-5), (2e-5, 3e-5), (-1e-5, -3e-5), (1e-5, -2e-5)] {
            let seed = LAW.midpoint_force(gap, step);
            let linear = LAW.midpoint_force_linear_damping(gap, step);
            // Same conservative part: the work splits into −ξΦ and a dissipation ≤ 0.
            let conservative = -LAW.xi * linear.squared_gap_change;
            let dissipation = linear.force * step - conservative;
            assert!(dissipation <= 0.0);
            assert!(
                (dissipation + LAW.linear_damping_loss(gap, step)).abs() < 1e-22,
                "{gap} {step}"
            );
            assert_eq!(seed.squared_gap_change, linear.squared_gap_change);
            // The Jacobian entry is −∂F/∂s, and ≥ 0.
            let h = 1e-12;
            let numerical = -(LAW.midpoint_force_linear_damping(gap, step + h).force
                - LAW.midpoint_force_linear_damping(gap, step - h).force)
                / (2.0 * h);
            assert!(linear.stiffness >= 0.0);
            assert!((numerical - linear.stiffness).abs() <= 1e-5 * linear.stiffness.max(1.0));
        }
        // In contact the force is linear in s.
        let (a, b, c) = (
            LAW.midpoint_force_linear_damping(3e-5, 0.0).force,
            LAW.midpoint_force_linear_damping(3e-5, 1e-5).force,
            LAW.midpoint_force_linear_damping(3e-5, 2e-5).force,
        );
        assert!((a - 2.0 * b + c).abs() < 1e-15 * a.abs());
    }

    #[test]
    fn scaling_uses_four_rho_a() {
        let law = HuntCrossley::scaled(1e8, 0.1, 1.0 / 176_400.0, 5.58e-4);
        let expected_xi = 1e8 / (176_400.0f64 * 176_400.0) / (4.0 * 5.58e-4);
        assert!((law.xi - expected_xi).abs() < 1e-15 * expected_xi);
        assert!((law.psi - law.xi * 0.1 * 176_400.0).abs() < 1e-12 * law.psi);
    }
}
