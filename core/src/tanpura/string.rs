//! The physical string shared by every discretisation: its constants in SI units (seed 000,
//! eq. 5–7, section 5; `shared/notes/tanpura-model.md`).
//!
//! `ρA y_tt = (T y_xx − EI y_xxxx)(1 + η ∂_t) − ρA γ y_t + contact forces`, with `y(0) = y_TB` (the
//! lowered left support at the tuning bead), `y(L) = 0` (the nut) and `y_xx = 0` at both ends.
//! Per mode of angular frequency ω the decay rate is σ = γ/2 + η ω²/2.

/// Physical constants of one string (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StringParameters {
    /// Length from the tuning bead (x = 0) to the nut (x = L), m. Seed: 0.668.
    pub length_m: f64,
    /// Tension T, N. Seed: 31.47.
    pub tension_n: f64,
    /// Bending stiffness EI, N m². Seed: 8.35e-5.
    pub bending_stiffness_n_m2: f64,
    /// Linear density ρA, kg/m. Seed: 5.58e-4.
    pub linear_density_kg_m: f64,
    /// Frequency-independent loss γ, 1/s. Seed: 0.6.
    pub gamma_per_s: f64,
    /// Frequency-dependent (Kelvin–Voigt) loss η, s. Seed: 7e-9.
    pub eta_s: f64,
    /// Height y_TB of the lowered left support, m (negative presses the string onto the
    /// bridge). The seed does not print it; −2 mm gives a firm preload on the thread.
    pub left_support_m: f64,
}

impl StringParameters {
    /// The string of the seed's section 5.
    pub const SEED: StringParameters = StringParameters {
        length_m: 0.668,
        tension_n: 31.47,
        bending_stiffness_n_m2: 8.35e-5,
        linear_density_kg_m: 5.58e-4,
        gamma_per_s: 0.6,
        eta_s: 7e-9,
        left_support_m: -2e-3,
    };

    /// Wave speed √(T/ρA), m/s.
    pub fn wave_speed_m_s(&self) -> f64 {
        (self.tension_n / self.linear_density_kg_m).sqrt()
    }
}
