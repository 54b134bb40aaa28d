//! Presets: a readable `key = value` file (a subset of TOML) mapped onto [`EngineSettings`].
//!
//! Every key names its unit. Lines are `key = value`; `#` starts a comment; strings are quoted
//! ("classic"), switches are `true`/`false`. A key left out keeps its default, so an old preset
//! keeps loading when keys are added; an unknown key, a value of the wrong kind or out of range is
//! an error naming the file, the line, the key and what was expected.
//!
//! | key | unit | range | meaning |
//! |---|---|---|---|
//! | `name` | text | | shown in the plugin |
//! | `bridge_stiffness_n_m2` | N/m² | 0–1e12 | k_b, bridge (and thread) contact stiffness |
//! | `thread_enabled` | bool | | the cotton thread (jawari) under the string |
//! | `thread_position_m` | m | 0.030–0.045 | thread position from the tuning bead |
//! | `bridge_beyond_thread` | bool | | false: no bridge contact past the thread |
//! | `gamma_per_s` | 1/s | 0–20 | frequency-independent loss γ |
//! | `eta_s` | s | 0–1e-6 | frequency-dependent loss η |
//! | `nut_pickup_weight` | 1 | 0–1 | 1: nut force, 0: bridge force |
//! | `quality` | text | draft, live, studio, reference | speed against accuracy (`quality.rs`) |
//! | `pluck_position_m` | m | 0.05–0.6 | pluck point from the tuning bead |
//! | `pluck_width_m` | m | 0.002–0.040 | fingertip width |
//! | `pluck_amplitude_m` | m | 0–0.005 | finger lift at full velocity |
//! | `output_gain_db` | dB | −60–24 | output gain |
//! | `drone_enabled` | bool | | drone mode |
//! | `drone_first_string` | text | pa, ma, ni | first drone string |
//! | `drone_tempo_sync` | bool | | follow the host tempo |
//! | `drone_tempo_bpm` | 1/min | 20–300 | tempo without sync |
//! | `instrument` | text | tanpura, bowed | which instrument plays |
//! | `bow_model` | text | rounded-corner, bow-table | the bowed tier |
//! | `bow_string` | text | violin-a, cello-d | the bowed string's constants |
//! | `bow_pressure` | 1 | 0–1 | bow force as a fraction of Schelleng's range |
//! | `bow_velocity_m_s` | m/s | 0.02–1 | bow speed |
//! | `bow_position` | 1 | 0.02–0.5 | β, bow distance from the bridge over the string length |
//! | `bow_glide_s` | s | 0–1 | legato glide time |
//! | `bow_vibrato_cents` | cents | 0–100 | vibrato depth at full modulation wheel |
//! | `bow_body` | bool | | the body resonance filter |

use super::drone::TEMPO_RANGE_BPM;
use super::{BowedStringKind, EngineSettings, Instrument, OUTPUT_GAIN_RANGE_DB};
use crate::bowed::BowTier;
use crate::tanpura::excitation::Pluck;
use crate::tanpura::geometry::ThreadSettings;
use crate::tanpura::quality::Quality;
use crate::tanpura::{FirstString, VoiceSettings};
use std::fmt;
use std::path::Path;

/// Range of the pluck position, m from the tuning bead: past the bridge and thread, short of the
/// nut (string length 0.668 m).
pub const PLUCK_POSITION_RANGE_M: (f64, f64) = (0.05, 0.6);

/// Names of the quality tiers, as written in presets ([`Quality::name`]).
pub const QUALITY_NAMES: [&str; 4] = ["draft", "live", "studio", "reference"];

/// Names of the instruments, bowed models and bowed strings, as written in presets.
pub const INSTRUMENT_NAMES: [&str; 2] = ["tanpura", "bowed"];
pub const BOW_MODEL_NAMES: [&str; 2] = ["rounded-corner", "bow-table"];
pub const BOW_STRING_NAMES: [&str; 2] = ["violin-a", "cello-d"];
pub const BOW_VELOCITY_RANGE_M_S: (f64, f64) = (0.02, 1.0);
pub const BOW_POSITION_RANGE: (f64, f64) = (0.02, 0.5);

/// Names of the first drone string's choices, as written in presets.
pub const FIRST_STRING_NAMES: [&str; 3] = ["pa", "ma", "ni"];

fn first_string_name(first: FirstString) -> &'static str {
    match first {
        FirstString::Pa => "pa",
        FirstString::Ma => "ma",
        FirstString::Ni => "ni",
    }
}

/// A named set of engine settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    pub name: String,
    pub settings: EngineSettings,
}

/// A preset that could not be read: which file, which line and key, and what was expected.
#[derive(Debug, Clone, PartialEq)]
pub struct PresetError {
    pub file: String,
    pub line: usize,
    pub field: String,
    pub expected: String,
}

impl fmt::Display for PresetError {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(formatter, "{}:{}: {}", self.file, self.line, self.expected)
        } else {
            write!(
                formatter,
                "{}:{}: `{}`: expected {}",
                self.file, self.line, self.field, self.expected
            )
        }
    }
}

impl std::error::Error for PresetError {}

impl Preset {
    /// Reads and parses a preset file.
    pub fn load(path: &Path) -> Result<Self, PresetError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| PresetError {
            file: file.clone(),
            line: 0,
            field: String::new(),
            expected: format!("a readable preset file ({error})"),
        })?;
        Self::parse(&text, &file)
    }

    /// Parses preset text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, PresetError> {
        let mut preset = Preset {
            name: String::from("unnamed"),
            settings: EngineSettings::default(),
        };
        let mut seen: Vec<String> = Vec::new();
        for (index, raw_line) in text.lines().enumerate() {
            let line_number = index + 1;
            let line = strip_comment(raw_line).trim();
            if line.is_empty() {
                continue;
            }
            let error = |field: &str, expected: String| PresetError {
                file: file.to_string(),
                line: line_number,
                field: field.to_string(),
                expected,
            };
            let Some((key, value)) = line.split_once('=') else {
                return Err(error("", format!("a `key = value` line, found `{line}`")));
            };
            let key = key.trim();
            let value = Value {
                text: value.trim(),
                key,
                make_error: &error,
            };
            if seen.iter().any(|done| done == key) {
                return Err(error(key, "each key at most once".to_string()));
            }
            seen.push(key.to_string());
            let settings = &mut preset.settings;
            match key {
                "name" => preset.name = value.string()?.to_string(),
                "bridge_stiffness_n_m2" => {
                    settings.voice.bridge_stiffness_n_m2 =
                        value.number(VoiceSettings::BRIDGE_STIFFNESS_RANGE)?
                }
                "thread_enabled" => settings.voice.thread_enabled = value.boolean()?,
                "thread_position_m" => {
                    settings.voice.thread_position_m =
                        value.number(ThreadSettings::POSITION_RANGE_M)?
                }
                "bridge_beyond_thread" => settings.voice.bridge_beyond_thread = value.boolean()?,
                "gamma_per_s" => {
                    settings.voice.gamma_per_s = value.number(VoiceSettings::GAMMA_RANGE)?
                }
                "eta_s" => settings.voice.eta_s = value.number(VoiceSettings::ETA_RANGE)?,
                "nut_pickup_weight" => {
                    settings.voice.nut_pickup_weight = value.number((0.0, 1.0))?
                }
                "quality" => {
                    let name = value.choice(&QUALITY_NAMES)?;
                    settings.voice.quality =
                        Quality::from_name(name).expect("choice() only returns listed names");
                }
                "pluck_position_m" => {
                    settings.pluck.position_m = value.number(PLUCK_POSITION_RANGE_M)?
                }
                "pluck_width_m" => settings.pluck.width_m = value.number(Pluck::WIDTH_RANGE_M)?,
                "pluck_amplitude_m" => {
                    settings.pluck.amplitude_m = value.number(Pluck::AMPLITUDE_RANGE_M)?
                }
                "output_gain_db" => settings.output_gain_db = value.number(OUTPUT_GAIN_RANGE_DB)?,
                "drone_enabled" => settings.drone.enabled = value.boolean()?,
                "drone_first_string" => {
                    settings.drone.first_string = match value.choice(&FIRST_STRING_NAMES)? {
                        "ma" => FirstString::Ma,
                        "ni" => FirstString::Ni,
                        _ => FirstString::Pa,
                    }
                }
                "drone_tempo_sync" => settings.drone.tempo_sync = value.boolean()?,
                "drone_tempo_bpm" => {
                    settings.drone.free_tempo_bpm = value.number(TEMPO_RANGE_BPM)?
                }
                "instrument" => {
                    settings.instrument = match value.choice(&INSTRUMENT_NAMES)? {
                        "bowed" => Instrument::Bowed,
                        _ => Instrument::Tanpura,
                    }
                }
                "bow_model" => {
                    settings.bowed.player.tier = match value.choice(&BOW_MODEL_NAMES)? {
                        "bow-table" => BowTier::BowTable,
                        _ => BowTier::RoundedCorner,
                    }
                }
                "bow_string" => {
                    settings.bowed.string = match value.choice(&BOW_STRING_NAMES)? {
                        "cello-d" => BowedStringKind::CelloD,
                        _ => BowedStringKind::ViolinA,
                    }
                }
                "bow_pressure" => settings.bowed.pressure = value.number((0.0, 1.0))?,
                "bow_velocity_m_s" => {
                    settings.bowed.bow_velocity_m_s = value.number(BOW_VELOCITY_RANGE_M_S)?
                }
                "bow_position" => settings.bowed.bow_position = value.number(BOW_POSITION_RANGE)?,
                "bow_glide_s" => settings.bowed.player.glide_time_s = value.number((0.0, 1.0))?,
                "bow_vibrato_cents" => {
                    settings.bowed.player.max_vibrato_cents = value.number((0.0, 100.0))?
                }
                "bow_body" => settings.bowed.player.body_enabled = value.boolean()?,
                _ => {
                    return Err(error(
                        key,
                        format!("a known key, one of: {}", KNOWN_KEYS.join(", ")),
                    ))
                }
            }
        }
        Ok(preset)
    }

    /// The preset as text that [`Preset::parse`] reads back to the same settings.
    pub fn to_text(&self) -> String {
        let s = &self.settings;
        let v = &s.voice;
        format!(
            "name = \"{}\"\n\
             bridge_stiffness_n_m2 = {:e}\n\
             thread_enabled = {}\n\
             thread_position_m = {}\n\
             bridge_beyond_thread = {}\n\
             gamma_per_s = {}\n\
             eta_s = {:e}\n\
             nut_pickup_weight = {}\n\
             quality = \"{}\"\n\
             pluck_position_m = {}\n\
             pluck_width_m = {}\n\
             pluck_amplitude_m = {}\n\
             output_gain_db = {}\n\
             drone_enabled = {}\n\
             drone_first_string = \"{}\"\n\
             drone_tempo_sync = {}\n\
             drone_tempo_bpm = {}\n\
             instrument = \"{}\"\n\
             bow_model = \"{}\"\n\
             bow_string = \"{}\"\n\
             bow_pressure = {}\n\
             bow_velocity_m_s = {}\n\
             bow_position = {}\n\
             bow_glide_s = {}\n\
             bow_vibrato_cents = {}\n\
             bow_body = {}\n",
            self.name,
            v.bridge_stiffness_n_m2,
            v.thread_enabled,
            v.thread_position_m,
            v.bridge_beyond_thread,
            v.gamma_per_s,
            v.eta_s,
            v.nut_pickup_weight,
            v.quality.name(),
            s.pluck.position_m,
            s.pluck.width_m,
            s.pluck.amplitude_m,
            s.output_gain_db,
            s.drone.enabled,
            first_string_name(s.drone.first_string),
            s.drone.tempo_sync,
            s.drone.free_tempo_bpm,
            INSTRUMENT_NAMES[s.instrument as usize],
            BOW_MODEL_NAMES[s.bowed.player.tier as usize],
            BOW_STRING_NAMES[s.bowed.string as usize],
            s.bowed.pressure,
            s.bowed.bow_velocity_m_s,
            s.bowed.bow_position,
            s.bowed.player.glide_time_s,
            s.bowed.player.max_vibrato_cents,
            s.bowed.player.body_enabled,
        )
    }
}

const KNOWN_KEYS: [&str; 26] = [
    "name",
    "bridge_stiffness_n_m2",
    "thread_enabled",
    "thread_position_m",
    "bridge_beyond_thread",
    "gamma_per_s",
    "eta_s",
    "nut_pickup_weight",
    "quality",
    "pluck_position_m",
    "pluck_width_m",
    "pluck_amplitude_m",
    "output_gain_db",
    "drone_enabled",
    "drone_first_string",
    "drone_tempo_sync",
    "drone_tempo_bpm",
    "instrument",
    "bow_model",
    "bow_string",
    "bow_pressure",
    "bow_velocity_m_s",
    "bow_position",
    "bow_glide_s",
    "bow_vibrato_cents",
    "bow_body",
];

/// Removes a `#` comment that is not inside a quoted string.
fn strip_comment(line: &str) -> &str {
    let mut in_string = false;
    for (index, character) in line.char_indices() {
        match character {
            '"' => in_string = !in_string,
            '#' if !in_string => return &line[..index],
            _ => {}
        }
    }
    line
}

struct Value<'a, E: Fn(&str, String) -> PresetError> {
    text: &'a str,
    key: &'a str,
    make_error: &'a E,
}

impl<'a, E: Fn(&str, String) -> PresetError> Value<'a, E> {
    fn fail(&self, expected: String) -> PresetError {
        (self.make_error)(self.key, format!("{expected}, found `{}`", self.text))
    }

    fn number(&self, (min, max): (f64, f64)) -> Result<f64, PresetError> {
        let expected = format!("a number from {min} to {max}");
        let value: f64 = self.text.parse().map_err(|_| self.fail(expected.clone()))?;
        if !(min <= value && value <= max) {
            return Err(self.fail(expected));
        }
        Ok(value)
    }

    fn boolean(&self) -> Result<bool, PresetError> {
        match self.text {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(self.fail("true or false".to_string())),
        }
    }

    fn string(&self) -> Result<&'a str, PresetError> {
        self.text
            .strip_prefix('"')
            .and_then(|rest| rest.strip_suffix('"'))
            .filter(|inner| !inner.contains('"'))
            .ok_or_else(|| self.fail("a quoted string".to_string()))
    }

    fn choice(&self, choices: &[&'static str]) -> Result<&'static str, PresetError> {
        let text = self.string()?;
        choices
            .iter()
            .copied()
            .find(|choice| *choice == text)
            .ok_or_else(|| self.fail(format!("one of \"{}\"", choices.join("\", \""))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_through_text() {
        let mut preset = Preset {
            name: "test".to_string(),
            settings: EngineSettings::default(),
        };
        preset.settings.voice.bridge_stiffness_n_m2 = 3.5e9;
        preset.settings.voice.thread_enabled = false;
        preset.settings.pluck.width_m = 0.02;
        preset.settings.drone.enabled = true;
        preset.settings.drone.first_string = FirstString::Ni;
        preset.settings.voice.quality = Quality::Studio;
        preset.settings.instrument = Instrument::Bowed;
        preset.settings.bowed.string = BowedStringKind::CelloD;
        preset.settings.bowed.player.tier = BowTier::BowTable;
        preset.settings.bowed.bow_position = 0.07;
        let parsed = Preset::parse(&preset.to_text(), "mem").unwrap();
        assert_eq!(parsed, preset);
    }

    #[test]
    fn out_of_range_value_names_file_line_field_and_range() {
        let error =
            Preset::parse("name = \"x\"\n\nthread_position_m = 0.2\n", "bad.toml").unwrap_err();
        let message = error.to_string();
        assert_eq!(error.line, 3);
        assert!(message.starts_with("bad.toml:3:"), "{message}");
        assert!(message.contains("`thread_position_m`"), "{message}");
        assert!(message.contains("0.03 to 0.045"), "{message}");
        assert!(message.contains("0.2"), "{message}");
    }

    #[test]
    fn wrong_kinds_and_unknown_keys_are_errors() {
        let cases = [
            ("thread_enabled = yes", "true or false"),
            (
                "quality = \"ultra\"",
                "\"draft\", \"live\", \"studio\", \"reference\"",
            ),
            ("gamma_per_s = fast", "a number from 0 to 20"),
            ("bridge_stifness = 1e8", "a known key"),
            ("just words", "`key = value`"),
            ("name = unquoted", "a quoted string"),
            ("eta_s = 1e-9\neta_s = 2e-9", "at most once"),
        ];
        for (text, expected) in cases {
            let message = Preset::parse(text, "p.toml").unwrap_err().to_string();
            assert!(message.contains(expected), "{text}: {message}");
        }
    }

    #[test]
    fn quality_names_are_the_tiers_names() {
        let names: Vec<&str> = Quality::ALL.iter().map(|quality| quality.name()).collect();
        assert_eq!(names, QUALITY_NAMES);
    }

    #[test]
    fn comments_and_missing_keys_keep_defaults() {
        let preset = Preset::parse("# comment\nname = \"a # b\" # trailing\n", "p").unwrap();
        assert_eq!(preset.name, "a # b");
        assert_eq!(preset.settings, EngineSettings::default());
    }
}
