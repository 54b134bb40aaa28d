//! The barriers a tanpura string touches, shared by every discretisation: the curved bridge, the
//! cotton thread and the plucking finger, as profiles y_barrier(x) with their Hunt–Crossley
//! constants (seed 000, eq. 1–2, 6; `shared/notes/tanpura-model.md`).
//!
//! The seed's measured bridge profile is not public, so this one is our own:
//! - bridge: the parabola `y_b(x) = −(x − x_crest)²/(2 R_b)` with crest at 46.5 mm, y = 0, and
//!   radius of curvature `R_b` = 0.1 m, over 25–60 mm (beyond that the string never reaches it);
//! - thread: a cap on the bridge surface, `y_c(x) = y_b(x_c) + h_c − (x − x_c)²/(2 R_c)`, with
//!   height `h_c` = 0.18 mm and an effective radius `R_c` = 20 mm (a compressible cotton thread
//!   seen through k_c = 1e8 N/m²); at the default 40 mm its top lies 31 µm below the crest, so the
//!   string rests on both and grazes the crest as it vibrates (the jawari);
//! - finger: a parabolic tip of radius half its width (`excitation.rs`).
//!
//! The grid spacings are those of the seed's FD barrier grids; the modal tiers place their own,
//! coarser contact points on the same profiles.

/// The curved bridge (a one-sided barrier) and its contact law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BridgeSettings {
    /// Position of the crest (highest point, y = 0), m from the tuning bead. Seed: 46.5 mm.
    pub crest_position_m: f64,
    /// Radius of curvature of the parabolic profile, m.
    pub curvature_radius_m: f64,
    /// Where the bridge grid starts and ends, m.
    pub start_m: f64,
    pub end_m: f64,
    /// Δx_b, m. Seed: 0.18 mm.
    pub spacing_m: f64,
    /// k_b, N/m². Seed: 1e8. Zero removes the bridge.
    pub stiffness_n_m2: f64,
    /// r_b, s/m. Seed: 0.1.
    pub damping_s_m: f64,
    /// False sets k_b = 0 beyond the thread (x > x_c), the seed's Figure 5 comparison.
    pub beyond_thread: bool,
}

impl BridgeSettings {
    pub const SEED: BridgeSettings = BridgeSettings {
        crest_position_m: 0.0465,
        curvature_radius_m: 0.1,
        start_m: 0.025,
        end_m: 0.060,
        spacing_m: 0.18e-3,
        stiffness_n_m2: 1e8,
        damping_s_m: 0.1,
        beyond_thread: true,
    };

    /// Height of the bridge surface at `x`, m.
    pub fn height_m(&self, x_m: f64) -> f64 {
        let offset = x_m - self.crest_position_m;
        -offset * offset / (2.0 * self.curvature_radius_m)
    }
}

/// The cotton thread between string and bridge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreadSettings {
    /// x_c, m from the tuning bead. Seed: 40 mm. Valid 30–45 mm (on the bridge, before its crest).
    pub position_m: f64,
    /// Height of the thread's top above the bridge surface, m.
    pub height_m: f64,
    /// Effective radius of curvature of its top, m.
    pub curvature_radius_m: f64,
    /// Δx_c, m. Seed: 0.15 mm.
    pub spacing_m: f64,
    /// k_c, N/m². Seed: 1e8.
    pub stiffness_n_m2: f64,
    /// r_c, s/m. Seed: 0.1.
    pub damping_s_m: f64,
}

impl ThreadSettings {
    pub const SEED: ThreadSettings = ThreadSettings {
        position_m: 0.040,
        height_m: 0.18e-3,
        curvature_radius_m: 0.020,
        spacing_m: 0.15e-3,
        stiffness_n_m2: 1e8,
        damping_s_m: 0.1,
    };
    pub const POSITION_RANGE_M: (f64, f64) = (0.030, 0.045);

    /// Half the length over which the thread's cap stands above the bridge surface, m.
    pub fn half_width_m(&self) -> f64 {
        (2.0 * self.curvature_radius_m * self.height_m).sqrt()
    }

    /// The thread's points at `spacing_m` as the FD string's barrier grid lays them: the first
    /// at the cap's first edge (`position − half width`), and how many cover the cap's width.
    /// The grid modes lay theirs the same way, so that both strings touch the thread at the same
    /// points (`docs/modal-tanpura.md` §10, stop 50).
    pub fn barrier_lattice(&self, spacing_m: f64) -> (f64, usize) {
        let half_width = self.half_width_m();
        (
            self.position_m - half_width,
            grid_points(0.0, 2.0 * half_width, spacing_m),
        )
    }

    /// Height of the thread's top surface at `x` (it sits on the bridge), m.
    pub fn height_over(&self, bridge: &BridgeSettings, x_m: f64) -> f64 {
        let offset = x_m - self.position_m;
        bridge.height_m(self.position_m) + self.height_m
            - offset * offset / (2.0 * self.curvature_radius_m)
    }
}

/// Points of a grid covering `[start, end]` with the given spacing (at least one).
pub fn grid_points(start_m: f64, end_m: f64, spacing_m: f64) -> usize {
    ((end_m - start_m) / spacing_m).floor().max(0.0) as usize + 1
}

/// The plucking finger's grid and contact law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerSettings {
    /// Δx_f, m. Seed: 1 mm.
    pub spacing_m: f64,
    /// k_f while pressing, N/m².
    pub stiffness_n_m2: f64,
    /// r_f, s/m. Seed: 1.
    pub damping_s_m: f64,
}

impl FingerSettings {
    pub const SEED: FingerSettings = FingerSettings {
        spacing_m: 1e-3,
        stiffness_n_m2: 1e8,
        damping_s_m: 1.0,
    };
}
