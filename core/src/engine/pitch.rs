//! MIDI note numbers to string pitch: twelve-tone equal temperament with A4 (note 69) = 440 Hz,
//! or any reference pitch and fine tuning a player sets ([`Tuning`]).
//!
//! `f = A4 · 2^((n − 69)/12 + c/1200)`, A4 = 415–466 Hz (baroque to high modern pitch), the fine
//! tuning c = ±100 cents (so Sa can sit anywhere between two notes). Notes whose pitch falls outside the tanpura voice's range
//! ([`VoiceSettings::FUNDAMENTAL_RANGE_HZ`], 20–2000 Hz, i.e. notes 16 to 95) are not played:
//! a string tuned outside that range is not the instrument any more.

use crate::tanpura::VoiceSettings;

/// Pitch of MIDI note 69 (A4), Hz.
pub const A4_HZ: f64 = 440.0;
/// MIDI note number of A4.
pub const A4_NOTE: u8 = 69;

/// Valid reference pitch range, Hz, and fine tuning range, cents.
pub const A4_RANGE_HZ: (f64, f64) = (415.0, 466.0);
pub const FINE_TUNE_RANGE_CENTS: (f64, f64) = (-100.0, 100.0);

/// How MIDI notes become pitches: the reference pitch of A4 and a fine tuning of every note.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    pub a4_hz: f64,
    pub fine_tune_cents: f64,
    /// Tune each string by its sustained pitch as played (`tanpura/as_played.rs`) where a
    /// calibration is at hand; off: by its small-amplitude linearisation only.
    pub as_played: bool,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            a4_hz: A4_HZ,
            fine_tune_cents: 0.0,
            as_played: true,
        }
    }
}

impl Tuning {
    /// The pitch of `note`, Hz (values outside the ranges are clamped; NaN takes the default).
    pub fn note_hz(&self, note: u8) -> f64 {
        let a4 = if self.a4_hz.is_nan() {
            A4_HZ
        } else {
            self.a4_hz.clamp(A4_RANGE_HZ.0, A4_RANGE_HZ.1)
        };
        let cents = if self.fine_tune_cents.is_nan() {
            0.0
        } else {
            self.fine_tune_cents
                .clamp(FINE_TUNE_RANGE_CENTS.0, FINE_TUNE_RANGE_CENTS.1)
        };
        a4 * ((f64::from(note) - f64::from(A4_NOTE)) / 12.0 + cents / 1200.0).exp2()
    }

    /// [`Tuning::note_hz`] if a tanpura string can be tuned there.
    pub fn playable_note_hz(&self, note: u8) -> Option<f64> {
        let hz = self.note_hz(note);
        let (low, high) = VoiceSettings::FUNDAMENTAL_RANGE_HZ;
        (low..=high).contains(&hz).then_some(hz)
    }
}

/// The equal-tempered pitch of a MIDI note at A4 = 440 Hz, Hz.
pub fn note_to_hz(note: u8) -> f64 {
    A4_HZ * ((f64::from(note) - f64::from(A4_NOTE)) / 12.0).exp2()
}

/// The pitch of `note` if a tanpura string can be tuned to it.
pub fn playable_note_hz(note: u8) -> Option<f64> {
    let hz = note_to_hz(note);
    let (low, high) = VoiceSettings::FUNDAMENTAL_RANGE_HZ;
    (low..=high).contains(&hz).then_some(hz)
}

/// Distance between two frequencies in cents (positive when `measured_hz` is sharp).
pub fn cents(measured_hz: f64, expected_hz: f64) -> f64 {
    1200.0 * (measured_hz / expected_hz).log2()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a4_is_440_and_octaves_double() {
        assert_eq!(note_to_hz(69), 440.0);
        assert_eq!(note_to_hz(81), 880.0);
        assert_eq!(note_to_hz(57), 220.0);
        // Middle C: 440 · 2^(−9/12) = 261.6255653 Hz.
        assert!((note_to_hz(60) - 261.625_565_300_6).abs() < 1e-9);
    }

    #[test]
    fn playable_range_follows_the_voice_range() {
        assert!(playable_note_hz(15).is_none()); // 19.4 Hz
        assert!(playable_note_hz(16).is_some()); // 20.6 Hz
        assert!(playable_note_hz(95).is_some()); // 1975.5 Hz
        assert!(playable_note_hz(96).is_none()); // 2093.0 Hz
    }

    #[test]
    fn reference_pitch_and_fine_tuning_move_every_note() {
        let baroque = Tuning {
            a4_hz: 415.0,
            fine_tune_cents: 0.0,
            as_played: true,
        };
        assert_eq!(baroque.note_hz(69), 415.0);
        // 415 Hz is 101.4 cents below 440 Hz, for every note.
        let shift = 1200.0 * (415.0f64 / 440.0).log2();
        assert!((cents(baroque.note_hz(48), note_to_hz(48)) - shift).abs() < 1e-9);
        let raised = Tuning {
            a4_hz: 440.0,
            fine_tune_cents: 37.0,
            as_played: true,
        };
        assert!((cents(raised.note_hz(50), note_to_hz(50)) - 37.0).abs() < 1e-9);
        assert_eq!(Tuning::default().note_hz(60), note_to_hz(60));
        let wild = Tuning {
            a4_hz: f64::NAN,
            fine_tune_cents: 1e9,
            as_played: true,
        };
        assert!((cents(wild.note_hz(60), note_to_hz(60)) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn cents_of_a_semitone_is_100() {
        assert!((cents(note_to_hz(61), note_to_hz(60)) - 100.0).abs() < 1e-9);
    }
}
