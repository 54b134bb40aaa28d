//! The bowed instrument: a player's MIDI gestures mapped onto one bowed string.
//!
//! One bow on one string, monophonic with last-note priority, as a violinist plays one string.
//! The mapping (documented in README.md), all in SI units once mapped:
//!
//! | gesture | control | mapping |
//! |---|---|---|
//! | note | pitch | 12-TET, A4 = 440 Hz; a note played while another is held glides to it (legato, no new attack) over `glide_time_s`; releasing it glides back to the last held note |
//! | note-on velocity | bow velocity | v_b = 0.05 + 0.45·velocity m/s at the attack |
//! | expression (CC 11) | bow velocity | v_b = 0.02 + 0.58·x m/s, from the first CC on |
//! | channel pressure, breath (CC 2), MPE per-note pressure | bow force | F_b = F_max(v_b, β)·(0.05 + 0.75·p), a fraction of Schelleng's maximum for the current bow speed and position (default p = 0.5) |
//! | CC 74 (MPE "timbre") | bow position | β = 0.04 + 0.21·x (default 0.1) |
//! | modulation (CC 1) | vibrato depth | 0 to `max_vibrato_cents` at `vibrato_rate_hz` |
//! | pitch bend | pitch | ± `pitch_bend_range_semitones` |
//! | note-off of the last held note | bow lift | the force falls to 0 over `bow_lift_time_s`; the string rings on |
//!
//! Bow force, velocity and position move through one-pole smoothers (10 ms) so that no control
//! clicks. Both tiers (rounded corner and bow table) are built up front; switching is
//! allocation-free.

use super::{
    BowTableString, BowedCapacity, BowedConfigError, BowedString, BowedVoice, ContactState,
    StringConstants,
};

/// Which bowed model plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BowTier {
    /// McIntyre–Schumacher–Woodhouse with rounded-corner reflection functions.
    #[default]
    RoundedCorner,
    /// The STK bow table, the cheap tier.
    BowTable,
}

/// The player's settings, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BowedPlayerSettings {
    pub tier: BowTier,
    /// Legato glide time, s (0–1).
    pub glide_time_s: f64,
    /// Vibrato rate, Hz.
    pub vibrato_rate_hz: f64,
    /// Vibrato depth at full modulation wheel, cents.
    pub max_vibrato_cents: f64,
    /// Pitch-bend range, semitones (2 for ordinary MIDI, 48 for MPE).
    pub pitch_bend_range_semitones: f64,
    /// Time for the bow to lift after the last note-off, s.
    pub bow_lift_time_s: f64,
    pub body_enabled: bool,
}

impl BowedPlayerSettings {
    /// Ranges the engine clamps to (`EngineSettings::clamped`): vibrato rate, Hz; pitch-bend
    /// range, semitones (MPE's 48 at most); bow lift time, s.
    pub const VIBRATO_RATE_RANGE_HZ: (f64, f64) = (0.0, 20.0);
    pub const PITCH_BEND_RANGE_SEMITONES: (f64, f64) = (0.0, 48.0);
    pub const BOW_LIFT_TIME_RANGE_S: (f64, f64) = (1e-4, 10.0);
}

impl Default for BowedPlayerSettings {
    fn default() -> Self {
        Self {
            tier: BowTier::RoundedCorner,
            glide_time_s: 0.08,
            vibrato_rate_hz: 5.5,
            max_vibrato_cents: 40.0,
            pitch_bend_range_semitones: 2.0,
            bow_lift_time_s: 0.03,
            body_enabled: true,
        }
    }
}

/// A MIDI gesture, already decoded (values normalised to 0–1 as MIDI sends them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BowedEvent {
    NoteOn {
        note: u8,
        velocity: f32,
    },
    NoteOff {
        note: u8,
    },
    /// CC 11.
    Expression(f32),
    /// Channel pressure, CC 2 or MPE per-note pressure.
    Pressure(f32),
    /// CC 1.
    Modulation(f32),
    /// CC 74.
    Timbre(f32),
    /// Pitch bend, −1 to 1.
    PitchBend(f32),
    /// Lift the bow and forget the held notes.
    AllNotesOff,
}

/// Bow velocity from note-on velocity, m/s.
pub fn bow_velocity_from_note_velocity(velocity: f64) -> f64 {
    0.05 + 0.45 * velocity.clamp(0.0, 1.0)
}

/// Bow velocity from the expression controller, m/s.
pub fn bow_velocity_from_expression(value: f64) -> f64 {
    0.02 + 0.58 * value.clamp(0.0, 1.0)
}

/// Bow position β from CC 74.
pub fn bow_position_from_timbre(value: f64) -> f64 {
    0.04 + 0.21 * value.clamp(0.0, 1.0)
}

/// Bow force as a fraction of Schelleng's maximum, from pressure.
pub fn force_fraction_from_pressure(pressure: f64) -> f64 {
    0.05 + 0.75 * pressure.clamp(0.0, 1.0)
}

/// Schelleng's maximum bow force `2Z₀v_b/(β(μ_s − μ_d))` with the default friction
/// (μ_s = 0.8, μ_d = 0.3), N.
pub fn schelleng_max_force_n(impedance_n_s_m: f64, bow_velocity_m_s: f64, beta: f64) -> f64 {
    2.0 * impedance_n_s_m * bow_velocity_m_s.abs() / (beta * 0.5)
}

const MAX_HELD_NOTES: usize = 16;
/// Samples of bow-point velocity and contact state kept for the editor's view.
pub const BOW_HISTORY_SAMPLES: usize = 1024;
const CONTROL_SMOOTHING_S: f64 = 0.01;

/// The controls the string receives, after mapping and smoothing.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BowControls {
    pub pitch_hz: f64,
    pub bow_force_n: f64,
    pub bow_velocity_m_s: f64,
    pub bow_position: f64,
}

/// One bowed string played from MIDI; allocation-free after `new`.
#[derive(Debug, Clone)]
pub struct BowedInstrument {
    settings: BowedPlayerSettings,
    sample_rate_hz: f64,
    rounded: BowedString,
    table: BowTableString,
    impedance_n_s_m: f64,
    held: [u8; MAX_HELD_NOTES],
    held_count: usize,
    bowing: bool,
    /// Pitch in semitones (MIDI note numbers) and the glide target.
    pitch_note: f64,
    target_note: f64,
    glide_per_sample: f64,
    /// The note number sounding at the last sample (glide, bend and vibrato included) and its
    /// frequency, Hz.
    sounding_note: f64,
    sounding_hz: f64,
    bend_semitones: f64,
    vibrato_depth: f64,
    vibrato_phase: f64,
    velocity_target: f64,
    pressure: f64,
    position_target: f64,
    controls: BowControls,
    /// The smoothed force fraction of Schelleng's maximum (from pressure).
    force_fraction: f64,
    smoothing: f64,
    lift_per_sample: f64,
    /// 1 while bowing, falling to 0 as the bow lifts.
    contact: f64,
    /// The last samples' bow-point velocity (m/s) and whether the string stuck to the bow,
    /// in a ring written at `history_write`.
    velocity_history: Vec<f32>,
    sticking_history: Vec<bool>,
    history_write: usize,
}

impl BowedInstrument {
    /// Builds both tiers for `constants` (allocates), prepared at `sample_rate_hz`.
    pub fn new(
        constants: StringConstants,
        settings: BowedPlayerSettings,
        sample_rate_hz: f64,
    ) -> Result<Self, BowedConfigError> {
        let capacity = BowedCapacity::default();
        let mut rounded = BowedString::new(capacity, constants);
        let mut table = BowTableString::new(capacity, constants);
        rounded.prepare(sample_rate_hz)?;
        table.prepare(sample_rate_hz)?;
        let mut instrument = Self {
            settings,
            sample_rate_hz,
            rounded,
            table,
            impedance_n_s_m: constants.wave_impedance_n_s_m(),
            held: [0; MAX_HELD_NOTES],
            held_count: 0,
            bowing: false,
            pitch_note: 57.0,
            target_note: 57.0,
            glide_per_sample: 0.0,
            sounding_note: 57.0,
            sounding_hz: note_to_hz(57.0),
            bend_semitones: 0.0,
            vibrato_depth: 0.0,
            vibrato_phase: 0.0,
            velocity_target: bow_velocity_from_note_velocity(0.5),
            pressure: 0.5,
            position_target: 0.1,
            controls: BowControls::default(),
            force_fraction: force_fraction_from_pressure(0.5),
            smoothing: 1.0 - (-1.0 / (CONTROL_SMOOTHING_S * sample_rate_hz)).exp(),
            lift_per_sample: 0.0,
            contact: 0.0,
            velocity_history: vec![0.0; BOW_HISTORY_SAMPLES],
            sticking_history: vec![false; BOW_HISTORY_SAMPLES],
            history_write: 0,
        };
        instrument.set_settings(settings);
        instrument.reset();
        Ok(instrument)
    }

    /// Applies player settings; allocation-free. A NaN or negative time, rate, depth or range
    /// takes the default's value (a NaN glide would make the pitch NaN).
    pub fn set_settings(&mut self, mut settings: BowedPlayerSettings) {
        let default = BowedPlayerSettings::default();
        for (value, fallback) in [
            (&mut settings.glide_time_s, default.glide_time_s),
            (&mut settings.vibrato_rate_hz, default.vibrato_rate_hz),
            (&mut settings.max_vibrato_cents, default.max_vibrato_cents),
            (
                &mut settings.pitch_bend_range_semitones,
                default.pitch_bend_range_semitones,
            ),
            (&mut settings.bow_lift_time_s, default.bow_lift_time_s),
        ] {
            if !(value.is_finite() && *value >= 0.0) {
                *value = fallback;
            }
        }
        if settings.tier != self.settings.tier {
            self.rounded.reset();
            self.table.reset();
        }
        self.settings = settings;
        self.lift_per_sample = 1.0 / (settings.bow_lift_time_s.max(1e-4) * self.sample_rate_hz);
        self.rounded.set_body_enabled(settings.body_enabled);
        self.table.set_body_enabled(settings.body_enabled);
    }

    pub fn settings(&self) -> &BowedPlayerSettings {
        &self.settings
    }

    /// Silence: bow lifted, strings at rest, held notes forgotten.
    pub fn reset(&mut self) {
        self.velocity_history.fill(0.0);
        self.sticking_history.fill(false);
        self.history_write = 0;
        self.rounded.reset();
        self.table.reset();
        self.held_count = 0;
        self.bowing = false;
        self.contact = 0.0;
        self.vibrato_phase = 0.0;
        self.controls = BowControls {
            pitch_hz: note_to_hz(self.pitch_note),
            bow_force_n: 0.0,
            bow_velocity_m_s: self.velocity_target,
            bow_position: self.position_target,
        };
    }

    /// Sets the bow speed target directly, m/s (clamped to 0–5); the next expression CC or
    /// attack overrides it.
    pub fn set_bow_velocity_m_s(&mut self, velocity_m_s: f64) {
        if velocity_m_s.is_finite() {
            self.velocity_target = velocity_m_s.clamp(0.0, 5.0);
        }
    }

    /// Sets the bow position target β directly (clamped to 0.02–0.5).
    pub fn set_bow_position(&mut self, beta: f64) {
        if beta.is_finite() {
            self.position_target = beta.clamp(0.02, 0.5);
        }
    }

    /// Sets the bow pressure (0–1, see [`force_fraction_from_pressure`]).
    pub fn set_pressure(&mut self, pressure: f64) {
        if pressure.is_finite() {
            self.pressure = pressure.clamp(0.0, 1.0);
        }
    }

    /// The controls the string received at the last sample.
    pub fn controls(&self) -> BowControls {
        self.controls
    }

    /// Whether the bow is on the string (or still lifting).
    pub fn is_bowing(&self) -> bool {
        self.bowing || self.contact > 0.0
    }

    /// Applies one event (at the current sample).
    pub fn handle(&mut self, event: BowedEvent) {
        match event {
            BowedEvent::NoteOn { note, velocity } if velocity > 0.0 => {
                let legato = self.bowing && self.held_count > 0;
                self.remove_held(note);
                if self.held_count < MAX_HELD_NOTES {
                    self.held[self.held_count] = note;
                    self.held_count += 1;
                }
                self.glide_to(note as f64, legato);
                if !legato {
                    // A new attack: bow speed from the key velocity.
                    self.velocity_target = bow_velocity_from_note_velocity(velocity as f64);
                }
                self.bowing = true;
            }
            BowedEvent::NoteOn { note, .. } | BowedEvent::NoteOff { note } => {
                let was_sounding = self.held_count > 0 && self.held[self.held_count - 1] == note;
                self.remove_held(note);
                if self.held_count == 0 {
                    self.bowing = false;
                } else if was_sounding {
                    let previous = self.held[self.held_count - 1] as f64;
                    self.glide_to(previous, true);
                }
            }
            BowedEvent::Expression(value) => {
                self.velocity_target = bow_velocity_from_expression(value as f64)
            }
            BowedEvent::Pressure(value) => self.pressure = (value as f64).clamp(0.0, 1.0),
            BowedEvent::Modulation(value) => {
                self.vibrato_depth =
                    (value as f64).clamp(0.0, 1.0) * self.settings.max_vibrato_cents
            }
            BowedEvent::Timbre(value) => {
                self.position_target = bow_position_from_timbre(value as f64)
            }
            BowedEvent::PitchBend(value) => {
                self.bend_semitones =
                    (value as f64).clamp(-1.0, 1.0) * self.settings.pitch_bend_range_semitones
            }
            BowedEvent::AllNotesOff => {
                self.held_count = 0;
                self.bowing = false;
            }
        }
    }

    fn remove_held(&mut self, note: u8) {
        let mut kept = 0;
        for index in 0..self.held_count {
            if self.held[index] != note {
                self.held[kept] = self.held[index];
                kept += 1;
            }
        }
        self.held_count = kept;
    }

    fn glide_to(&mut self, note: f64, legato: bool) {
        self.target_note = note;
        if legato && self.settings.glide_time_s > 0.0 {
            self.glide_per_sample =
                (note - self.pitch_note).abs() / (self.settings.glide_time_s * self.sample_rate_hz);
        } else {
            self.pitch_note = note;
            self.glide_per_sample = 0.0;
        }
    }

    /// One output sample: the radiated bridge force, N.
    pub fn next_sample(&mut self) -> f64 {
        // Glide (linear in semitones) and vibrato.
        if self.pitch_note != self.target_note {
            let remaining = self.target_note - self.pitch_note;
            if remaining.abs() <= self.glide_per_sample {
                self.pitch_note = self.target_note;
            } else {
                self.pitch_note += self.glide_per_sample * remaining.signum();
            }
        }
        self.vibrato_phase += self.settings.vibrato_rate_hz / self.sample_rate_hz;
        if self.vibrato_phase >= 1.0 {
            self.vibrato_phase -= 1.0;
        }
        let vibrato_semitones = if self.vibrato_depth > 0.0 {
            self.vibrato_depth / 100.0 * (std::f64::consts::TAU * self.vibrato_phase).sin()
        } else {
            0.0
        };
        // powf only when the sounding note moved (glide, bend or vibrato), not every sample.
        let sounding_note = self.pitch_note + self.bend_semitones + vibrato_semitones;
        if sounding_note != self.sounding_note {
            self.sounding_note = sounding_note;
            self.sounding_hz = note_to_hz(sounding_note);
        }
        let pitch_hz = self.sounding_hz;

        // Bow contact: on while bowing, lifting linearly after the last note-off.
        self.contact = if self.bowing {
            1.0
        } else {
            (self.contact - self.lift_per_sample).max(0.0)
        };
        let a = self.smoothing;
        let c = &mut self.controls;
        c.bow_velocity_m_s += a * (self.velocity_target - c.bow_velocity_m_s);
        c.bow_position += a * (self.position_target - c.bow_position);
        self.force_fraction +=
            a * (force_fraction_from_pressure(self.pressure) - self.force_fraction);
        // The contact ramp lifts the bow smoothly; once lifted the force is exactly zero.
        c.bow_force_n = self.contact
            * schelleng_max_force_n(self.impedance_n_s_m, c.bow_velocity_m_s, c.bow_position)
            * self.force_fraction;
        c.pitch_hz = pitch_hz;
        let controls = *c;
        let voice: &mut dyn BowedVoice = match self.settings.tier {
            BowTier::RoundedCorner => &mut self.rounded,
            BowTier::BowTable => &mut self.table,
        };
        voice.set_pitch_hz(controls.pitch_hz);
        voice.set_bow_velocity_m_s(controls.bow_velocity_m_s);
        voice.set_bow_position(controls.bow_position);
        voice.set_bow_force_n(controls.bow_force_n);
        let output = voice.next_sample();
        // Sticking: the string moves with the bow (the rounded corner reports its branch; for
        // the bow table, equal velocities within 0.1 % of the bow speed).
        let sticking = match self.settings.tier {
            BowTier::RoundedCorner => {
                self.rounded.last_bow_point().state == ContactState::Sticking
                    && controls.bow_force_n > 0.0
            }
            BowTier::BowTable => {
                controls.bow_force_n > 0.0
                    && (output.bow_point_velocity_m_s - controls.bow_velocity_m_s).abs()
                        <= 1e-3 * controls.bow_velocity_m_s.abs()
            }
        };
        self.velocity_history[self.history_write] = output.bow_point_velocity_m_s as f32;
        self.sticking_history[self.history_write] = sticking;
        self.history_write = (self.history_write + 1) % BOW_HISTORY_SAMPLES;
        output.radiated
    }

    /// Copies the last [`BOW_HISTORY_SAMPLES`] bow-point velocities (m/s) and sticking flags,
    /// oldest first. Allocation-free.
    pub fn bow_history(
        &self,
        velocities: &mut [f32; BOW_HISTORY_SAMPLES],
        sticking: &mut [bool; BOW_HISTORY_SAMPLES],
    ) {
        for k in 0..BOW_HISTORY_SAMPLES {
            let index = (self.history_write + k) % BOW_HISTORY_SAMPLES;
            velocities[k] = self.velocity_history[index];
            sticking[k] = self.sticking_history[index];
        }
    }
}

/// 12-TET, A4 = 440 Hz, for fractional note numbers.
pub fn note_to_hz(note: f64) -> f64 {
    440.0 * 2f64.powf((note - 69.0) / 12.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn instrument() -> BowedInstrument {
        BowedInstrument::new(
            StringConstants::violin_a(),
            BowedPlayerSettings::default(),
            44_100.0,
        )
        .unwrap()
    }

    #[test]
    fn mappings_follow_the_documented_table() {
        assert_eq!(bow_velocity_from_note_velocity(1.0), 0.5);
        assert_eq!(bow_velocity_from_note_velocity(0.0), 0.05);
        assert!((bow_velocity_from_expression(1.0) - 0.6).abs() < 1e-15);
        assert!((bow_position_from_timbre(1.0) - 0.25).abs() < 1e-15);
        assert_eq!(force_fraction_from_pressure(0.5), 0.425);
        assert!((note_to_hz(57.0) - 220.0).abs() < 1e-9);
    }

    #[test]
    fn legato_glides_without_a_new_attack_and_returns_on_release() {
        let mut player = instrument();
        player.handle(BowedEvent::NoteOn {
            note: 57,
            velocity: 0.8,
        });
        for _ in 0..4410 {
            player.next_sample();
        }
        player.handle(BowedEvent::NoteOn {
            note: 60,
            velocity: 0.1,
        });
        let glide_samples = (0.08 * 44_100.0) as usize;
        let mut previous = player.controls().pitch_hz;
        for k in 0..glide_samples + 10 {
            player.next_sample();
            let pitch = player.controls().pitch_hz;
            assert!(pitch >= previous - 1e-9, "monotone glide at {k}");
            previous = pitch;
            if k == glide_samples / 2 {
                assert!(pitch > 225.0 && pitch < 256.0, "half way: {pitch}");
            }
        }
        assert!((previous - note_to_hz(60.0)).abs() < 1e-9);
        // Legato keeps the bow speed of the attack (velocity 0.1 did not re-attack).
        let attack_velocity = bow_velocity_from_note_velocity(0.8);
        assert!((player.controls().bow_velocity_m_s - attack_velocity).abs() < 1e-3);
        assert!(player.is_bowing());
        player.handle(BowedEvent::NoteOff { note: 60 });
        for _ in 0..glide_samples + 10 {
            player.next_sample();
        }
        assert!((player.controls().pitch_hz - 220.0).abs() < 1e-9);
        assert!(player.is_bowing());
    }

    #[test]
    fn pressure_sets_force_within_schelleng_range_and_note_off_lifts_the_bow() {
        let mut player = instrument();
        player.handle(BowedEvent::NoteOn {
            note: 57,
            velocity: 0.5,
        });
        player.handle(BowedEvent::Pressure(1.0));
        for _ in 0..8820 {
            player.next_sample();
        }
        let c = player.controls();
        let maximum = schelleng_max_force_n(
            StringConstants::violin_a().wave_impedance_n_s_m(),
            c.bow_velocity_m_s,
            c.bow_position,
        );
        assert!((c.bow_force_n / maximum - 0.8).abs() < 1e-3, "{c:?}");
        player.handle(BowedEvent::NoteOff { note: 57 });
        for _ in 0..(0.1 * 44_100.0) as usize {
            player.next_sample();
        }
        assert_eq!(player.controls().bow_force_n, 0.0);
        assert!(!player.is_bowing());
    }

    #[test]
    fn bow_history_holds_the_last_samples_oldest_first_with_sticking_in_helmholtz_motion() {
        let mut player = instrument();
        player.handle(BowedEvent::NoteOn {
            note: 57,
            velocity: 0.5,
        });
        for _ in 0..22_050 {
            player.next_sample();
        }
        let mut velocities = [0.0f32; BOW_HISTORY_SAMPLES];
        let mut sticking = [false; BOW_HISTORY_SAMPLES];
        player.bow_history(&mut velocities, &mut sticking);
        // Helmholtz motion at β = 0.1: sticking about 90 % of the time, at the bow's speed.
        let stuck = sticking.iter().filter(|&&s| s).count() as f64 / BOW_HISTORY_SAMPLES as f64;
        assert!((0.8..0.95).contains(&stuck), "{stuck}");
        let bow = player.controls().bow_velocity_m_s as f32;
        for (v, s) in velocities.iter().zip(&sticking) {
            if *s {
                assert!((v - bow).abs() < 1e-4, "{v} vs {bow}");
            }
        }
        // The newest entry is the last sample's velocity.
        let last = velocities[BOW_HISTORY_SAMPLES - 1];
        player.next_sample();
        player.bow_history(&mut velocities, &mut sticking);
        assert_eq!(velocities[BOW_HISTORY_SAMPLES - 2], last);
    }

    #[test]
    fn modulation_sets_vibrato_depth_in_cents() {
        let mut player = instrument();
        player.handle(BowedEvent::NoteOn {
            note: 69,
            velocity: 0.5,
        });
        player.handle(BowedEvent::Modulation(1.0));
        let (mut low, mut high) = (f64::MAX, f64::MIN);
        for _ in 0..44_100 {
            player.next_sample();
            let cents = 1200.0 * (player.controls().pitch_hz / 440.0).log2();
            low = low.min(cents);
            high = high.max(cents);
        }
        assert!(
            (high - 40.0).abs() < 0.1 && (low + 40.0).abs() < 0.1,
            "{low} {high}"
        );
    }
}
