//! MIDI note numbers to string pitch: twelve-tone equal temperament with A4 (note 69) = 440 Hz.
//!
//! `f = 440 Hz · 2^((n − 69)/12)`. Notes whose pitch falls outside the tanpura voice's range
//! ([`VoiceSettings::FUNDAMENTAL_RANGE_HZ`], 20–2000 Hz, i.e. notes 16 to 95) are not played:
//! a string tuned outside that range is not the instrument any more.

use crate::tanpura::VoiceSettings;

/// Pitch of MIDI note 69 (A4), Hz.
pub const A4_HZ: f64 = 440.0;
/// MIDI note number of A4.
pub const A4_NOTE: u8 = 69;

/// The equal-tempered pitch of a MIDI note, Hz.
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
    fn cents_of_a_semitone_is_100() {
        assert!((cents(note_to_hz(61), note_to_hz(60)) - 100.0).abs() < 1e-9);
    }
}
