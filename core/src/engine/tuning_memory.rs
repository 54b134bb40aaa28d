//! The tensions that tune the engine's strings, remembered per string settings, so that a
//! note-on on a string tuned before configures its voice once instead of tuning it.
//!
//! A note-on that takes a voice tuned to another pitch retunes it
//! ([`crate::tanpura::TanpuraVoice::set_settings`]): the tension is scaled twice by
//! `T ← T (f / f_lin)²`, each pass a configuration of the string (its modes, its rest state on
//! bridge and thread) and an inverse iteration for its linearised fundamental, then configured
//! a third time. At the fine tier that took 345–357 µs of a note-on's 0.48 ms on a 2.6 GHz
//! AVX-512 Xeon, a quarter of a 64-sample block's deadline, on top of the block's other strings
//! (`docs/performance.md`, "Stop 51"); 235–237 µs since stop 55 (`--example note_on_cost`).
//! The tension it reaches is a function of the settings alone (the losses and the pickup mix
//! aside, which the tuning does not see), so the engine remembers it: the next note-on with the
//! same settings configures the string once at that tension
//! ([`crate::tanpura::TanpuraVoice::set_settings_tuned`]).
//!
//! The memory fills as strings are tuned on note-ons, and [`crate::engine::Engine::prepare_tunings`]
//! fills it off the audio thread for every note the tuning can play, as a host does when it
//! activates the plugin. After a change of what the tuning sees (the bridge, the thread, the
//! tier, the tuning, the drone's Sa or its strings), the engine hands out the new [`TuningPlan`]
//! ([`crate::engine::Engine::take_wanted_tuning_plan`]) for a worker to tune off the audio
//! thread and hand back string by string ([`crate::engine::Engine::remember_tuning`]). In drone
//! mode the plan holds the drone's strings on its Sa first (each with its own fine tuning and
//! thread, so most are no note's string): they are the ones ringing.
//!
//! A ringing string retuned to settings the memory holds (a glide's last retune, once the plan
//! is back) is configured at the remembered tension too (`Engine::control_tick`).
//!
//! Entries are keyed by the whole settings, so a change of any setting the tuning sees (the
//! thread, the bridge, the tier, the pitch) finds none and tunes the string as before, until a
//! plan's tensions arrive; the oldest entry makes room for a new one. A fixed array searched in
//! order: at most [`TUNING_MEMORY_CAPACITY`] comparisons of a few numbers each, against the
//! 170 µs a hit saves at the fine tier (configured once in 67–68 µs, tuned in 235–237 µs,
//! `--example note_on_cost`, stop 55), and nothing allocates after [`TuningMemory::new`].

use crate::engine::drone::MAX_DRONE_STRINGS;
use crate::engine::pitch::Tuning;
use crate::tanpura::{TanpuraVoice, VoiceSettings};

/// Settings remembered at once: every playable note of one tuning (MIDI 16–95 at A4 = 440 Hz)
/// with room for the drone's strings and calibrated variants.
pub const TUNING_MEMORY_CAPACITY: usize = 128;

/// Tuned tensions by string settings.
#[derive(Debug, Clone)]
pub struct TuningMemory {
    entries: Vec<(VoiceSettings, f64)>,
    /// Where the next entry goes once the memory is full (the oldest).
    next: usize,
}

impl Default for TuningMemory {
    fn default() -> Self {
        Self::new()
    }
}

impl TuningMemory {
    /// An empty memory with room for [`TUNING_MEMORY_CAPACITY`] entries. Allocates.
    pub fn new() -> Self {
        Self {
            entries: Vec::with_capacity(TUNING_MEMORY_CAPACITY),
            next: 0,
        }
    }

    /// The settings as the tuning sees them: clamped, without the losses and the pickup mix.
    pub(crate) fn key(settings: &VoiceSettings) -> VoiceSettings {
        let clamped = settings.clamped();
        let reference = VoiceSettings::default();
        VoiceSettings {
            gamma_per_s: reference.gamma_per_s,
            eta_s: reference.eta_s,
            nut_pickup_weight: reference.nut_pickup_weight,
            ..clamped
        }
    }

    /// The tension remembered for `settings`, N. Allocation-free.
    pub fn tension_n(&self, settings: &VoiceSettings) -> Option<f64> {
        let key = Self::key(settings);
        self.entries
            .iter()
            .find(|(settings, _)| *settings == key)
            .map(|&(_, tension)| tension)
    }

    /// Remembers that `tension_n` tunes the string for `settings` (a tension that is not a
    /// positive number is not kept). Allocation-free.
    pub fn remember(&mut self, settings: &VoiceSettings, tension_n: f64) {
        if !(tension_n.is_finite() && tension_n > 0.0) {
            return;
        }
        let key = Self::key(settings);
        if let Some(entry) = self
            .entries
            .iter_mut()
            .find(|(settings, _)| *settings == key)
        {
            entry.1 = tension_n;
            return;
        }
        if self.entries.len() < TUNING_MEMORY_CAPACITY {
            self.entries.push((key, tension_n));
        } else {
            self.entries[self.next] = (key, tension_n);
            self.next = (self.next + 1) % TUNING_MEMORY_CAPACITY;
        }
    }

    /// How many settings are remembered.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Whether a tension is remembered for every string of `plan`.
    pub fn covers(&self, plan: &TuningPlan) -> bool {
        plan.strings()
            .all(|settings| self.tension_n(&settings).is_some())
    }

    /// Forgets every entry. Allocation-free.
    pub fn clear(&mut self) {
        self.entries.clear();
        self.next = 0;
    }
}

/// Every playable note's string with one set of settings, and the drone's strings on its Sa:
/// what a memory is prepared for ([`crate::engine::Engine::prepare_tunings`],
/// [`crate::engine::Engine::take_wanted_tuning_plan`]). Two plans are equal when the tuning sees
/// the same strings in them. Plain data, so the audio thread can hand it to another thread
/// without allocating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TuningPlan {
    /// The strings' settings as the tuning sees them ([`TuningMemory`]'s key), any pitch.
    base: VoiceSettings,
    tuning: Tuning,
    sample_rate_hz: f64,
    /// The drone's strings as the tuning sees them, in playing order (none out of drone mode).
    drone: [Option<VoiceSettings>; MAX_DRONE_STRINGS],
}

/// One string of a [`TuningPlan`] and the tension that tunes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedTension {
    pub settings: VoiceSettings,
    pub tension_n: f64,
    pub sample_rate_hz: f64,
}

impl TuningPlan {
    /// The plan for strings with `base`'s settings (its pitch aside) at every note `tuning` can
    /// play, at `sample_rate_hz`.
    pub fn new(base: &VoiceSettings, tuning: &Tuning, sample_rate_hz: f64) -> Self {
        Self {
            base: TuningMemory::key(base),
            tuning: *tuning,
            sample_rate_hz,
            drone: [None; MAX_DRONE_STRINGS],
        }
    }

    /// The same plan with the drone's strings too, each at its pitch and with its thread moved
    /// by its offset from the base's (as [`crate::engine::Engine`] plucks them); a pitch outside
    /// [`VoiceSettings::FUNDAMENTAL_RANGE_HZ`] is not played, so not planned.
    pub fn with_drone_strings(mut self, strings: impl IntoIterator<Item = (f64, f64)>) -> Self {
        let (low, high) = VoiceSettings::FUNDAMENTAL_RANGE_HZ;
        for (slot, (fundamental_hz, thread_offset_m)) in self.drone.iter_mut().zip(strings) {
            *slot = (low..=high).contains(&fundamental_hz).then(|| {
                TuningMemory::key(&VoiceSettings {
                    fundamental_hz,
                    thread_position_m: self.base.thread_position_m + thread_offset_m,
                    ..self.base
                })
            });
        }
        self
    }

    /// The output rate the plan's strings play at, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// The drone's strings in playing order (they are the ones ringing), then each playable
    /// note's string from the lowest note up, each once.
    pub fn strings(&self) -> impl Iterator<Item = VoiceSettings> + '_ {
        let drone = self
            .drone
            .iter()
            .enumerate()
            .filter(|&(index, string)| !self.drone[..index].contains(string))
            .filter_map(|(_, string)| *string);
        let notes = (0..=127u8).filter_map(|note| {
            let hz = self.tuning.playable_note_hz(note)?;
            Some(
                VoiceSettings {
                    fundamental_hz: hz,
                    ..self.base
                }
                .clamped(),
            )
        });
        drone.chain(notes.filter(|note| {
            let key = TuningMemory::key(note);
            !self.drone.contains(&Some(key))
        }))
    }

    /// A voice to tune the plan's strings with ([`TuningPlan::tune`]). Allocates.
    pub fn scratch_voice(&self) -> TanpuraVoice {
        TanpuraVoice::new(&self.base, self.sample_rate_hz)
    }

    /// Tunes `settings`' string on `voice` (a fine string: 235–237 µs on a 2.6 GHz Xeon).
    pub fn tune(&self, voice: &mut TanpuraVoice, settings: &VoiceSettings) -> PlannedTension {
        voice.set_settings(settings);
        PlannedTension {
            settings: *settings,
            tension_n: voice.tension_n(),
            sample_rate_hz: self.sample_rate_hz,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The losses and the pickup mix do not enter the key; the pitch and the thread do; a full
    /// memory forgets its oldest entry first; a tension that is not a positive number is not
    /// remembered.
    #[test]
    fn remembers_by_the_settings_the_tuning_sees() {
        let mut memory = TuningMemory::new();
        let settings = VoiceSettings::default();
        memory.remember(&settings, 30.0);
        let damped = VoiceSettings {
            gamma_per_s: 3.0,
            eta_s: 1e-8,
            nut_pickup_weight: 0.2,
            ..settings
        };
        assert_eq!(memory.tension_n(&damped), Some(30.0));
        let higher = VoiceSettings {
            fundamental_hz: settings.fundamental_hz * 1.5,
            ..settings
        };
        assert_eq!(memory.tension_n(&higher), None);
        let moved = VoiceSettings {
            thread_position_m: settings.thread_position_m + 1e-3,
            ..settings
        };
        assert_eq!(memory.tension_n(&moved), None);
        memory.remember(&settings, 31.0);
        assert_eq!((memory.tension_n(&settings), memory.len()), (Some(31.0), 1));
        memory.remember(&higher, f64::NAN);
        memory.remember(&higher, 0.0);
        assert_eq!(memory.tension_n(&higher), None);

        for index in 0..TUNING_MEMORY_CAPACITY {
            let pitched = VoiceSettings {
                fundamental_hz: 100.0 + index as f64,
                ..settings
            };
            memory.remember(&pitched, 1.0 + index as f64);
        }
        assert_eq!(memory.len(), TUNING_MEMORY_CAPACITY);
        assert_eq!(memory.tension_n(&settings), None, "the oldest went first");
        let newest = VoiceSettings {
            fundamental_hz: 100.0 + (TUNING_MEMORY_CAPACITY - 1) as f64,
            ..settings
        };
        assert_eq!(
            memory.tension_n(&newest),
            Some(TUNING_MEMORY_CAPACITY as f64)
        );
        memory.clear();
        assert!(memory.is_empty());
    }
}
