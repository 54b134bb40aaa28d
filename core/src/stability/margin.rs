//! Stability margin of the Helmholtz motion of a bowed setting: the link from the analysis of
//! seed 001 to the bowed voice (`shared/notes/bowed-model.md`), for warnings on unstable presets.
//!
//! The setting is expressed on the analysis grid of the compact formulation (section 3.1): the
//! bow divides one period into p steps on the bridge side and q on the finger side (β = p/(p + q)),
//! and each side's reflection function is sampled on that grid (a Raman tap −λ, the three-tap
//! rounded corner of eq. 22, or any discrete pulse). The friction curve enters through its slope at
//! the Helmholtz operating point, k = dμ/dv (s/m) with f = F_b μ(v), and the bow force F_b (N);
//! Y₀ = 1/Z₀ is the string's wave admittance (s/kg).
//!
//! ζ(F_b) is eq. 3 in its exact form, `ζ = k F_b Y₀ / (2 − k F_b Y₀)`: it is what a bow junction
//! that solves its friction-curve intersection exactly gives when linearised (the transient
//! cross-check of section 2.5 grows at exactly the eigenvalue this ζ gives). The seed's own section
//! 2.5 thresholds (1.75 and 77.2) use the proportional form `ζ = k F_b Y₀/2` instead; the exact
//! form puts them at 1.7216 and 43.56 (see `docs/stability.md`). The
//! margin is F_b,crit / F_b: above 1 the Helmholtz motion is stable, below 1 it is not.

use super::compact::{CompactModel, ReflectionFunction};
use super::pattern::ContactPattern;
use super::spectrum::Eigenvalue;
use super::threshold::{PeriodicMotion, ThresholdOutcome, ThresholdSearch, UNIT_CIRCLE_SLACK};
use super::{bow_force_from_zeta, zeta_from_friction_slope, StabilityError};

/// A bowed setting on the analysis grid.
#[derive(Debug, Clone, PartialEq)]
pub struct BowedSetting {
    /// Steps of the bridge-side round trip (β = p/(p + q)).
    pub p: usize,
    /// Steps of the finger-side round trip.
    pub q: usize,
    /// Bridge-side reflection function, sign included (Raman: `−λ` at delay p).
    pub bridge_reflection: ReflectionFunction,
    /// Finger-side reflection function, sign included (Raman: `−λ` at delay q).
    pub finger_reflection: ReflectionFunction,
    /// Sticking reflection magnitude γ (eq. 6), 1 without torsion, 0 ≤ γ ≤ 1.
    pub sticking_gamma: f64,
    /// k = dμ/dv of the friction curve at the Helmholtz slipping velocity, s/m (> 0 falling).
    pub friction_slope_s_per_m: f64,
    /// Bow normal force F_b, N (> 0).
    pub bow_force_n: f64,
    /// String wave admittance Y₀ = 1/Z₀, s/kg (> 0).
    pub admittance_s_per_kg: f64,
    /// Slipping steps per period; `None` for the Helmholtz value p.
    pub slip_steps: Option<usize>,
}

impl BowedSetting {
    /// Raman's model (one tap −λ per side) at β = p/(p + q).
    #[allow(clippy::too_many_arguments)]
    pub fn raman(
        p: usize,
        q: usize,
        lambda: f64,
        sticking_gamma: f64,
        friction_slope_s_per_m: f64,
        bow_force_n: f64,
        admittance_s_per_kg: f64,
    ) -> Result<Self, StabilityError> {
        let model = CompactModel::raman(p, q, lambda)?;
        Ok(Self {
            p,
            q,
            bridge_reflection: model.left,
            finger_reflection: model.right,
            sticking_gamma,
            friction_slope_s_per_m,
            bow_force_n,
            admittance_s_per_kg,
            slip_steps: None,
        })
    }

    /// ζ of this setting by eq. 3 (exact form).
    pub fn zeta(&self) -> Result<f64, StabilityError> {
        zeta_from_friction_slope(
            self.friction_slope_s_per_m,
            self.bow_force_n,
            self.admittance_s_per_kg,
        )
        .ok_or_else(|| {
            StabilityError::InvalidParameter(format!(
                "friction slope x bow force x admittance = {} must be below 2 (eq. 2)",
                self.friction_slope_s_per_m * self.bow_force_n * self.admittance_s_per_kg
            ))
        })
    }

    fn validate(&self) -> Result<(), StabilityError> {
        let positive = |value: f64, name: &str| {
            if value > 0.0 && value.is_finite() {
                Ok(())
            } else {
                Err(StabilityError::InvalidParameter(format!(
                    "{name}: {value} must be a positive finite number"
                )))
            }
        };
        positive(self.bow_force_n, "bow force")?;
        positive(self.admittance_s_per_kg, "admittance Y0")?;
        if !self.friction_slope_s_per_m.is_finite() {
            return Err(StabilityError::InvalidParameter(
                "friction slope: must be finite".into(),
            ));
        }
        if self.p == 0 || self.q == 0 {
            return Err(StabilityError::InvalidParameter(format!(
                "p and q: both must be at least 1 (got p = {}, q = {})",
                self.p, self.q
            )));
        }
        Ok(())
    }
}

/// The stability of a setting's Helmholtz motion.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityMargin {
    /// ζ at the setting's bow force (eq. 3).
    pub zeta: f64,
    /// Largest eigenvalue modulus at that ζ: the perturbation growth factor per period.
    pub spectral_radius: f64,
    /// The least stable eigenvalue at that ζ.
    pub least_stable: Eigenvalue,
    /// True when every eigenvalue lies inside the unit circle at the setting's ζ.
    pub stable: bool,
    /// Critical ζ, when an eigenvalue leaves the unit circle for ζ up to the search's maximum.
    pub zeta_critical: Option<f64>,
    /// The bow force at the critical ζ (eq. 3 inverted), N; `None` when there is no crossing or
    /// when the friction slope is not positive (then ζ ≤ 0 and no bow force reaches it).
    pub critical_bow_force_n: Option<f64>,
    /// F_b,crit / F_b: above 1 stable. Infinite when no crossing exists, 0 when even the
    /// smallest ζ searched is unstable.
    pub bow_force_margin: f64,
}

/// The stability margin of the Helmholtz motion (or the given slip time) of `setting`.
pub fn stability_margin(setting: &BowedSetting) -> Result<StabilityMargin, StabilityError> {
    setting.validate()?;
    let zeta = setting.zeta()?;
    let model = CompactModel::new(
        setting.bridge_reflection.clone(),
        setting.finger_reflection.clone(),
    );
    let slip_steps = setting.slip_steps.unwrap_or(setting.p);
    let pattern = ContactPattern::single_slip(setting.p + setting.q, slip_steps)?;
    let motion = PeriodicMotion::new(model, pattern, setting.sticking_gamma)?;
    let spectrum = motion.spectrum(zeta)?;
    let least_stable = spectrum[0];
    let outcome = ThresholdSearch::default().run(&motion)?;
    let zeta_critical = outcome.crossing().map(|threshold| threshold.zeta);
    let critical_bow_force_n = zeta_critical
        .filter(|_| setting.friction_slope_s_per_m > 0.0)
        .map(|critical| {
            bow_force_from_zeta(
                critical,
                setting.friction_slope_s_per_m,
                setting.admittance_s_per_kg,
            )
        });
    let bow_force_margin = match (&outcome, critical_bow_force_n) {
        (ThresholdOutcome::UnstableFrom { .. }, _) => 0.0,
        (_, Some(force)) => force / setting.bow_force_n,
        (_, None) => f64::INFINITY,
    };
    Ok(StabilityMargin {
        zeta,
        spectral_radius: least_stable.modulus,
        least_stable,
        stable: least_stable.modulus <= 1.0 + UNIT_CIRCLE_SLACK,
        zeta_critical,
        critical_bow_force_n,
        bow_force_margin,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn section_2_5(bow_force_n: f64) -> BowedSetting {
        BowedSetting::raman(2, 5, 0.99, 0.9, 0.01, bow_force_n, 2.0).unwrap()
    }

    #[test]
    fn margin_straddles_the_section_2_5_threshold() {
        let below = stability_margin(&section_2_5(1.5)).unwrap();
        assert!(below.stable);
        assert!(below.spectral_radius < 1.0);
        // Exact eq. 3: the critical force is 1.7216 N (the seed's 1.75 uses ζ = 0.01 F_b).
        let critical = below.critical_bow_force_n.unwrap();
        assert!((critical - 1.7216).abs() < 5e-5, "{critical}");
        assert!((below.bow_force_margin - critical / 1.5).abs() < 1e-12);
        assert_eq!(below.least_stable.subharmonic_order, 1);

        let above = stability_margin(&section_2_5(2.0)).unwrap();
        assert!(!above.stable);
        assert!(above.bow_force_margin < 1.0);
        assert!((above.zeta - 0.04 / 1.96).abs() < 1e-15);
    }

    #[test]
    fn rising_friction_curve_has_no_critical_force() {
        let mut setting = section_2_5(2.0);
        setting.friction_slope_s_per_m = -0.01;
        let margin = stability_margin(&setting).unwrap();
        assert!(margin.stable);
        assert_eq!(margin.critical_bow_force_n, None);
        assert_eq!(margin.bow_force_margin, f64::INFINITY);
    }

    #[test]
    fn bad_settings_name_the_field() {
        let mut setting = section_2_5(2.0);
        setting.bow_force_n = -1.0;
        assert!(stability_margin(&setting)
            .unwrap_err()
            .to_string()
            .contains("bow force"));
        let mut setting = section_2_5(2.0);
        setting.friction_slope_s_per_m = 1.0;
        assert!(stability_margin(&setting)
            .unwrap_err()
            .to_string()
            .contains("below 2"));
    }
}
