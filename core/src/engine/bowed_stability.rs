//! Whether a bowed preset plays stable Helmholtz motion: Woodhouse's linear analysis (seed 001,
//! `stability/voice_link.rs`) applied to the engine's bowed settings at a given note, for the
//! warnings of `cargo xtask render` and `cargo xtask stability --preset`.
//!
//! The bow controls are the preset's own (pressure, bow speed, bow position); the bow force is
//! what the instrument applies for them, `F_b = F_max(v_b, β) · (0.05 + 0.75 p)`
//! (`bowed/instrument.rs`).

use super::{pitch, BowedEngineSettings};
use crate::bowed::instrument::{force_fraction_from_pressure, schelleng_max_force_n};
use crate::stability::{voice_stability_margin, StabilityError, VoiceSetting};

/// The verdict for one note.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BowedStability {
    pub note: u8,
    /// The bow force the preset applies at that note, N.
    pub bow_force_n: f64,
    /// The largest stable bow force, N (None when no threshold was found).
    pub critical_bow_force_n: Option<f64>,
    /// F_crit / F_b: above 1 stable.
    pub margin: f64,
    pub stable: bool,
}

/// The stability of `bowed`'s Helmholtz motion at `note`.
pub fn bowed_stability(
    bowed: &BowedEngineSettings,
    note: u8,
) -> Result<BowedStability, StabilityError> {
    let constants = bowed.string.constants();
    let pitch_hz = pitch::note_to_hz(note);
    let bow_force_n = schelleng_max_force_n(
        constants.wave_impedance_n_s_m(),
        bowed.bow_velocity_m_s,
        bowed.bow_position,
    ) * force_fraction_from_pressure(bowed.pressure);
    let setting = VoiceSetting::with_default_friction(
        constants,
        pitch_hz,
        bowed.bow_position,
        bow_force_n,
        bowed.bow_velocity_m_s,
    );
    let margin = voice_stability_margin(&setting)?;
    Ok(BowedStability {
        note,
        bow_force_n,
        critical_bow_force_n: margin.critical_bow_force_n,
        margin: margin.bow_force_margin,
        stable: margin.stable,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_violin_is_stable_and_a_heavy_bow_near_the_fingerboard_is_not() {
        let violin = BowedEngineSettings::default();
        let verdict = bowed_stability(&violin, 57).unwrap();
        assert!(verdict.stable && verdict.margin > 1.0, "{verdict:?}");
        // β = 0.2 at full pressure: 0.8 F_max, above the critical force the analysis finds
        // there (0.21 N at 0.1 m/s, `tests/stability_voice.rs`).
        let heavy = BowedEngineSettings {
            pressure: 1.0,
            bow_velocity_m_s: 0.1,
            bow_position: 0.2,
            ..violin
        };
        let verdict = bowed_stability(&heavy, 57).unwrap();
        assert!(!verdict.stable && verdict.margin < 1.0, "{verdict:?}");
    }
}
