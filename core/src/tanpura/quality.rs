//! Quality tiers: how much of the seed's resolution a tanpura voice spends.
//!
//! A tier sets the internal oversampling, the string grid Δx, the barrier grid spacings, the
//! Newton tolerance and cap, and the solver. Reference is the seed's own discretisation
//! (section 5: 4 × 44.1 kHz, Δx = 3⅓ mm, Δx_b = 0.18 mm, Δx_c = 0.15 mm) with a tolerance at
//! round-off. Every tier solves the same energy-stable scheme (eq. 22) with Newton reduced to the
//! contact region (`condensed.rs`), so every tier keeps the exact discrete energy balance; the
//! cheaper tiers only resolve less. The balance is exact only for a converged Newton: a tolerance
//! of 1e-8 m let the energy of the draft tier grow by 0.3 % per step at k_b = 1e12 N/m² (found by
//! `tests/tanpura_extremes.rs`), so every tier iterates to 1e-12 m or tighter, and the cap of 30
//! updates leaves room for the stiffest contact (24 updates at most, measured at k_b = 1e12 on the
//! draft grid). Coarser tiers get a stiffer EI that keeps their inharmonicity at the reference's
//! (`tanpura.rs`, `dispersion_compensated_stiffness`). What each tier costs and how far it lands from the reference
//! is measured by `cargo xtask bench`.

use crate::newton::NewtonSettings;
use crate::tanpura::fd::SolverKind;

/// The four tiers, cheapest first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Quality {
    Draft,
    #[default]
    Live,
    Studio,
    Reference,
}

/// The numerical choices of one tier.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tier {
    /// Internal rate / output rate.
    pub oversample: usize,
    /// N, string grid intervals over the 668 mm string.
    pub intervals: usize,
    /// Barrier grid spacings relative to the seed's (0.18 mm bridge, 0.15 mm thread).
    pub barrier_spacing_scale: f64,
    pub newton: NewtonSettings,
    pub solver: SolverKind,
}

impl Quality {
    pub const ALL: [Quality; 4] = [
        Quality::Draft,
        Quality::Live,
        Quality::Studio,
        Quality::Reference,
    ];

    pub fn tier(self) -> Tier {
        match self {
            Quality::Draft => Tier {
                oversample: 1,
                intervals: 50,
                barrier_spacing_scale: 4.0,
                newton: NewtonSettings {
                    tolerance_m: 1e-12,
                    max_iterations: 30,
                },
                solver: SolverKind::Condensed,
            },
            Quality::Live => Tier {
                oversample: 2,
                intervals: 100,
                barrier_spacing_scale: 2.0,
                newton: NewtonSettings {
                    tolerance_m: 1e-12,
                    max_iterations: 30,
                },
                solver: SolverKind::Condensed,
            },
            Quality::Studio => Tier {
                oversample: 2,
                intervals: 200,
                barrier_spacing_scale: 1.0,
                newton: NewtonSettings {
                    tolerance_m: 1e-12,
                    max_iterations: 30,
                },
                solver: SolverKind::Condensed,
            },
            Quality::Reference => Tier {
                oversample: 4,
                intervals: 200,
                barrier_spacing_scale: 1.0,
                newton: NewtonSettings::REFERENCE,
                solver: SolverKind::Condensed,
            },
        }
    }

    /// Position in [`Quality::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            Quality::Draft => "draft",
            Quality::Live => "live",
            Quality::Studio => "studio",
            Quality::Reference => "reference",
        }
    }

    /// Parses a tier name as printed by [`Quality::name`].
    pub fn from_name(name: &str) -> Option<Quality> {
        Quality::ALL
            .into_iter()
            .find(|quality| quality.name() == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_index_follows_order() {
        for (index, quality) in Quality::ALL.into_iter().enumerate() {
            assert_eq!(Quality::from_name(quality.name()), Some(quality));
            assert_eq!(quality.index(), index);
        }
        assert_eq!(Quality::from_name("ultra"), None);
    }

    #[test]
    fn reference_is_the_seed_discretisation() {
        let tier = Quality::Reference.tier();
        assert_eq!(tier.oversample, 4);
        assert_eq!(tier.intervals, 200);
        assert_eq!(tier.barrier_spacing_scale, 1.0);
        assert_eq!(tier.newton, NewtonSettings::REFERENCE);
    }

    #[test]
    fn tiers_get_cheaper_in_order() {
        let cost = |q: Quality| {
            let tier = q.tier();
            tier.oversample as f64 * tier.intervals as f64 / tier.barrier_spacing_scale.sqrt()
        };
        for pair in Quality::ALL.windows(2) {
            assert!(cost(pair[0]) < cost(pair[1]), "{pair:?}");
        }
    }
}
