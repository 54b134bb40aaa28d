//! How a tanpura string is set into motion: the finger pluck and the "first mode" shape.
//!
//! Source: seed 000, section 3 and 5.1. The finger is a third barrier (eq. 6c) with a
//! parabolic tip. A pluck presses it into the string (k_f > 0) until the string is in static
//! equilibrium against finger, bridge and thread, then releases it (k_f → 0), as the seed does.
//! The "first mode" excitation replaces the finger by the shape of the string's first mode over
//! its speaking length (the seed re-defines the finger's shape to get it).

/// A finger pluck, measured from the tuning-bead end of the string.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pluck {
    /// Where the finger's centre presses, m from the tuning bead (the string is 0.668 m long
    /// in the seed; the thread sits at 0.040 m).
    pub position_m: f64,
    /// Width of the fingertip, m: the tip is a parabola whose radius of curvature is half this
    /// width, so a wider finger bends the string less sharply (fewer high partials).
    pub width_m: f64,
    /// How far the finger lifts the string above its rest position at `position_m`, m.
    pub amplitude_m: f64,
}

impl Pluck {
    /// Valid ranges, in SI units: position along the speaking length, width 2–40 mm,
    /// amplitude 0–5 mm (the largest a tanpura string tolerates without hitting the neck).
    pub const WIDTH_RANGE_M: (f64, f64) = (0.002, 0.040);
    pub const AMPLITUDE_RANGE_M: (f64, f64) = (0.0, 0.005);

    /// The pluck with a NaN replaced by the default's value and width and amplitude clamped to
    /// their ranges (the position is clamped to the speaking length where the finger lands).
    /// A NaN width would otherwise reach `f64::clamp` as a bound, which panics.
    pub fn clamped(&self) -> Self {
        let default = Self::default();
        let or_default = |value: f64, fallback: f64| if value.is_nan() { fallback } else { value };
        Self {
            position_m: or_default(self.position_m, default.position_m),
            width_m: or_default(self.width_m, default.width_m)
                .clamp(Self::WIDTH_RANGE_M.0, Self::WIDTH_RANGE_M.1),
            amplitude_m: or_default(self.amplitude_m, default.amplitude_m)
                .clamp(Self::AMPLITUDE_RANGE_M.0, Self::AMPLITUDE_RANGE_M.1),
        }
    }
}

impl Default for Pluck {
    /// A pluck a player would make: 2 mm at 0.35 m (about mid speaking length) with a 10 mm
    /// fingertip.
    fn default() -> Self {
        Self {
            position_m: 0.35,
            width_m: 0.010,
            amplitude_m: 0.002,
        }
    }
}

/// The finger barrier's height at `x` for a tip centred at `centre_m` whose top is at `top_m`.
pub fn finger_height_m(x_m: f64, centre_m: f64, width_m: f64, top_m: f64) -> f64 {
    let radius_m = 0.5 * width_m;
    let offset = x_m - centre_m;
    top_m - offset * offset / (2.0 * radius_m)
}

/// The first-mode shape over the speaking length `[start_m, length_m]`: `sin(π ξ)` with `ξ` the
/// relative position on it, and zero on the bead side of `start_m`.
pub fn first_mode_shape(x_m: f64, start_m: f64, length_m: f64) -> f64 {
    if x_m <= start_m || x_m >= length_m {
        0.0
    } else {
        (std::f64::consts::PI * (x_m - start_m) / (length_m - start_m)).sin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finger_tip_is_a_parabola_of_radius_half_the_width() {
        let top = 1e-3;
        assert_eq!(finger_height_m(0.3, 0.3, 0.01, top), top);
        // At 5 mm from the centre with radius 5 mm: drop = 25e-6 / 10e-3 = 2.5 mm.
        let drop = top - finger_height_m(0.305, 0.3, 0.01, top);
        assert!((drop - 2.5e-3).abs() < 1e-15);
    }

    #[test]
    fn first_mode_peaks_mid_speaking_length_and_vanishes_at_its_ends() {
        assert_eq!(first_mode_shape(0.02, 0.04, 0.668), 0.0);
        assert!(first_mode_shape(0.04, 0.04, 0.668).abs() < 1e-15);
        assert!((first_mode_shape(0.354, 0.04, 0.668) - 1.0).abs() < 1e-12);
        assert_eq!(first_mode_shape(0.668, 0.04, 0.668), 0.0);
    }
}
