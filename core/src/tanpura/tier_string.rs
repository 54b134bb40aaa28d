//! The string of one quality tier, whichever its discretisation: the seed's FD scheme
//! ([`FdString`], the reference) or the modal scheme ([`ModalString`] in f32: live, fine and
//! studio). A plain enum, so the voice dispatches with one branch per call and no allocation or
//! indirection on the audio thread; everything the voice, the engine and the tests read of a
//! string is here.

use super::excitation::Pluck;
use super::fd::FdString;
use super::modal::ModalString;
use super::string::StringParameters;
use crate::newton::NewtonStats;

/// The pickup signal from a step's force changes at nut and bridge, N:
/// `w · ΔF_nut + (1 − w) · ΔF_bridge` with `w = nut_weight`.
#[inline(always)]
pub fn weighted_pickup_n(nut_weight: f64, nut_change_n: f64, bridge_change_n: f64) -> f64 {
    nut_weight * nut_change_n + (1.0 - nut_weight) * bridge_change_n
}

/// The string a tier runs.
#[derive(Debug, Clone)]
pub enum TierString {
    /// Both boxed (the strings differ in size by kilobytes); the boxes are made once, when the
    /// voice is built.
    FiniteDifference(Box<FdString>),
    Modal(Box<ModalString<f32>>),
}

impl TierString {
    pub fn as_fd(&self) -> Option<&FdString> {
        match self {
            TierString::FiniteDifference(string) => Some(string),
            TierString::Modal(_) => None,
        }
    }

    pub fn as_modal(&self) -> Option<&ModalString<f32>> {
        match self {
            TierString::Modal(string) => Some(string),
            TierString::FiniteDifference(_) => None,
        }
    }

    /// Advances one internal step (one output sample for a modal string).
    pub fn step(&mut self) {
        match self {
            TierString::FiniteDifference(string) => string.step(),
            TierString::Modal(string) => string.step(),
        }
    }

    pub fn pluck(&mut self, pluck: &Pluck) {
        match self {
            TierString::FiniteDifference(string) => string.pluck(pluck),
            TierString::Modal(string) => string.pluck(pluck),
        }
    }

    pub fn excite_first_mode(&mut self, amplitude_m: f64) {
        match self {
            TierString::FiniteDifference(string) => string.excite_first_mode(amplitude_m),
            TierString::Modal(string) => string.excite_first_mode(amplitude_m),
        }
    }

    pub fn reset(&mut self) {
        match self {
            TierString::FiniteDifference(string) => string.reset(),
            TierString::Modal(string) => string.reset(),
        }
    }

    pub fn settle_to_rest(&mut self) {
        match self {
            TierString::FiniteDifference(string) => string.settle_to_rest(),
            TierString::Modal(string) => string.settle_to_rest(),
        }
    }

    pub fn linearised_fundamental_hz(&mut self) -> f64 {
        match self {
            TierString::FiniteDifference(string) => string.linearised_fundamental_hz(),
            TierString::Modal(string) => string.linearised_fundamental_hz(),
        }
    }

    /// The pickup signal: `w` · (nut force change) + (1 − w) · (bridge force change), N.
    pub fn pickup_n(&self, nut_weight: f64) -> f64 {
        let (nut, bridge) = match self {
            TierString::FiniteDifference(string) => (
                string.nut_force_n() - string.rest_nut_force_n(),
                string.bridge_force_n() - string.rest_bridge_force_n(),
            ),
            TierString::Modal(string) => {
                (string.nut_force_change_n(), string.bridge_force_change_n())
            }
        };
        weighted_pickup_n(nut_weight, nut, bridge)
    }

    /// The string's physical constants as configured (the tuned tension included).
    pub fn parameters(&self) -> &StringParameters {
        match self {
            TierString::FiniteDifference(string) => &string.config().string,
            TierString::Modal(string) => &string.config().string,
        }
    }

    /// The unit round-off of the arithmetic the string's state is carried in (f64 for FD, f32
    /// for the modal tiers' modes).
    pub fn unit_round_off(&self) -> f64 {
        match self {
            TierString::FiniteDifference(_) => f64::EPSILON / 2.0,
            TierString::Modal(_) => f64::from(f32::EPSILON) / 2.0,
        }
    }

    /// Internal time step, s.
    pub fn time_step_s(&self) -> f64 {
        match self {
            TierString::FiniteDifference(string) => string.config().time_step_s,
            TierString::Modal(string) => string.config().time_step_s,
        }
    }
}

/// Accessors with the same name and meaning in both discretisations.
macro_rules! forward {
    ($($(#[$doc:meta])* $name:ident -> $out:ty;)*) => {
        impl TierString {
            $(
                $(#[$doc])*
                pub fn $name(&self) -> $out {
                    match self {
                        TierString::FiniteDifference(string) => string.$name(),
                        TierString::Modal(string) => string.$name(),
                    }
                }
            )*
        }
    };
}

forward! {
    /// The discrete energy H, J.
    energy_j -> f64;
    /// H at the rest state, J.
    rest_energy_j -> f64;
    /// The energy above the rest state, J (what decides sleep).
    vibration_energy_j -> f64;
    nut_force_n -> f64;
    bridge_force_n -> f64;
    rest_nut_force_n -> f64;
    rest_bridge_force_n -> f64;
    cumulative_losses_j -> f64;
    external_work_j -> f64;
    max_penetration_m -> f64;
    static_solve_failures -> u64;
    non_finite_resets -> u64;
    rest_contact_end_m -> Option<f64>;
}

impl TierString {
    pub fn newton_stats(&self) -> &NewtonStats {
        match self {
            TierString::FiniteDifference(string) => string.newton_stats(),
            TierString::Modal(string) => string.newton_stats(),
        }
    }
}
