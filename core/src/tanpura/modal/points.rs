//! The points where the modal string meets the bridge and the thread (`docs/modal-tanpura.md`,
//! section 3).
//!
//! Each point `x_i` stands for a length `w_i` of its barrier (the point spacing), with the
//! barrier's height `h_i` from `geometry.rs` (the same profiles as the FD tiers), its spring
//! `w_i k` and its mid-point law scaled to newtons (`contact.rs`, [`HuntCrossley::for_point`]).
//! For the modes it holds the shapes `Ψ_ik = φ_k(x_i)/√κ_k` and the coupling
//! `G = Ψ diag(b) Ψᵀ` of eq. M1 (the step of point i per newton at point j, constant while the
//! string's parameters are), the truncated modes' static compliance `R = C − Ψ Ψᵀ` between the
//! points (`docs/modal-tanpura.md`, section 8; `C` in closed form from `modes.rs`), and for the
//! rest state its gaps and forces. R enters the static problems only (the rest state, the pressed
//! finger): the step's coupling is G alone (see `docs/modal-tanpura.md` §8 for why).

use super::lanes::{padded_lanes, Kernels};
use super::modes::{ModeSet, MODE_CAPACITY};
use crate::dense::{leading_eigenpairs, symmetric_eigen_jacobi, LEADING_BLOCK_CAPACITY};
use crate::tanpura::contact::HuntCrossley;
use crate::tanpura::geometry::{grid_points, BridgeSettings, ThreadSettings};

/// The bridge and thread points of one modal string; allocation-free after `with_capacity`.
#[derive(Debug, Clone)]
pub struct ContactPoints {
    count: usize,
    bridge_count: usize,
    capacity: usize,
    pub positions_m: Vec<f64>,
    pub heights_m: Vec<f64>,
    /// w_i, m: the barrier length a point stands for.
    pub weights_m: Vec<f64>,
    /// w_i k, N/m: the point's static spring.
    pub springs_n_m: Vec<f64>,
    pub laws: Vec<HuntCrossley>,
    /// g_i = h_i − y_s(x_i): the gap over the straight line between the supports, m.
    pub free_gaps_m: Vec<f64>,
    /// Ψ rows, `capacity × MODE_CAPACITY`, zero beyond the kept modes.
    pub shapes: Vec<f64>,
    /// G = Ψ diag(b) Ψᵀ, `capacity × capacity`, row-major.
    pub coupling: Vec<f64>,
    /// R = C − Ψ Ψᵀ, `capacity × capacity`, row-major; zero with the static flexibility off.
    pub residual: Vec<f64>,
    /// Whether R is in use (some entry non-zero).
    pub flexible: bool,
    /// The rest state: gaps a_rest,i (m) and forces F_rest,i = w_i k ⌊a_rest,i⌋ (N).
    pub rest_gaps_m: Vec<f64>,
    pub rest_forces_n: Vec<f64>,
    /// Scratch of [`ContactPoints::couple`]: a row of Ψ diag(b), the point indices in order,
    /// and one row of G and of Ψ Ψᵀ.
    weighted_row: Vec<f64>,
    all_points: Vec<usize>,
    coupling_row: Vec<f64>,
    kept_row: Vec<f64>,
    /// Scratch of the residual modes: the kept modes' residual compliance on the points and
    /// its eigenvectors (`capacity × capacity`).
    eigen_matrix: Vec<f64>,
    eigen_vectors: Vec<f64>,
    /// Subspace iteration's block and its image ([`leading_eigenpairs`]).
    eigen_work: Vec<f64>,
}

impl ContactPoints {
    /// Room for `capacity` points. Allocates.
    pub fn with_capacity(capacity: usize) -> Self {
        let zeros = |n: usize| vec![0.0; n];
        Self {
            count: 0,
            bridge_count: 0,
            capacity,
            positions_m: zeros(capacity),
            heights_m: zeros(capacity),
            weights_m: zeros(capacity),
            springs_n_m: zeros(capacity),
            laws: vec![HuntCrossley { xi: 0.0, psi: 0.0 }; capacity],
            free_gaps_m: zeros(capacity),
            shapes: zeros(capacity * MODE_CAPACITY),
            coupling: zeros(capacity * capacity),
            residual: zeros(capacity * capacity),
            flexible: false,
            rest_gaps_m: zeros(capacity),
            rest_forces_n: zeros(capacity),
            weighted_row: zeros(MODE_CAPACITY),
            all_points: (0..capacity).collect(),
            coupling_row: zeros(capacity),
            kept_row: zeros(capacity),
            eigen_matrix: zeros(capacity * capacity),
            eigen_vectors: zeros(capacity * capacity),
            eigen_work: zeros(2 * capacity * LEADING_BLOCK_CAPACITY),
        }
    }

    /// M, the points in use (bridge first, then thread).
    pub fn len(&self) -> usize {
        self.count
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// The bridge points are `0..bridge_count()`, the thread's the rest.
    pub fn bridge_count(&self) -> usize {
        self.bridge_count
    }

    /// Ψ_i, the shapes of the modes at point i.
    pub fn shape(&self, i: usize) -> &[f64] {
        &self.shapes[i * MODE_CAPACITY..(i + 1) * MODE_CAPACITY]
    }

    /// G_ij.
    #[inline]
    pub fn coupling(&self, i: usize, j: usize) -> f64 {
        self.coupling[i * self.capacity + j]
    }

    /// Places the bridge's points (a point per `bridge_spacing_m` over the part of the bridge
    /// between `bridge_start_m` and `bridge_end_m`, if its stiffness is positive) and sets their
    /// laws for the step `time_step_s`; the thread's follow by [`ContactPoints::place_thread`].
    /// Points beyond the capacity are dropped. `left_support_m` and `length_m` give the line
    /// y_s. Allocation-free.
    #[allow(clippy::too_many_arguments)]
    pub fn place_bridge(
        &mut self,
        bridge: &BridgeSettings,
        bridge_start_m: f64,
        bridge_end_m: f64,
        bridge_spacing_m: f64,
        time_step_s: f64,
        left_support_m: f64,
        length_m: f64,
    ) {
        self.count = 0;
        if bridge.stiffness_n_m2 > 0.0 && bridge_end_m > bridge_start_m {
            let points = grid_points(bridge_start_m, bridge_end_m, bridge_spacing_m);
            for index in 0..points {
                let x = bridge_start_m + index as f64 * bridge_spacing_m;
                self.push(
                    x,
                    bridge.height_m(x),
                    bridge_spacing_m,
                    bridge.stiffness_n_m2,
                    bridge.damping_s_m,
                    time_step_s,
                );
            }
        }
        self.bridge_count = self.count;
        self.set_free_gaps(0, left_support_m, length_m);
    }

    /// Places the thread's points (over the part of its cap above the bridge, if its stiffness
    /// is positive), `thread_spacing_m` apart and `thread_offset_m` from its top (0: symmetric
    /// about the top with a point on it), after the bridge's points of the last
    /// [`ContactPoints::place_bridge`], which stay; as many times as lattices are tried.
    /// Allocation-free.
    #[allow(clippy::too_many_arguments)]
    pub fn place_thread(
        &mut self,
        bridge: &BridgeSettings,
        thread: Option<&ThreadSettings>,
        thread_spacing_m: f64,
        thread_offset_m: f64,
        time_step_s: f64,
        left_support_m: f64,
        length_m: f64,
    ) {
        let side = thread.map_or(0, |thread| {
            (thread.half_width_m() / thread_spacing_m).floor() as usize
        });
        let centre_m = thread.map_or(0.0, |thread| thread.position_m + thread_offset_m);
        let positions = (0..2 * side + 1)
            .map(|index| centre_m + (index as f64 - side as f64) * thread_spacing_m);
        self.place_thread_points(bridge, thread, positions, thread_spacing_m, time_step_s);
        self.set_free_gaps(self.bridge_count, left_support_m, length_m);
    }

    /// Places the thread's points where the FD string's barrier grid has them (`fd/mod.rs`):
    /// from the first edge of its cap (`position − half width`), `thread_spacing_m` apart over
    /// the cap's width, after the bridge's points of the last [`ContactPoints::place_bridge`],
    /// which stay. The grid modes' rule (`docs/modal-tanpura.md` §10, stop 50): with the
    /// reference's spacing the two strings then touch the thread at the same points.
    /// Allocation-free.
    pub fn place_thread_as_the_grid(
        &mut self,
        bridge: &BridgeSettings,
        thread: Option<&ThreadSettings>,
        thread_spacing_m: f64,
        time_step_s: f64,
        left_support_m: f64,
        length_m: f64,
    ) {
        let (first_m, count) =
            thread.map_or((0.0, 0), |thread| thread.barrier_lattice(thread_spacing_m));
        let positions = (0..count).map(|index| first_m + index as f64 * thread_spacing_m);
        self.place_thread_points(bridge, thread, positions, thread_spacing_m, time_step_s);
        self.set_free_gaps(self.bridge_count, left_support_m, length_m);
    }

    /// The thread's points at `positions`, each standing for `spacing_m` of it, after the
    /// bridge's, if the thread has a positive stiffness.
    fn place_thread_points(
        &mut self,
        bridge: &BridgeSettings,
        thread: Option<&ThreadSettings>,
        positions: impl Iterator<Item = f64>,
        spacing_m: f64,
        time_step_s: f64,
    ) {
        self.count = self.bridge_count;
        let Some(thread) = thread.filter(|thread| thread.stiffness_n_m2 > 0.0) else {
            return;
        };
        for x in positions {
            self.push(
                x,
                thread.height_over(bridge, x),
                spacing_m,
                thread.stiffness_n_m2,
                thread.damping_s_m,
                time_step_s,
            );
        }
    }

    /// g_i = h_i − y_s(x_i) for the points `first..`.
    fn set_free_gaps(&mut self, first: usize, left_support_m: f64, length_m: f64) {
        for i in first..self.count {
            let line = left_support_m * (1.0 - self.positions_m[i] / length_m);
            self.free_gaps_m[i] = self.heights_m[i] - line;
        }
    }

    fn push(
        &mut self,
        x_m: f64,
        height_m: f64,
        spacing_m: f64,
        stiffness_n_m2: f64,
        damping_s_m: f64,
        time_step_s: f64,
    ) {
        if self.count == self.capacity {
            return;
        }
        let i = self.count;
        self.positions_m[i] = x_m;
        self.heights_m[i] = height_m;
        self.weights_m[i] = spacing_m;
        self.springs_n_m[i] = stiffness_n_m2 * spacing_m;
        self.laws[i] = HuntCrossley::for_point(stiffness_n_m2, damping_s_m, spacing_m, time_step_s);
        self.count += 1;
    }

    /// R_ij, m/N.
    pub fn residual(&self, i: usize, j: usize) -> f64 {
        self.residual[i * self.capacity + j]
    }

    /// Recomputes Ψ (with the residual modes' columns, if `modes` has any), G and (with
    /// `flexible`) R for the modes, from point `first` on: 0 after placing the points or a
    /// change of the string's parameters, `bridge_count()` after a thread placed anew by
    /// [`ContactPoints::place_thread`] (the points before `first` and the modes unchanged since
    /// they were coupled). The rows from `first` on hold the columns below it by symmetry, so
    /// the numbers are a whole coupling's. The residual modes' shapes depend on every point, so
    /// with residual modes it couples them all. Returns the first point whose row it recomputed.
    /// Allocation-free; O(M K + M² K), the M² K part as SIMD dot products
    /// (`kernels.dots_pair`): each row i of G and of Ψ Ψᵀ up to the diagonal is
    /// `Ψ_j · (Ψ_i ⊙ b)` and `Ψ_j · Ψ_i` for j ≤ i. It runs on every retune of a ringing string
    /// (each tuning pass), so it is on the audio thread's path.
    pub fn couple_from(
        &mut self,
        first: usize,
        modes: &ModeSet,
        flexible: bool,
        kernels: &Kernels,
    ) -> usize {
        let first = if modes.count() > modes.kept() {
            0
        } else {
            first
        };
        self.flexible = flexible;
        let lanes = padded_lanes(modes.count());
        for i in first..self.count {
            let x = self.positions_m[i];
            modes.shape_row(
                x,
                &mut self.shapes[i * MODE_CAPACITY..(i + 1) * MODE_CAPACITY],
            );
        }
        if modes.count() > modes.kept() {
            self.shape_residual_modes(modes, kernels);
        }
        for i in first..self.count {
            let row_i = &self.shapes[i * MODE_CAPACITY..i * MODE_CAPACITY + lanes];
            for ((weighted, psi), b) in self.weighted_row.iter_mut().zip(row_i).zip(&modes.b) {
                *weighted = psi * b;
            }
            kernels.dots_pair(
                &self.shapes,
                MODE_CAPACITY,
                &self.all_points[..=i],
                &self.weighted_row[..lanes],
                row_i,
                &mut self.coupling_row[..=i],
                &mut self.kept_row[..=i],
            );
            for j in 0..=i {
                let (sum, kept) = (self.coupling_row[j], self.kept_row[j]);
                let residual = if flexible {
                    let (x_i, x_j) = (self.positions_m[i], self.positions_m[j]);
                    modes.static_compliance_m_n(x_i, x_j) - kept
                } else {
                    0.0
                };
                self.coupling[i * self.capacity + j] = sum;
                self.coupling[j * self.capacity + i] = sum;
                self.residual[i * self.capacity + j] = residual;
                self.residual[j * self.capacity + i] = residual;
            }
        }
        first
    }

    /// The residual modes' shapes at the points (`docs/modal-tanpura.md`, section 8): the
    /// truncated modes' static compliance on the points, `R = C − Ψ_K Ψ_Kᵀ` (kept modes only;
    /// symmetric, positive semi-definite), is decomposed `R = Σ_j λ_j v_j v_jᵀ`, and residual mode
    /// j takes the shape `√λ_j v_j` at the points for the j-th largest λ_j, so that with J modes
    /// `Ψ Ψᵀ` is the best rank-J completion of the kept modes' compliance towards the continuous
    /// string's. Needs the kept modes' rows in place; writes the residual columns.
    fn shape_residual_modes(&mut self, modes: &ModeSet, kernels: &Kernels) {
        let (kept, count, stride) = (modes.kept(), self.count, self.capacity);
        let kept_lanes = padded_lanes(kept);
        for i in 0..count {
            let row_i = &self.shapes[i * MODE_CAPACITY..i * MODE_CAPACITY + kept_lanes];
            kernels.dots(
                &self.shapes,
                MODE_CAPACITY,
                &self.all_points[..=i],
                row_i,
                &mut self.kept_row[..=i],
            );
            for j in 0..=i {
                let (x_i, x_j) = (self.positions_m[i], self.positions_m[j]);
                let residual = modes.static_compliance_m_n(x_i, x_j) - self.kept_row[j];
                self.eigen_matrix[i * stride + j] = residual;
                self.eigen_matrix[j * stride + i] = residual;
            }
        }
        // The leading pairs by subspace iteration (a few hundred short dot products; columns of
        // `eigen_vectors` in rank order, values in `coupling_row`).
        if leading_eigenpairs(
            &self.eigen_matrix,
            count,
            stride,
            modes.count() - kept,
            &mut self.coupling_row,
            &mut self.eigen_vectors,
            &mut self.eigen_work,
        ) {
            for (rank, mode) in (kept..modes.count()).enumerate() {
                let scale = self.coupling_row[rank].max(0.0).sqrt();
                for i in 0..count {
                    self.shapes[i * MODE_CAPACITY + mode] =
                        scale * self.eigen_vectors[i * stride + rank];
                }
            }
            return;
        }
        // Where that does not apply (more residual modes than the block holds or the points
        // allow) or does not converge: the whole decomposition.
        symmetric_eigen_jacobi(
            &mut self.eigen_matrix,
            &mut self.eigen_vectors,
            count,
            stride,
        );
        // The eigenvalues, largest first: each pick marks its entry taken with −∞.
        for (i, value) in self.coupling_row[..count].iter_mut().enumerate() {
            *value = self.eigen_matrix[i * stride + i];
        }
        for mode in kept..modes.count() {
            let eigenvalues = &mut self.coupling_row[..count];
            let largest = (0..count).max_by(|&a, &b| eigenvalues[a].total_cmp(&eigenvalues[b]));
            let (scale, column) = match largest {
                Some(e) if eigenvalues[e] > 0.0 => (eigenvalues[e].sqrt(), e),
                _ => (0.0, 0),
            };
            if let Some(e) = largest {
                eigenvalues[e] = f64::NEG_INFINITY;
            }
            for i in 0..count {
                self.shapes[i * MODE_CAPACITY + mode] =
                    scale * self.eigen_vectors[i * stride + column];
            }
        }
    }

    /// The contact potential `Σ_i w_i k/2 ⌊a_i⌋²` for the gaps `gaps_m`, J.
    pub fn potential_energy_j(&self, gaps_m: &[f64]) -> f64 {
        (0..self.count)
            .map(|i| {
                let penetration = gaps_m[i].max(0.0);
                0.5 * self.springs_n_m[i] * penetration * penetration
            })
            .sum()
    }

    /// The contact part of the vibration energy: the Bregman divergence
    /// `Σ_i V_i(a_i) − V_i(a_rest,i) − V_i'(a_rest,i)(a_i − a_rest,i) ≥ 0`, J (section 4).
    pub fn excess_energy_j(&self, gaps_m: &[f64]) -> f64 {
        (0..self.count)
            .map(|i| {
                let spring = self.springs_n_m[i];
                let (gap, rest) = (gaps_m[i], self.rest_gaps_m[i]);
                let potential = |a: f64| 0.5 * spring * a.max(0.0) * a.max(0.0);
                potential(gap) - potential(rest) - self.rest_forces_n[i] * (gap - rest)
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tanpura::string::StringParameters;

    /// The seed's bridge and thread at 44.1 kHz, placed (not coupled).
    fn seed_points(
        bridge_spacing_m: f64,
        thread_spacing_m: f64,
        thread_offset_m: f64,
    ) -> ContactPoints {
        let (bridge, thread) = (BridgeSettings::SEED, ThreadSettings::SEED);
        let (time_step_s, left_support_m, length_m) = (1.0 / 44_100.0, -2e-3, 0.668);
        let mut points = ContactPoints::with_capacity(64);
        points.place_bridge(
            &bridge,
            bridge.start_m,
            bridge.end_m,
            bridge_spacing_m,
            time_step_s,
            left_support_m,
            length_m,
        );
        points.place_thread(
            &bridge,
            Some(&thread),
            thread_spacing_m,
            thread_offset_m,
            time_step_s,
            left_support_m,
            length_m,
        );
        points
    }

    #[test]
    fn coupling_is_symmetric_and_its_diagonal_positive() {
        let mut modes = ModeSet::new();
        modes.configure(&StringParameters::SEED, 1.0 / 44_100.0, 20_000.0, None);
        let thread = ThreadSettings::SEED;
        let mut points = seed_points(1e-3, 1e-3, 0.0);
        points.couple_from(0, &modes, true, &Kernels::detect());
        assert!(points.len() > 30);
        for i in 0..points.len() {
            assert!(points.coupling(i, i) > 0.0);
            for j in 0..points.len() {
                assert_eq!(points.coupling(i, j), points.coupling(j, i));
            }
        }
        // The thread's middle point sits on its top.
        let top = points.bridge_count() + (points.len() - points.bridge_count()) / 2;
        assert!((points.positions_m[top] - thread.position_m).abs() < 1e-12);
    }

    /// A thread placed anew (another spacing and offset) and coupled from its first point gives
    /// the numbers a whole placement and coupling give, bit for bit (with the static
    /// flexibility's R too).
    #[test]
    fn a_thread_placed_anew_couples_as_a_whole_placement_does() {
        let mut modes = ModeSet::new();
        modes.configure(&StringParameters::SEED, 1.0 / 44_100.0, 20_000.0, None);
        let (bridge, thread) = (BridgeSettings::SEED, ThreadSettings::SEED);
        let kernels = Kernels::detect();
        let placed = |thread_spacing_m: f64, thread_offset_m: f64| {
            let mut points = seed_points(2e-3, thread_spacing_m, thread_offset_m);
            points.couple_from(0, &modes, true, &kernels);
            points
        };
        let mut moved = placed(0.5e-3, 0.0);
        moved.place_thread(
            &bridge,
            Some(&thread),
            0.55e-3,
            0.275e-3,
            1.0 / 44_100.0,
            -2e-3,
            0.668,
        );
        let recoupled = moved.couple_from(moved.bridge_count(), &modes, true, &kernels);
        assert_eq!(recoupled, moved.bridge_count());
        let whole = placed(0.55e-3, 0.275e-3);
        assert_eq!(moved.len(), whole.len());
        assert_eq!(moved.len(), whole.bridge_count() + 9);
        let n = whole.len();
        assert_eq!(moved.positions_m[..n], whole.positions_m[..n]);
        assert_eq!(moved.free_gaps_m[..n], whole.free_gaps_m[..n]);
        assert_eq!(moved.weights_m[..n], whole.weights_m[..n]);
        assert_eq!(
            moved.shapes[..n * MODE_CAPACITY],
            whole.shapes[..n * MODE_CAPACITY]
        );
        for i in 0..n {
            for j in 0..n {
                assert_eq!(moved.coupling(i, j), whole.coupling(i, j), "G {i} {j}");
                assert_eq!(moved.residual(i, j), whole.residual(i, j), "R {i} {j}");
            }
        }
    }
}
