//! Drone mode: a held note sets Sa and the strings are plucked in the cycle a tanpura player
//! plays.
//!
//! **Strings** ([`DronePattern`]), in playing order, with the first string's note
//! ([`FirstString::ratio`]: Pa 3/4, Ma 2/3, shuddha Ni 15/16, komal Ni 8/9, Dha 5/6 of Sa, just
//! intonation in the lower octave) and low Sa 1/2:
//! - four strings: first, Sa, Sa, low Sa (the common tanpura);
//! - five strings: first, Ni (15/16), Sa, Sa, low Sa;
//! - six strings: first, first, Sa, Sa, low Sa, low Sa.
//!
//! **Sa** is the held MIDI note (the drone plays while it is held), or a note set in the
//! settings ([`DroneSettings::sa_note`]): then the drone plays whenever drone mode is on, as a
//! tanpura box does, and MIDI notes do not touch it.
//!
//! **Timing.** A player plucks the strings evenly and lets the last one ring a little longer
//! before starting again: a gap of [`DroneSettings::pluck_spacing_beats`] after each pluck and
//! [`DroneSettings::cycle_pause_beats`] more after the last (the classic four-string cycle is
//! 1, 1, 1 and 2 beats). The beat follows the host's tempo when tempo sync is on (or a free
//! tempo otherwise).
//!
//! **Each string apart** ([`DroneString`]): players tune each string by ear and adjust each
//! string's jawari (the thread under it) apart, and balance the strings' levels. Each string has
//! a fine tuning (±50 cents on top of its interval), a level (dB, −60 to +6) and an offset of its
//! thread from the instrument's thread position (±5 mm; the sum stays within the thread's range).
//!
//! **Humanisation.** Each pluck may come early or late by up to
//! [`DroneSettings::humanize_timing_s`] and be softer by up to
//! [`DroneSettings::humanize_strength`] (a fraction of the full pluck), drawn from a SplitMix64
//! sequence seeded by [`DroneSettings::humanize_seed`] and the pluck's index in the cycle count:
//! the same seed gives the same performance, bit for bit, and the variation never moves the
//! cycle's grid (each pluck is displaced from its own nominal time, so nothing drifts).
//!
//! The sequencer only decides *when*, *which* string and *how strong*; the engine turns that into
//! plucks. Times are absolute sample indices, so the cycle does not depend on how the host splits
//! its blocks.

use crate::tanpura::FirstString;

/// Most strings a drone pattern has.
pub const MAX_DRONE_STRINGS: usize = 6;
/// Valid drone tempo range, beats per minute.
pub const TEMPO_RANGE_BPM: (f64, f64) = (20.0, 300.0);
/// Valid gap after each pluck and extra pause after the cycle, beats.
pub const PLUCK_SPACING_RANGE_BEATS: (f64, f64) = (0.25, 4.0);
pub const CYCLE_PAUSE_RANGE_BEATS: (f64, f64) = (0.0, 8.0);
/// Valid humanisation: timing spread (s) and strength spread (fraction of the pluck).
pub const HUMANIZE_TIMING_RANGE_S: (f64, f64) = (0.0, 0.05);
pub const HUMANIZE_STRENGTH_RANGE: (f64, f64) = (0.0, 0.5);

/// Valid per-string fine tuning (cents), level (dB) and thread offset (m).
pub const STRING_FINE_TUNE_RANGE_CENTS: (f64, f64) = (-50.0, 50.0);
pub const STRING_LEVEL_RANGE_DB: (f64, f64) = (-60.0, 6.0);
pub const STRING_THREAD_OFFSET_RANGE_M: (f64, f64) = (-0.005, 0.005);

/// What a player sets on one drone string apart from the others.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DroneString {
    /// Fine tuning on top of the string's interval, cents (±50).
    pub fine_tune_cents: f64,
    /// Level, dB (−60 to +6; 0: as plucked).
    pub level_db: f64,
    /// The thread's offset from the instrument's thread position, m (±0.005).
    pub thread_offset_m: f64,
}

impl DroneString {
    /// Every number within its range; NaN takes 0.
    pub fn clamped(&self) -> Self {
        Self {
            fine_tune_cents: within(self.fine_tune_cents, STRING_FINE_TUNE_RANGE_CENTS, 0.0),
            level_db: within(self.level_db, STRING_LEVEL_RANGE_DB, 0.0),
            thread_offset_m: within(self.thread_offset_m, STRING_THREAD_OFFSET_RANGE_M, 0.0),
        }
    }

    /// The level as an amplitude factor.
    pub fn level_factor(&self) -> f64 {
        10f64.powf(self.level_db / 20.0)
    }

    /// The pitch ratio of the fine tuning.
    pub fn fine_tune_ratio(&self) -> f64 {
        (self.fine_tune_cents / 1200.0).exp2()
    }
}

/// How many strings the drone has and what they play.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DronePattern {
    /// First, Sa, Sa, low Sa.
    #[default]
    Four,
    /// First, Ni, Sa, Sa, low Sa.
    Five,
    /// First, first, Sa, Sa, low Sa, low Sa.
    Six,
}

impl DronePattern {
    pub const ALL: [DronePattern; 3] = [DronePattern::Four, DronePattern::Five, DronePattern::Six];

    pub fn string_count(self) -> usize {
        match self {
            DronePattern::Four => 4,
            DronePattern::Five => 5,
            DronePattern::Six => 6,
        }
    }
}

/// How the drone is played, in musician's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DroneSettings {
    /// On: a held note sets Sa and the strings are plucked automatically; off: each note plucks
    /// its own string.
    pub enabled: bool,
    pub first_string: FirstString,
    pub pattern: DronePattern,
    /// Follow the host's tempo when it reports one.
    pub tempo_sync: bool,
    /// Beats per minute used without sync or when the host reports no tempo (20–300).
    pub free_tempo_bpm: f64,
    /// Gap after each pluck, beats (0.25–4).
    pub pluck_spacing_beats: f64,
    /// Extra gap after the cycle's last pluck before it starts again, beats (0–8).
    pub cycle_pause_beats: f64,
    /// Largest timing displacement of a pluck, s (0–0.05).
    pub humanize_timing_s: f64,
    /// Largest softening of a pluck, fraction of the full pluck (0–0.5).
    pub humanize_strength: f64,
    pub humanize_seed: u32,
    /// Sa as a MIDI note (the drone plays whenever drone mode is on, no note held), or `None`:
    /// the held note sets Sa and the drone plays while it is held.
    pub sa_note: Option<u8>,
    /// Each string's fine tuning, level and thread, in playing order.
    pub strings: [DroneString; MAX_DRONE_STRINGS],
}

impl Default for DroneSettings {
    fn default() -> Self {
        Self {
            enabled: false,
            first_string: FirstString::Pa,
            pattern: DronePattern::Four,
            tempo_sync: true,
            free_tempo_bpm: 60.0,
            pluck_spacing_beats: 1.0,
            cycle_pause_beats: 1.0,
            humanize_timing_s: 0.0,
            humanize_strength: 0.0,
            humanize_seed: 0,
            sa_note: None,
            strings: [DroneString::default(); MAX_DRONE_STRINGS],
        }
    }
}

impl DroneSettings {
    /// Each of the pattern's strings on a Sa of `sa_hz`, in playing order: its pitch, `Sa × its
    /// ratio × its fine tuning`, and its thread's offset. The one place that pitch is formed, so
    /// that a string planned or calibrated is the plucked one to the bit.
    pub fn string_pitches(&self, sa_hz: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        let (ratios, count) = string_ratios(self.first_string, self.pattern);
        ratios
            .into_iter()
            .zip(&self.strings)
            .take(count)
            .map(move |(ratio, string)| {
                (
                    sa_hz * ratio * string.fine_tune_ratio(),
                    string.thread_offset_m,
                )
            })
    }
}

/// Frequency ratio of each drone string to Sa, in playing order; the count is the pattern's.
pub fn string_ratios(
    first_string: FirstString,
    pattern: DronePattern,
) -> ([f64; MAX_DRONE_STRINGS], usize) {
    let first = first_string.ratio();
    let ni = FirstString::Ni.ratio();
    match pattern {
        DronePattern::Four => ([first, 1.0, 1.0, 0.5, 0.0, 0.0], 4),
        DronePattern::Five => ([first, ni, 1.0, 1.0, 0.5, 0.0], 5),
        DronePattern::Six => ([first, first, 1.0, 1.0, 0.5, 0.5], 6),
    }
}

/// `value` within `range`; NaN takes `fallback`.
fn within(value: f64, (low, high): (f64, f64), fallback: f64) -> f64 {
    if value.is_nan() {
        fallback
    } else {
        value.clamp(low, high)
    }
}

/// One due pluck: which string and how strong (1: the full pluck).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DronePluck {
    pub string: usize,
    pub strength: f64,
}

/// SplitMix64 (Steele, Lea & Flood 2014): a well-mixed 64-bit value from a counter, in a few
/// integer operations, no state beyond the counter (hand-written: the audio thread needs one
/// number per pluck, reproducibly from (seed, index), which a seeded generator crate would
/// give only by replaying the sequence).
fn split_mix(seed: u32, index: u64, stream: u64) -> f64 {
    let mut z = (u64::from(seed) << 32 ^ index.wrapping_mul(2) ^ stream)
        .wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    // The top 53 bits as a uniform number in [0, 1).
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// The held-note memory and the cycle's clock. Allocation-free.
#[derive(Debug, Clone)]
pub struct DroneSequencer {
    /// For each MIDI note: 0 when not held, else the order in which it was pressed.
    held_order: [u64; 128],
    press_counter: u64,
    /// Nominal absolute time of the next pluck in samples (fractional: beats need not be whole
    /// samples), before humanisation.
    next_pluck_time: Option<f64>,
    next_string: usize,
    /// Plucks taken since the cycle started: the humanisation's index.
    pluck_index: u64,
    /// The nominal times are `anchor + beats · 60 · rate / tempo`, computed afresh at every pluck
    /// (so that a whole number of samples comes out exact and nothing accumulates); a tempo change
    /// moves the anchor to the pluck where it is first seen.
    anchor_time: f64,
    anchor_tempo_bpm: f64,
    beats_since_anchor: f64,
}

impl Default for DroneSequencer {
    fn default() -> Self {
        Self {
            held_order: [0; 128],
            press_counter: 0,
            next_pluck_time: None,
            next_string: 0,
            pluck_index: 0,
            anchor_time: 0.0,
            anchor_tempo_bpm: 0.0,
            beats_since_anchor: 0.0,
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
            self.start(now);
        }
    }

    /// Starts the cycle at absolute sample `now` with the first string, without a held note
    /// (Sa set by [`DroneSettings::sa_note`]).
    pub fn start(&mut self, now: u64) {
        self.next_pluck_time = Some(now as f64);
        self.next_string = 0;
        self.pluck_index = 0;
        self.anchor_time = now as f64;
        self.anchor_tempo_bpm = 0.0;
        self.beats_since_anchor = 0.0;
    }

    /// Stops the cycle (the strings ring on).
    pub fn stop(&mut self) {
        self.next_pluck_time = None;
    }

    /// True while the cycle runs.
    pub fn is_running(&self) -> bool {
        self.next_pluck_time.is_some()
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

    /// The humanised time of the next pluck, samples: its nominal time displaced by up to
    /// ±`humanize_timing_s` (never before the cycle's start).
    fn due_time(&self, settings: &DroneSettings, sample_rate_hz: f64) -> Option<f64> {
        let nominal = self.next_pluck_time?;
        let spread = settings
            .humanize_timing_s
            .clamp(HUMANIZE_TIMING_RANGE_S.0, HUMANIZE_TIMING_RANGE_S.1);
        if spread <= 0.0 || self.pluck_index == 0 {
            // The first pluck sounds when the note is pressed.
            return Some(nominal);
        }
        let offset = (2.0 * split_mix(settings.humanize_seed, self.pluck_index, 0) - 1.0) * spread;
        Some(nominal + offset * sample_rate_hz)
    }

    /// The first absolute sample at or after which the next pluck is due.
    pub fn next_pluck_sample(&self, settings: &DroneSettings, sample_rate_hz: f64) -> Option<u64> {
        self.due_time(settings, sample_rate_hz)
            .map(|time| time.max(0.0).ceil() as u64)
    }

    /// If a pluck is due at `now`, returns it and schedules the next one a spacing (plus the
    /// pause after the cycle's last string) of `60 / tempo` s beats later.
    pub fn take_due_pluck(
        &mut self,
        now: u64,
        settings: &DroneSettings,
        tempo_bpm: f64,
        sample_rate_hz: f64,
    ) -> Option<DronePluck> {
        let due = self.due_time(settings, sample_rate_hz)?;
        if (now as f64) < due.max(0.0).ceil() {
            return None;
        }
        let nominal = self.next_pluck_time?;
        let count = settings.pattern.string_count();
        let string = self.next_string.min(count - 1);
        // A NaN would make every later pluck time NaN (a pluck at every sample): it takes the
        // default instead.
        let defaults = DroneSettings::default();
        let tempo = within(tempo_bpm, TEMPO_RANGE_BPM, defaults.free_tempo_bpm);
        if tempo != self.anchor_tempo_bpm {
            self.anchor_time = nominal;
            self.anchor_tempo_bpm = tempo;
            self.beats_since_anchor = 0.0;
        }
        let spacing = within(
            settings.pluck_spacing_beats,
            PLUCK_SPACING_RANGE_BEATS,
            defaults.pluck_spacing_beats,
        );
        let pause = within(
            settings.cycle_pause_beats,
            CYCLE_PAUSE_RANGE_BEATS,
            defaults.cycle_pause_beats,
        );
        let last = string + 1 >= count;
        let gap = spacing + if last { pause } else { 0.0 };
        self.beats_since_anchor += gap;
        self.next_pluck_time =
            Some(self.anchor_time + self.beats_since_anchor * 60.0 * sample_rate_hz / tempo);
        self.next_string = if last { 0 } else { string + 1 };
        let softening = within(settings.humanize_strength, HUMANIZE_STRENGTH_RANGE, 0.0);
        let strength = 1.0 - softening * split_mix(settings.humanize_seed, self.pluck_index, 1);
        self.pluck_index += 1;
        Some(DronePluck { string, strength })
    }

    pub fn reset(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plucks(
        settings: &DroneSettings,
        tempo: f64,
        rate: f64,
        until: u64,
    ) -> Vec<(u64, usize, f64)> {
        let mut drone = DroneSequencer::default();
        drone.note_on(60, 100);
        let mut out = Vec::new();
        for now in 100..until {
            if let Some(pluck) = drone.take_due_pluck(now, settings, tempo, rate) {
                out.push((now, pluck.string, pluck.strength));
            }
        }
        out
    }

    #[test]
    fn classic_cycle_order_and_gaps_at_60_bpm() {
        let rate = 1000.0; // one beat = 1000 samples at 60 bpm
        let times: Vec<(u64, usize)> = plucks(&DroneSettings::default(), 60.0, rate, 7000)
            .iter()
            .map(|&(now, string, _)| (now, string))
            .collect();
        assert_eq!(
            times,
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
    fn four_five_and_six_strings_follow_the_tempo_to_the_sample() {
        // 93 bpm at 44.1 kHz: a beat is 28 451.6… samples, so pluck n of the grid falls at the
        // first sample at or after 100 + (its beats) · 60/93 · 44 100.
        let (tempo, rate) = (93.0, 44_100.0);
        for pattern in DronePattern::ALL {
            let settings = DroneSettings {
                pattern,
                pluck_spacing_beats: 1.5,
                cycle_pause_beats: 2.0,
                ..DroneSettings::default()
            };
            let count = pattern.string_count();
            let beat = 60.0 / tempo * rate;
            let got = plucks(
                &settings,
                tempo,
                rate,
                100 + (3.0 * (count as f64 * 1.5 + 2.0) * beat) as u64,
            );
            let mut beats = 0.0;
            for (n, &(now, string, strength)) in got.iter().enumerate() {
                assert_eq!(string, n % count, "{pattern:?}");
                assert_eq!(
                    now,
                    (100.0 + beats * beat).ceil() as u64,
                    "{pattern:?} pluck {n}"
                );
                assert_eq!(strength, 1.0);
                beats += 1.5 + if string + 1 == count { 2.0 } else { 0.0 };
            }
            assert!(got.len() >= 3 * count, "{pattern:?}: {} plucks", got.len());
        }
    }

    #[test]
    fn humanisation_is_bounded_and_the_same_for_the_same_seed() {
        let rate = 44_100.0;
        let settings = DroneSettings {
            humanize_timing_s: 0.02,
            humanize_strength: 0.3,
            humanize_seed: 7,
            ..DroneSettings::default()
        };
        let until = 100 + 20 * 44_100;
        let first = plucks(&settings, 60.0, rate, until);
        assert_eq!(first, plucks(&settings, 60.0, rate, until));
        let other = plucks(
            &DroneSettings {
                humanize_seed: 8,
                ..settings
            },
            60.0,
            rate,
            until,
        );
        assert_ne!(first, other);
        let exact = plucks(&DroneSettings::default(), 60.0, rate, until);
        assert_eq!(first.len(), exact.len());
        let mut moved = 0;
        for (human, grid) in first.iter().zip(&exact) {
            assert_eq!(human.1, grid.1);
            let shift = human.0 as f64 - grid.0 as f64;
            assert!(shift.abs() <= 0.02 * rate + 1.0, "{shift} samples");
            moved += usize::from(shift != 0.0);
            assert!((0.7..=1.0).contains(&human.2), "{}", human.2);
        }
        assert!(
            moved > first.len() / 2,
            "humanisation moved {moved} of {}",
            first.len()
        );
        // The grid does not drift: the last pluck is still within the spread of its grid time.
        let (last_human, last_grid) = (first.last().unwrap().0, exact.last().unwrap().0);
        assert!((last_human as f64 - last_grid as f64).abs() <= 0.02 * rate + 1.0);
    }

    #[test]
    fn releasing_the_last_note_stops_the_cycle_and_latest_note_is_sa() {
        let settings = DroneSettings::default();
        let mut drone = DroneSequencer::default();
        drone.note_on(48, 0);
        drone.note_on(50, 10);
        assert_eq!(drone.sa_note(), Some(50));
        drone.note_off(50);
        assert_eq!(drone.sa_note(), Some(48));
        assert!(drone.next_pluck_sample(&settings, 44_100.0).is_some());
        drone.note_off(48);
        assert_eq!(drone.sa_note(), None);
        assert_eq!(drone.next_pluck_sample(&settings, 44_100.0), None);
    }

    #[test]
    fn string_ratios_follow_the_first_string_and_the_pattern() {
        assert_eq!(
            string_ratios(FirstString::Pa, DronePattern::Four),
            ([0.75, 1.0, 1.0, 0.5, 0.0, 0.0], 4)
        );
        assert_eq!(
            string_ratios(FirstString::Ma, DronePattern::Four).0[0],
            2.0 / 3.0
        );
        assert_eq!(
            string_ratios(FirstString::Ni, DronePattern::Four).0[0],
            15.0 / 16.0
        );
        assert_eq!(
            string_ratios(FirstString::KomalNi, DronePattern::Four).0[0],
            8.0 / 9.0
        );
        assert_eq!(
            string_ratios(FirstString::Dha, DronePattern::Four).0[0],
            5.0 / 6.0
        );
        assert_eq!(
            string_ratios(FirstString::Pa, DronePattern::Five),
            ([0.75, 15.0 / 16.0, 1.0, 1.0, 0.5, 0.0], 5)
        );
        assert_eq!(
            string_ratios(FirstString::Pa, DronePattern::Six),
            ([0.75, 0.75, 1.0, 1.0, 0.5, 0.5], 6)
        );
    }
}
