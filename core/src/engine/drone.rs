//! Drone mode: a held note sets Sa and the four strings are plucked in the classic cycle.
//!
//! The strings are, in playing order, the first string (Pa, Ma or Ni of the lower octave:
//! [`FirstString::ratio`], 3/4, 2/3 or 15/16 of Sa), Sa, Sa and low Sa (1/2). A tanpura player
//! plucks them evenly and lets the low Sa ring a little longer before starting again, so the
//! gaps after each pluck are 1, 1, 1 and 2 beats ([`CYCLE_GAPS_BEATS`], a cycle of five beats).
//! The beat follows the host's tempo when tempo sync is on (or a free tempo otherwise).
//!
//! The sequencer only decides *when* and *which* string; the engine turns that into plucks.
//! Times are absolute sample indices, so the cycle does not depend on how the host splits its
//! blocks.

use crate::tanpura::FirstString;

/// Gap after each string's pluck, in beats: string 1, Sa, Sa, low Sa.
pub const CYCLE_GAPS_BEATS: [f64; 4] = [1.0, 1.0, 1.0, 2.0];
/// Number of drone strings.
pub const DRONE_STRINGS: usize = 4;
/// Valid drone tempo range, beats per minute.
pub const TEMPO_RANGE_BPM: (f64, f64) = (20.0, 300.0);

/// How the drone is played, in musician's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DroneSettings {
    /// On: a held note sets Sa and the strings are plucked automatically; off: each note plucks
    /// its own string.
    pub enabled: bool,
    pub first_string: FirstString,
    /// Follow the host's tempo when it reports one.
    pub tempo_sync: bool,
    /// Beats per minute used without sync or when the host reports no tempo (20–300).
    pub free_tempo_bpm: f64,
}

impl Default for DroneSettings {
    fn default() -> Self {
        Self {
            enabled: false,
            first_string: FirstString::Pa,
            tempo_sync: true,
            free_tempo_bpm: 60.0,
        }
    }
}

/// Frequency ratio of each drone string to Sa, in playing order.
pub fn string_ratios(first_string: FirstString) -> [f64; DRONE_STRINGS] {
    [first_string.ratio(), 1.0, 1.0, 0.5]
}

/// The held-note memory and the cycle's clock. Allocation-free.
#[derive(Debug, Clone)]
pub struct DroneSequencer {
    /// For each MIDI note: 0 when not held, else the order in which it was pressed.
    held_order: [u64; 128],
    press_counter: u64,
    /// Absolute time of the next pluck in samples (fractional: beats need not be whole samples).
    next_pluck_time: Option<f64>,
    next_string: usize,
}

impl Default for DroneSequencer {
    fn default() -> Self {
        Self {
            held_order: [0; 128],
            press_counter: 0,
            next_pluck_time: None,
            next_string: 0,
        }
    }
}

impl DroneSequencer {
    /// A note is pressed at absolute sample `now`. Starting from silence, the cycle begins with
    /// the first string at that very sample.
    pub fn note_on(&mut self, note: u8, now: u64) {
        let was_idle = self.sa_note().is_none();
        self.press_counter += 1;
        self.held_order[usize::from(note & 0x7f)] = self.press_counter;
        if was_idle {
            self.next_pluck_time = Some(now as f64);
            self.next_string = 0;
        }
    }

    /// A note is released; when no note is held any more the cycle stops (the strings ring on).
    pub fn note_off(&mut self, note: u8) {
        self.held_order[usize::from(note & 0x7f)] = 0;
        if self.sa_note().is_none() {
            self.next_pluck_time = None;
        }
    }

    /// Releases every note.
    pub fn all_notes_off(&mut self) {
        self.held_order = [0; 128];
        self.next_pluck_time = None;
    }

    /// The note that sets Sa: the most recently pressed of the held notes.
    pub fn sa_note(&self) -> Option<u8> {
        let (note, order) = self
            .held_order
            .iter()
            .enumerate()
            .max_by_key(|(_, order)| **order)?;
        (*order > 0).then_some(note as u8)
    }

    /// The first absolute sample at or after which the next pluck is due.
    pub fn next_pluck_sample(&self) -> Option<u64> {
        self.next_pluck_time.map(|time| time.ceil() as u64)
    }

    /// If a pluck is due at `now`, returns the string index (0–3) and schedules the next one
    /// `gap × 60 / tempo` seconds later.
    pub fn take_due_pluck(
        &mut self,
        now: u64,
        tempo_bpm: f64,
        sample_rate_hz: f64,
    ) -> Option<usize> {
        let time = self.next_pluck_time?;
        if (now as f64) < time.ceil() {
            return None;
        }
        let string = self.next_string;
        // A NaN tempo would make every later pluck time NaN (a pluck at every sample).
        let tempo = if tempo_bpm.is_nan() {
            DroneSettings::default().free_tempo_bpm
        } else {
            tempo_bpm.clamp(TEMPO_RANGE_BPM.0, TEMPO_RANGE_BPM.1)
        };
        let beat_samples = 60.0 / tempo * sample_rate_hz;
        self.next_pluck_time = Some(time + CYCLE_GAPS_BEATS[string] * beat_samples);
        self.next_string = (string + 1) % DRONE_STRINGS;
        Some(string)
    }

    pub fn reset(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classic_cycle_order_and_gaps_at_60_bpm() {
        let mut drone = DroneSequencer::default();
        drone.note_on(60, 100);
        let rate = 1000.0; // one beat = 1000 samples at 60 bpm
        let mut plucks = Vec::new();
        for now in 100..7000 {
            if let Some(string) = drone.take_due_pluck(now, 60.0, rate) {
                plucks.push((now, string));
            }
        }
        assert_eq!(
            plucks,
            vec![
                (100, 0),
                (1100, 1),
                (2100, 2),
                (3100, 3),
                (5100, 0),
                (6100, 1)
            ]
        );
    }

    #[test]
    fn releasing_the_last_note_stops_the_cycle_and_latest_note_is_sa() {
        let mut drone = DroneSequencer::default();
        drone.note_on(48, 0);
        drone.note_on(50, 10);
        assert_eq!(drone.sa_note(), Some(50));
        drone.note_off(50);
        assert_eq!(drone.sa_note(), Some(48));
        assert!(drone.next_pluck_sample().is_some());
        drone.note_off(48);
        assert_eq!(drone.sa_note(), None);
        assert_eq!(drone.next_pluck_sample(), None);
    }

    #[test]
    fn string_ratios_follow_the_first_string() {
        assert_eq!(string_ratios(FirstString::Pa), [0.75, 1.0, 1.0, 0.5]);
        assert_eq!(string_ratios(FirstString::Ma)[0], 2.0 / 3.0);
        assert_eq!(string_ratios(FirstString::Ni)[0], 15.0 / 16.0);
    }
}
