//! Newton's iteration of a contact step on at most [`WIDE_BLOCK`] tracked points, in fixed lanes
//! (`docs/modal-tanpura.md`, section 4; the equations of `step.rs`, whose general path takes
//! more points).
//!
//! The bridge's crest and the thread rarely hold more than five tracked points.
//! [`ContactStep`](super::step::ContactStep) loads their state into fixed arrays of [`BLOCK`]
//! lanes, or [`WIDE_BLOCK`] when more points are tracked (a very stiff bridge); the slots past
//! the tracked ones are neutral (no gap, no step, no rest force, no coupling). It iterates here,
//! so that each pass (the law, the residual
//! `R = Δu − Δu_free − G ΔF`, the update `δ = −R − G_{:,A} D y`, the exact finish's direction
//! `w = G e_c − G_{:,A} D y'`) is a few full-width vector operations with no loop control, no
//! bounds checks and no overlap checks between arrays of one struct. Every value is formed by
//! the arithmetic of the general path in its order, so the iterates agree with it to the last
//! bit except, at most, in the sign of a zero: a point that adds nothing adds an exact zero
//! (`x − 0·g`), where the general path skips it.
//!
//! Hand-written rather than on a linear-algebra crate for the reasons of `step.rs`.

use super::solve::{ldl_factor_fixed, ldl_solve_in_place, ldl_substitute_fixed};
use crate::tanpura::contact::HuntCrossley;

/// The lanes of the fixed path: one AVX-512 register of f64, two AVX2 registers.
pub const BLOCK: usize = 8;
/// The wide fixed path's lanes, for up to twice as many tracked points.
pub const WIDE_BLOCK: usize = 16;
/// The largest active set whose system is solved by the unrolled LDLᵀ (with the exact finish of
/// a crossing point); larger ones by the general loops, as `ContactStep::update` does.
const FIXED_SOLVE: usize = 8;
/// One value per slot.
pub type Lanes<const N: usize> = [f64; N];
/// G on the first `N` slots, row by row.
pub type Block<const N: usize> = [Lanes<N>; N];
/// What an update did: the largest component of the applied change (NaN when the state is not
/// finite) and whether the step is now exact.
type Update = (f64, bool);

/// The tracked points' state in slot order; the lanes from `count` on are neutral.
#[derive(Debug, Clone, Copy)]
pub struct BlockState<const N: usize> {
    pub count: usize,
    pub gaps: Lanes<N>,
    pub free_steps: Lanes<N>,
    pub steps: Lanes<N>,
    pub rest_forces: Lanes<N>,
    pub xis: Lanes<N>,
    pub psis: Lanes<N>,
    /// F, c = −∂F/∂Δu and F − F_rest at the last evaluation.
    pub forces: Lanes<N>,
    pub stiffnesses: Lanes<N>,
    pub changes: Lanes<N>,
}

/// `values` as lanes (`values` holds at least `N` elements).
#[inline(always)]
pub fn lanes_of<const N: usize>(values: &[f64]) -> Lanes<N> {
    let mut lanes = [0.0; N];
    lanes.copy_from_slice(&values[..N]);
    lanes
}

/// Whether a point is in contact before and after a step `step` from gap `gap`.
#[inline(always)]
pub fn contact_case(gap: f64, step: f64) -> (bool, bool) {
    (gap > 0.0, gap - step > 0.0)
}

/// The crossing point c of the exact finish (`docs/modal-tanpura.md`, section 4): its gap
/// before the step, its step `s⁰` at the evaluation point, its law and the law's force and `c`
/// there, `w_c` of the direction `w = J⁻¹ G e_c`, and Newton's update `δ_c`.
#[derive(Debug, Clone, Copy)]
pub struct CrossingPoint {
    pub gap: f64,
    pub start: f64,
    pub law: HuntCrossley,
    pub force: f64,
    pub stiffness: f64,
    pub direction: f64,
    pub delta: f64,
}

/// The crossing point's own equation `s = s⁰ + δ_c + w_c ρ(s)`, where `ρ(s) = F_c(s) − F_c⁰ +
/// c_c (s − s⁰)`, solved in each of the point's two possible cases. On a crossing the law is
/// `F_c(s) = P/s + Q s + K` (leaving: `P = ξa²`, `Q = −2ψa`, `K = 0`; entering: `P = −ξa²`,
/// `Q = −ξ`, `K = 2ξa`), and the equation times s is a quadratic; its root in the crossing case
/// (the one nearer Newton's `s⁰ + δ_c` if both are) is taken. If it has none, the point stays in
/// the case it had before the step (in contact: `P = 0`, `Q = −ξ − 2ψa`, `K = 2ξa`; out: the law
/// is zero), where the equation is linear, and its root is taken if it lies in that case.
/// Returns the step and `ρ` there, or `None` if neither case holds a root. Both paths of the
/// solve (`block.rs`, `step.rs`) finish with it.
#[inline(always)]
pub fn exact_crossing_step(point: CrossingPoint) -> Option<(f64, f64)> {
    exact_step_crossing(&point).or_else(|| exact_step_staying(&point))
}

impl CrossingPoint {
    /// α and β of the point's own equation times s, `α s² − β s − γ = 0` (γ = w P), for a law
    /// `P/s + Q s + K`: `α = 1 − w (Q + c_c)`, `β = s⁰ + δ_c + w (K − F_c⁰ − c_c s⁰)`.
    #[inline(always)]
    fn own_equation(&self, q: f64, k: f64) -> (f64, f64) {
        let w = self.direction;
        let alpha = 1.0 - w * (q + self.stiffness);
        let beta = (self.start + self.delta) + w * (k - self.force - self.stiffness * self.start);
        (alpha, beta)
    }

    /// `ρ(s) = F_c(s) − F_c⁰ + c_c (s − s⁰)` for the law's value `law_force` at `step`.
    #[inline(always)]
    fn departure(&self, law_force: f64, step: f64) -> f64 {
        law_force - self.force + self.stiffness * (step - self.start)
    }
}

/// [`exact_crossing_step`] in the crossing case: the quadratic's root there.
#[inline(always)]
fn exact_step_crossing(point: &CrossingPoint) -> Option<(f64, f64)> {
    let (gap, law) = (point.gap, point.law);
    let leaving = gap > 0.0;
    let (p, q, k) = if leaving {
        (law.xi * gap * gap, -2.0 * law.psi * gap, 0.0)
    } else {
        (-law.xi * gap * gap, -law.xi, 2.0 * law.xi * gap)
    };
    let newton = point.start + point.delta;
    let (alpha, beta) = point.own_equation(q, k);
    let gamma = point.direction * p;
    let discriminant = beta * beta + 4.0 * alpha * gamma;
    // Also false for a NaN discriminant.
    let real_roots = discriminant >= 0.0;
    if !real_roots || alpha == 0.0 {
        return None;
    }
    let half = 0.5 * (beta + beta.signum() * discriminant.sqrt());
    if half == 0.0 {
        return None;
    }
    let in_case = |s: f64| {
        let (before, after) = contact_case(gap, s);
        before == leaving && after != leaving && s != 0.0
    };
    let step = match (half / alpha, -gamma / half) {
        (one, other) if in_case(one) && in_case(other) => {
            if (one - newton).abs() <= (other - newton).abs() {
                one
            } else {
                other
            }
        }
        (one, _) if in_case(one) => one,
        (_, other) if in_case(other) => other,
        _ => return None,
    };
    Some((step, point.departure(p / step + q * step + k, step)))
}

/// [`exact_crossing_step`] in the case the point had before the step, where its law is linear,
/// `F_c(s) = Q s + K` (P = 0): `α s = β`.
#[inline(always)]
fn exact_step_staying(point: &CrossingPoint) -> Option<(f64, f64)> {
    let (gap, law) = (point.gap, point.law);
    let (q, k) = if gap > 0.0 {
        (-law.xi - 2.0 * law.psi * gap, 2.0 * law.xi * gap)
    } else {
        (0.0, 0.0)
    };
    let (alpha, beta) = point.own_equation(q, k);
    let step = beta / alpha;
    let (before, after) = contact_case(gap, step);
    if !step.is_finite() || before != after {
        return None;
    }
    Some((step, point.departure(q * step + k, step)))
}

impl<const N: usize> BlockState<N> {
    /// Whether no point can exert a force different from its rest force during the free step
    /// (`ContactStep::settle_if_free`'s test).
    #[inline(always)]
    pub fn free_of_contact(&self) -> bool {
        let mut free = true;
        for lane in 0..N {
            let gap = self.gaps[lane];
            free &=
                self.rest_forces[lane] == 0.0 && gap <= 0.0 && gap - self.free_steps[lane] <= 0.0;
        }
        free
    }

    /// Whether some point enters or leaves contact during its current step.
    #[inline(always)]
    pub fn crosses(&self) -> bool {
        let mut crossing = false;
        for lane in 0..N {
            let (before, after) = contact_case(self.gaps[lane], self.steps[lane]);
            crossing |= before != after;
        }
        crossing
    }

    /// The law at the current steps when no point crosses: every point either stays in contact
    /// (the law's linear branch) or out of it, bit for bit
    /// [`HuntCrossley::midpoint_force_linear_damping`] in those cases.
    #[inline(always)]
    pub fn evaluate_without_crossing(&mut self) {
        for lane in 0..N {
            let (gap, step) = (self.gaps[lane], self.steps[lane]);
            let damping = 2.0 * self.psis[lane] * gap.max(0.0);
            let touching = gap > 0.0;
            let force = self.xis[lane] * (2.0 * gap - step) - damping * step;
            self.forces[lane] = if touching { force } else { 0.0 };
            self.stiffnesses[lane] = if touching {
                self.xis[lane] + damping
            } else {
                0.0
            };
            self.changes[lane] = self.forces[lane] - self.rest_forces[lane];
        }
    }

    /// The law at the current steps, point by point where some point crosses.
    #[inline(always)]
    pub fn evaluate(&mut self) {
        if !self.crosses() {
            self.evaluate_without_crossing();
            return;
        }
        for lane in 0..self.count {
            let law = HuntCrossley {
                xi: self.xis[lane],
                psi: self.psis[lane],
            };
            let contact = law.midpoint_force_linear_damping(self.gaps[lane], self.steps[lane]);
            self.forces[lane] = contact.force;
            self.stiffnesses[lane] = contact.stiffness;
            self.changes[lane] = contact.force - self.rest_forces[lane];
        }
    }

    /// Whether every point is in the same contact case before and after its step.
    #[inline(always)]
    pub fn cases_unchanged(&self) -> bool {
        !self.crosses()
    }

    /// How many points enter or leave contact during their step, and the slot of the last.
    #[inline(always)]
    fn crossing_points(&self) -> (usize, usize) {
        let mut count = 0;
        for lane in 0..N {
            let (before, after) = contact_case(self.gaps[lane], self.steps[lane]);
            count += usize::from(before != after);
        }
        let mut last = 0;
        if count == 1 {
            for slot in 0..self.count {
                let (before, after) = contact_case(self.gaps[slot], self.steps[slot]);
                if before != after {
                    last = slot;
                }
            }
        }
        (count, last)
    }

    /// Newton's iteration from the current steps, at most `max_iterations` updates, stopping
    /// as `ContactStep::newton` does; then the forces at the accepted step. Returns (updates,
    /// converged).
    #[inline(always)]
    pub fn newton(
        &mut self,
        block: &Block<N>,
        tolerance_m: f64,
        max_iterations: u32,
    ) -> (u32, bool) {
        let cap = max_iterations.max(1);
        let mut outcome = (cap, false);
        for iteration in 1..=cap {
            self.evaluate();
            let (crossing, crossing_slot) = self.crossing_points();
            let linear = crossing == 0;
            let (largest, exact) = self.update(block, (crossing == 1).then_some(crossing_slot));
            if !largest.is_finite() {
                outcome = (iteration, false);
                break;
            }
            // Exact: the update solved the step for the cases of the evaluation point, and the
            // step lies in those cases (always so when the law was linear at the evaluation
            // point and the cases did not change).
            if exact || largest <= tolerance_m || (linear && self.cases_unchanged()) {
                outcome = (iteration, true);
                break;
            }
        }
        self.evaluate();
        outcome
    }

    /// One Newton update `δ = −J⁻¹ R` at the last evaluation, applied to the steps; with
    /// `crossing` (the one point that enters or leaves contact), first the step solved exactly
    /// for the evaluation point's contact cases, taken if it lies in them
    /// (`ContactStep::update`).
    #[inline(always)]
    fn update(&mut self, block: &Block<N>, crossing: Option<usize>) -> Update {
        // R = Δu − Δu_free − G ΔF; a point with no force change adds an exact zero.
        let mut residual = [0.0; N];
        for lane in 0..N {
            residual[lane] = self.steps[lane] - self.free_steps[lane];
        }
        for (row, &change) in block.iter().zip(&self.changes) {
            for lane in 0..N {
                residual[lane] -= row[lane] * change;
            }
        }
        // A: the points with c > 0, and D = diag(√c) on them.
        let mut active = [0usize; N];
        let mut roots = [0.0; N];
        let mut size = 0;
        for slot in 0..self.count {
            if self.stiffnesses[slot] > 0.0 {
                active[size] = slot;
                roots[size] = self.stiffnesses[slot].sqrt();
                size += 1;
            }
        }
        // (I + D G_AA D) y = −D R_A and D y per point (zero off A); with a crossing point c,
        // also (I + D G_AA D) y' = D G_{A,c} and D y' (the exact finish needs the factors for a
        // second right-hand side: the unrolled sizes, as in `ContactStep::update`).
        let crossing = crossing.filter(|_| size <= FIXED_SOLVE);
        let system = Active {
            block,
            active: &active,
            roots: &roots,
            crossing,
        };
        let mut weights = [0.0; N];
        let mut crossing_weights = [0.0; N];
        let finite = match size {
            0 => true,
            1 => system.solve::<1>(&residual, &mut weights, &mut crossing_weights),
            2 => system.solve::<2>(&residual, &mut weights, &mut crossing_weights),
            3 => system.solve::<3>(&residual, &mut weights, &mut crossing_weights),
            4 => system.solve::<4>(&residual, &mut weights, &mut crossing_weights),
            5 => system.solve::<5>(&residual, &mut weights, &mut crossing_weights),
            6 => system.solve::<6>(&residual, &mut weights, &mut crossing_weights),
            7 => system.solve::<7>(&residual, &mut weights, &mut crossing_weights),
            8 => system.solve::<8>(&residual, &mut weights, &mut crossing_weights),
            _ => system.solve_any(size, &residual, &mut weights),
        };
        // δ = −R − G_{:,A} D y.
        let mut deltas = [0.0; N];
        for lane in 0..N {
            deltas[lane] = -residual[lane];
        }
        for (row, &weight) in block.iter().zip(&weights) {
            for lane in 0..N {
                deltas[lane] -= row[lane] * weight;
            }
        }
        if let Some(crossing) = crossing {
            if let Some(largest) = self.finish_exactly(block, crossing, &deltas, &crossing_weights)
            {
                return (largest, true);
            }
        }
        let mut largest = 0.0f64;
        for lane in 0..N {
            self.steps[lane] += deltas[lane];
            largest = largest.max(deltas[lane].abs());
        }
        if finite && largest.is_finite() {
            (largest, false)
        } else {
            (f64::NAN, false)
        }
    }

    /// The step solved exactly for the contact cases of the evaluation point when one point `c`
    /// crosses and every other stays in or out (`ContactStep::finish_exactly`, derived in
    /// `docs/modal-tanpura.md`, section 4): with the update `deltas` and `w = J⁻¹ G e_c`, the
    /// crossing point's own equation is a quadratic in its step (or linear, in the case the point
    /// had). Replaces the steps and returns the largest change if every other point then lies in
    /// the case it was evaluated in.
    #[inline(always)]
    fn finish_exactly(
        &mut self,
        block: &Block<N>,
        crossing: usize,
        deltas: &Lanes<N>,
        crossing_weights: &Lanes<N>,
    ) -> Option<f64> {
        // w = G e_c − G_{:,A} D y'.
        let mut direction = block[crossing];
        for (row, &weight) in block.iter().zip(crossing_weights) {
            for lane in 0..N {
                direction[lane] -= row[lane] * weight;
            }
        }
        let gap = self.gaps[crossing];
        let (step, departure) = exact_crossing_step(CrossingPoint {
            gap,
            start: self.steps[crossing],
            law: HuntCrossley {
                xi: self.xis[crossing],
                psi: self.psis[crossing],
            },
            force: self.forces[crossing],
            stiffness: self.stiffnesses[crossing],
            direction: direction[crossing],
            delta: deltas[crossing],
        })?;
        let mut candidates = self.steps;
        let mut largest = 0.0f64;
        for slot in 0..self.count {
            let candidate = if slot == crossing {
                step
            } else {
                self.steps[slot] + deltas[slot] + departure * direction[slot]
            };
            // The crossing point's case is the one its step was solved in.
            let evaluated = contact_case(self.gaps[slot], self.steps[slot]);
            let moved = contact_case(self.gaps[slot], candidate) != evaluated;
            if !candidate.is_finite() || (moved && slot != crossing) {
                return None;
            }
            candidates[slot] = candidate;
            largest = largest.max((candidate - self.steps[slot]).abs());
        }
        self.steps = candidates;
        Some(largest)
    }
}

/// The linear system of an update on the active points `A`: `I + D G_AA D`.
struct Active<'a, const N: usize> {
    block: &'a Block<N>,
    active: &'a [usize; N],
    roots: &'a Lanes<N>,
    crossing: Option<usize>,
}

impl<const N: usize> Active<'_, N> {
    /// `(I + D G_AA D) y = −D R_A` for the `N` active points: writes `D y` into `weights` at
    /// the points' lanes and, with a crossing point c, `D y'` for `(I + D G_AA D) y' = D G_{A,c}`
    /// into `crossing_weights`; returns whether `D y` is finite
    /// (`ContactStep::solve_active_fixed`).
    #[inline(always)]
    fn solve<const SIZE: usize>(
        &self,
        residual: &Lanes<N>,
        weights: &mut Lanes<N>,
        crossing_weights: &mut Lanes<N>,
    ) -> bool {
        let (block, active, roots) = (self.block, self.active, self.roots);
        let mut matrix = [[0.0; SIZE]; SIZE];
        let mut y = [0.0; SIZE];
        for a in 0..SIZE {
            let row = &block[active[a]];
            for b in 0..=a {
                matrix[b][a] = roots[a] * row[active[b]] * roots[b];
            }
            matrix[a][a] += 1.0;
            y[a] = -roots[a] * residual[active[a]];
        }
        ldl_factor_fixed(&mut matrix);
        ldl_substitute_fixed(&matrix, &mut y);
        let mut finite = true;
        for a in 0..SIZE {
            let weight = y[a] * roots[a];
            weights[active[a]] = weight;
            finite &= weight.is_finite();
        }
        if let Some(crossing) = self.crossing {
            let column = &block[crossing];
            let mut second = [0.0; SIZE];
            for a in 0..SIZE {
                second[a] = roots[a] * column[active[a]];
            }
            ldl_substitute_fixed(&matrix, &mut second);
            for a in 0..SIZE {
                crossing_weights[active[a]] = second[a] * roots[a];
            }
        }
        finite
    }

    /// [`Active::solve`] for more than [`FIXED_SOLVE`] active points, by the general path's
    /// loops (`ContactStep::solve_active_any`, the same arithmetic), with no crossing finish.
    #[inline(always)]
    fn solve_any(&self, size: usize, residual: &Lanes<N>, weights: &mut Lanes<N>) -> bool {
        let (block, active, roots) = (self.block, self.active, self.roots);
        let mut matrix = [0.0; WIDE_BLOCK * WIDE_BLOCK];
        let (mut y, mut scratch) = ([0.0; WIDE_BLOCK], [0.0; WIDE_BLOCK]);
        let matrix = &mut matrix[..size * size];
        for a in 0..size {
            let row = &block[active[a]];
            for b in 0..=a {
                matrix[a * size + b] = roots[a] * row[active[b]] * roots[b];
            }
            matrix[a * size + a] += 1.0;
            y[a] = -roots[a] * residual[active[a]];
        }
        ldl_solve_in_place(matrix, size, &mut y[..size], &mut scratch[..size]);
        let mut finite = true;
        for a in 0..size {
            let weight = y[a] * roots[a];
            weights[active[a]] = weight;
            finite &= weight.is_finite();
        }
        finite
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A crossing point of a stiff law with a mild coupling (`w` = 1e-6 m/N), its law
    /// evaluated at the iterate `start` and Newton's update `delta`.
    fn evaluated_at(gap: f64, start: f64, delta: f64) -> CrossingPoint {
        let law = HuntCrossley {
            xi: 2.0e4,
            psi: 1.0e7,
        };
        let evaluated = law.midpoint_force_linear_damping(gap, start);
        CrossingPoint {
            gap,
            start,
            law,
            force: evaluated.force,
            stiffness: evaluated.stiffness,
            direction: 1.0e-6,
            delta,
        }
    }

    /// The residual of the crossing point's own equation `s − s⁰ − δ_c − w ρ(s)` at `step`,
    /// with the law of the case `step` lies in (`midpoint_force_linear_damping`).
    fn own_equation_residual(point: &CrossingPoint, step: f64) -> f64 {
        let force = point
            .law
            .midpoint_force_linear_damping(point.gap, step)
            .force;
        let departure = force - point.force + point.stiffness * (step - point.start);
        step - point.start - point.delta - point.direction * departure
    }

    /// A point whose iterate leaves contact but whose step stays in it (or enters but stays
    /// out): the quadratic of the crossing case has no root there, and the finish takes the
    /// root of the point's own, linear, case, which solves its equation to round-off.
    #[test]
    fn the_finish_solves_the_staying_case_when_the_crossing_case_has_no_root() {
        for (gap, start) in [(1.0e-6, 1.5e-6), (-1.0e-6, -1.5e-6)] {
            // Newton's update points back across the contact edge.
            let point = evaluated_at(gap, start, -1.2 * start);
            assert!(exact_step_crossing(&point).is_none(), "gap {gap:e}");
            let (step, departure) = exact_crossing_step(point).expect("a root in the staying case");
            let (before, after) = contact_case(gap, step);
            assert_eq!(
                before, after,
                "gap {gap:e}: the step {step:e} stays in its case"
            );
            let scale = start.abs();
            let residual = own_equation_residual(&point, step);
            assert!(residual.abs() <= 1e-14 * scale, "gap {gap:e}: {residual:e}");
            let expected = point.law.midpoint_force_linear_damping(gap, step).force - point.force
                + point.stiffness * (step - start);
            assert!((departure - expected).abs() <= 1e-12 * expected.abs().max(1e-9));
        }
    }

    /// When the crossing case holds the root, the finish still takes it there.
    #[test]
    fn the_finish_keeps_the_crossing_root_when_there_is_one() {
        let (gap, start) = (1.0e-6, 1.5e-6);
        let point = evaluated_at(gap, start, 0.2e-6);
        let (step, _) = exact_crossing_step(point).expect("a root");
        assert_eq!(contact_case(gap, step), (true, false), "{step:e}");
        assert!(own_equation_residual(&point, step).abs() <= 1e-14 * start);
    }
}
