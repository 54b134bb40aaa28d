//! Quality tiers: which discretisation a tanpura voice runs, and at what resolution.
//!
//! - Live and Fine run the modal scheme (`modal/`, `docs/modal-tanpura.md`): the string's
//!   eigenmodes advanced by exact two-pole recursions at the output rate (exact partials and decay
//!   rates, no oversampling, no decimator, no latency), in f32 over the modes, with the contact
//!   force on a few points of the bridge and thread solved by Newton in f64. Live keeps the modes
//!   below 20 kHz, a point every 2 mm of the bridge and every half millimetre of the thread. The
//!   string rests on the thread, so the thread's points shape every note. The bridge's points
//!   matter only where the vibrating string reaches the crest, and between points 2 mm apart the
//!   bridge's parabola (radius 0.1 m) lies at most 5 µm from its chord. Points every 2 mm instead
//!   of 1 mm make the live string 17–23 % faster and leave its playing-range figures within the
//!   measures' own spread: mean changes of 0.01 cents and 0.05 dB, at most 0.13 cents and 1.4 dB
//!   at one pluck (`docs/performance.md`, stop 29).
//! - The draft tier (live's scheme with the modes below 10 kHz and the thread's points every
//!   millimetre) was withdrawn in stop 62: its bridge never fed the upper band, at any key
//!   measured, so it played no jawari (`docs/modal-tanpura.md` §14), and the falling formant's
//!   signature test, which holds every other tier, could not hold it. A preset or a saved plugin
//!   state that names it plays live ([`Quality::withdrawn`]).
//! - Fine runs the modal scheme on the reference's own grid (`docs/modal-tanpura.md` §10–11): every
//!   mode of the seed's FD grid (N = 200, the 199 sampled sines with the frequencies and decays
//!   of its trapezoidal rule at 4× the output rate), advanced exactly at the output rate, with the
//!   contact points the reference's own barrier points (every 0.18 mm of the bridge and 0.15 mm of
//!   the thread, on the FD grids' lattices) seen through the FD's cubic interpolation and solved
//!   on the 11 grid nodes they reach (`modal/nodal.rs`), the rest state, the finger's press and
//!   the tuning too (`modal/nodal_statics.rs`). It is the reference's string in space and its
//!   partials in time, at a modal tier's cost; its jawari is set on the reference's
//!   (`as_played::jawari_set_on`). The points must be the reference's, not only as fine: at key
//!   63's softest pluck the seed's grid feeds the 4th partial through the crest's grazing contact
//!   with its points and not with points half a spacing away, and the fine string follows it on
//!   the same points (`docs/modal-tanpura.md` §10, stop 50; worst pluck of the playing range,
//!   linearised tuning: 5.68 dB against 7.74 dB with points every 0.36 / 0.2 mm from the fine
//!   string's own start, median 1.28 against 1.97 dB, for 18–26 % of the tier's speed).
//! - Studio runs the fine tier's string stepped at the reference's own step, four times the
//!   output rate (its grid modes then step with the very poles they were given; the contact is
//!   solved every quarter output sample), decimated by the reference's Kaiser filter
//!   (`fd/decimator.rs`, 29 samples of latency at 44.1 kHz, as the reference's). What parts the
//!   fine tier from the reference at its worst plucks is the contact's time step: at key 53,
//!   bistable at hard plucks, the string stepped at twice the output rate (the studio of stops
//!   57–58) lay up to 2.52 cents from the reference (velocity 115), and at four times it within
//!   0.15 cents at every velocity 88–127 (`docs/modal-tanpura.md` §13, stop 58); over the
//!   playing range's 180 plucks it lies 0.32 cents, 0.75 dB and 2.1 % from the reference at
//!   worst (stop 59). It costs about twice the 2× string's time and runs at 1.7–1.8 times the
//!   reference's speed. Until stop 57 the studio tier was the seed's FD scheme at 3 × 44.1 kHz
//!   (with its EI raised to match the reference's dispersion): 4.9 dB at worst and 4.5× real
//!   time per string, slower and less accurate than the modal string, so it was replaced
//!   (`docs/tiers-log.md`, stop 57).
//! - Reference runs the seed's finite-difference scheme (`fd/`), its own discretisation
//!   (section 5: 4 × 44.1 kHz, Δx = 3⅓ mm, Δx_b = 0.18 mm, Δx_c = 0.15 mm) with a tolerance at
//!   round-off.
//!
//! Every tier keeps its scheme's exact discrete energy balance; the balance holds only for a
//! converged Newton: a tolerance of 1e-8 m let an FD tier's energy grow by 0.3 % per step at
//! k_b = 1e12 N/m² (found by `tests/tanpura_extremes.rs`), so every tier iterates to 1e-12 m or
//! tighter, with a cap of 30 updates. What each tier costs and how far it lands from the
//! reference is measured by `cargo xtask bench`.

use crate::newton::NewtonSettings;
use crate::tanpura::fd::SolverKind;
use crate::tanpura::modal::GridModes;

/// The four tiers, cheapest first; Fine is the plugin's default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Quality {
    Live,
    #[default]
    Fine,
    Studio,
    Reference,
}

/// The numerical choices of one modal tier.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalTier {
    /// Modes are kept below this frequency (and below 0.45 of the sample rate), Hz.
    pub highest_mode_hz: f64,
    /// Contact point spacing on the bridge and on the thread, m.
    pub bridge_point_spacing_m: f64,
    pub thread_point_spacing_m: f64,
    pub newton: NewtonSettings,
    /// Take the reference's FD grid's modes with the contact condensed on its nodes
    /// (`modal/nodal.rs`) instead of the continuous string's modes.
    pub grid_modes: bool,
    /// Steps per output sample: the contact is solved at this multiple of the output rate and
    /// the pickup decimated by the reference's Kaiser filter (`fd/decimator.rs`); 1 runs at the
    /// output rate with no decimator and no latency.
    pub oversample: usize,
}

/// The numerical choices of one finite-difference tier.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdTier {
    /// Internal rate / output rate.
    pub oversample: usize,
    /// N, string grid intervals over the 668 mm string.
    pub intervals: usize,
    pub newton: NewtonSettings,
    pub solver: SolverKind,
}

/// The discretisation of one tier with its resolution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tier {
    Modal(ModalTier),
    FiniteDifference(FdTier),
}

/// The reference tier's grid as modes for a modal string at `output_sample_rate_hz`: its
/// intervals, and the time step of its oversampled trapezoidal rule; the contact condensed on
/// the grid's nodes (`docs/modal-tanpura.md` §10–11). The fine tier's modes.
pub fn reference_grid_modes(output_sample_rate_hz: f64) -> GridModes {
    let (intervals, oversample) = Quality::Reference
        .fd_tier()
        .map_or((200, 4), |tier| (tier.intervals, tier.oversample));
    GridModes {
        intervals,
        time_step_s: 1.0 / (output_sample_rate_hz * oversample as f64),
        condensed: true,
    }
}

/// The seed's time step: four steps per output sample (its section 5, at 44.1 kHz). The reference
/// steps its FD scheme at it, and the studio tier the fine tier's string.
const REFERENCE_OVERSAMPLE: usize = 4;

/// The fine tier: the reference's grid modes and barrier points, stepped at the output rate.
/// The studio tier is the same string stepped at the reference's step.
const FINE_GRID: ModalTier = ModalTier {
    highest_mode_hz: 20_000.0,
    bridge_point_spacing_m: 0.18e-3,
    thread_point_spacing_m: 0.15e-3,
    newton: TIER_NEWTON,
    grid_modes: true,
    oversample: 1,
};

/// Newton's tolerance and cap in every tier but the reference.
const TIER_NEWTON: NewtonSettings = NewtonSettings {
    tolerance_m: 1e-12,
    max_iterations: 30,
};

impl Quality {
    pub const ALL: [Quality; 4] = [
        Quality::Live,
        Quality::Fine,
        Quality::Studio,
        Quality::Reference,
    ];

    pub fn tier(self) -> Tier {
        match self {
            Quality::Live => Tier::Modal(ModalTier {
                highest_mode_hz: 20_000.0,
                bridge_point_spacing_m: 2e-3,
                thread_point_spacing_m: 0.5e-3,
                newton: TIER_NEWTON,
                grid_modes: false,
                oversample: 1,
            }),
            Quality::Fine => Tier::Modal(FINE_GRID),
            Quality::Studio => Tier::Modal(ModalTier {
                oversample: REFERENCE_OVERSAMPLE,
                ..FINE_GRID
            }),
            Quality::Reference => Tier::FiniteDifference(FdTier {
                oversample: REFERENCE_OVERSAMPLE,
                intervals: 200,
                newton: NewtonSettings::REFERENCE,
                solver: SolverKind::Condensed,
            }),
        }
    }

    /// The FD tier's numerical choices, `None` for a modal tier.
    pub fn fd_tier(self) -> Option<FdTier> {
        match self.tier() {
            Tier::FiniteDifference(tier) => Some(tier),
            Tier::Modal(_) => None,
        }
    }

    /// The modal tier's numerical choices, `None` for an FD tier.
    pub fn modal_tier(self) -> Option<ModalTier> {
        match self.tier() {
            Tier::Modal(tier) => Some(tier),
            Tier::FiniteDifference(_) => None,
        }
    }

    /// Internal steps per output sample.
    pub fn oversample(self) -> usize {
        match self.tier() {
            Tier::FiniteDifference(tier) => tier.oversample,
            Tier::Modal(tier) => tier.oversample,
        }
    }

    /// Position in [`Quality::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            Quality::Live => "live",
            Quality::Fine => "fine",
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

    /// The tier that plays a withdrawn tier's name ([`WITHDRAWN_TIERS`]) where a file saved by an
    /// earlier version holds it (a preset, the plugin's state); `None` for any other name.
    pub fn withdrawn(name: &str) -> Option<Quality> {
        WITHDRAWN_TIERS
            .into_iter()
            .find_map(|(withdrawn, quality)| (withdrawn == name).then_some(quality))
    }
}

/// Tiers withdrawn from the instrument, by the name files saved before then hold, with the tier
/// that plays them now. Draft (stop 62): live's scheme on fewer modes, without the jawari; live
/// is the cheapest tier that plays it.
pub const WITHDRAWN_TIERS: [(&str, Quality); 1] = [("draft", Quality::Live)];

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
        let tier = Quality::Reference.fd_tier().unwrap();
        assert_eq!(tier.oversample, 4);
        assert_eq!(tier.intervals, 200);
        // The seed's barrier grids: 0.18 mm on the bridge, 0.15 mm on the thread.
        let config = crate::tanpura::VoiceSettings::default()
            .fd_config_at(Quality::Reference, 44_100.0)
            .unwrap();
        assert_eq!(config.bridge.spacing_m, 0.18e-3);
        assert_eq!(config.thread.unwrap().spacing_m, 0.15e-3);
        assert_eq!(tier.newton, NewtonSettings::REFERENCE);
    }

    #[test]
    fn fast_tiers_are_modal_at_the_output_rate() {
        assert!(Quality::Live.modal_tier().is_some());
        assert!(Quality::Fine.modal_tier().is_some());
        assert_eq!(Quality::Live.oversample(), 1);
        assert_eq!(Quality::Fine.oversample(), 1);
    }

    /// A file saved while the draft tier existed loads with the live tier, and the withdrawn
    /// name is no tier's name today (so nothing writes it again).
    #[test]
    fn the_withdrawn_draft_tier_reads_as_live() {
        assert_eq!(Quality::from_name("draft"), None);
        assert_eq!(Quality::withdrawn("draft"), Some(Quality::Live));
        for quality in Quality::ALL {
            assert!(Quality::withdrawn(quality.name()).is_none());
        }
        assert_eq!(Quality::withdrawn("ultra"), None);
    }

    /// The studio tier is the fine tier's string (its grid modes with the poles of the
    /// reference's time step, its points, its Newton) stepped at the reference's own step.
    #[test]
    fn studio_is_the_fine_string_at_the_references_step() {
        let fine = Quality::Fine.modal_tier().unwrap();
        let studio = Quality::Studio.modal_tier().unwrap();
        assert_eq!(
            studio,
            ModalTier {
                oversample: 4,
                ..fine
            }
        );
        assert_eq!(
            Quality::Studio.oversample(),
            Quality::Reference.oversample()
        );
        let settings = crate::tanpura::VoiceSettings::default();
        let rate = 44_100.0;
        let fine = settings.modal_config_at(Quality::Fine, rate).unwrap();
        let studio = settings.modal_config_at(Quality::Studio, rate).unwrap();
        assert_eq!(studio.time_step_s, 0.25 / rate);
        let grid = reference_grid_modes(rate);
        assert_eq!(studio.grid_modes, Some(grid));
        assert_eq!(studio.time_step_s, grid.time_step_s);
        assert_eq!(
            crate::tanpura::modal::ModalStringConfig {
                time_step_s: fine.time_step_s,
                ..studio
            },
            fine
        );
    }

    #[test]
    fn fine_is_the_default_and_runs_the_reference_grid_on_its_nodes() {
        assert_eq!(Quality::default(), Quality::Fine);
        let fine = Quality::Fine.modal_tier().unwrap();
        assert!(fine.grid_modes);
        assert!(!Quality::Live.modal_tier().unwrap().grid_modes);
        let grid = reference_grid_modes(48_000.0);
        let reference = Quality::Reference.fd_tier().unwrap();
        assert_eq!(grid.intervals, reference.intervals);
        assert_eq!(
            grid.time_step_s,
            1.0 / (48_000.0 * reference.oversample as f64)
        );
        assert!(grid.condensed && grid.is_valid());
        let settings = crate::tanpura::VoiceSettings::default();
        let config = settings.modal_config_at(Quality::Fine, 48_000.0).unwrap();
        assert_eq!(config.grid_modes, Some(grid));
        let string = crate::tanpura::modal::ModalString::<f32>::new(config);
        assert_eq!(string.modes().count(), reference.intervals - 1);
        assert!(
            string.contact_node_count() > 0,
            "the contact is on the nodes"
        );
    }
}
