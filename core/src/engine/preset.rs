//! Presets: a readable TOML file of top-level `key = value` lines mapped onto
//! [`EngineSettings`]. The `toml` crate reads it through serde (`PresetFile`); this module adds
//! the ranges and the error messages.
//!
//! Every key names its unit. `#` starts a comment; strings are quoted ("classic"), switches are
//! `true`/`false`, numbers may be written as integers. A key left out keeps its default, so an old
//! preset keeps loading when keys are added; an unknown key, a value of the wrong kind or out of
//! range, a repeated key or a line that is not TOML is an error naming the file, the line, the key
//! and what was expected (the parser's byte spans are turned into line numbers).
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
//! | `nut_pickup_weight` | 1 | 0–1 | with output pickup: 1: nut force, 0: bridge force |
//! | `tanpura_output` | text | pickup, radiated | the pickup forces, or the body's radiated sound |
//! | `quality` | text | live, fine, studio, reference | speed against accuracy (`quality.rs`); `draft`, a tier withdrawn in stop 62, reads as live |
//! | `pluck_position_m` | m | 0.05–0.6 | pluck point from the tuning bead |
//! | `pluck_width_m` | m | 0.002–0.040 | fingertip width |
//! | `pluck_amplitude_m` | m | 0–0.005 | finger lift at full velocity |
//! | `output_gain_db` | dB | −60–24 | output gain |
//! | `reference_a4_hz` | Hz | 415–466 | the pitch of A4 every note is tuned from |
//! | `fine_tune_cents` | cents | −100–100 | moves every note (and the drone's Sa) |
//! | `drone_enabled` | bool | | drone mode |
//! | `drone_first_string` | text | pa, ma, ni, komal-ni, dha | first drone string (`FirstString`) |
//! | `drone_pattern` | text | four, five, six | the drone's strings (`drone.rs`) |
//! | `drone_tempo_sync` | bool | | follow the host tempo |
//! | `drone_tempo_bpm` | 1/min | 20–300 | tempo without sync |
//! | `drone_pluck_spacing_beats` | beats | 0.25–4 | gap after each pluck |
//! | `drone_cycle_pause_beats` | beats | 0–8 | extra gap after the cycle's last pluck |
//! | `drone_humanize_timing_s` | s | 0–0.05 | largest timing displacement of a pluck |
//! | `drone_humanize_strength` | 1 | 0–0.5 | largest softening of a pluck |
//! | `drone_humanize_seed` | 1 | 0–4294967295 | the humanisation's seed (whole number) |
//! | `drone_sa_note` | MIDI note | 0–127 | Sa set here: the drone plays whenever drone mode is on (left out: the held note sets Sa) |
//! | `drone_string_fine_tune_cents` | cents | up to 6 of −50–50 | each drone string's fine tuning, in playing order (missing strings: 0) |
//! | `drone_string_level_db` | dB | up to 6 of −60–6 | each drone string's level |
//! | `drone_string_thread_offset_m` | m | up to 6 of −0.005–0.005 | each drone string's thread, from `thread_position_m` |
//! | `tune_as_played` | bool | | tune each string by its sustained pitch as played (`tanpura/as_played.rs`) |
//! | `stereo_width` | 1 | 0–1 | how far the strings spread over the stereo image (0: mono) |
//! | `instrument` | text | tanpura, bowed | which instrument plays |
//! | `bow_model` | text | rounded-corner, bow-table | the bowed tier |
//! | `bow_string` | text | violin-a, cello-d | the bowed string's constants |
//! | `bow_pressure` | 1 | 0–1 | bow force as a fraction of Schelleng's range |
//! | `bow_velocity_m_s` | m/s | 0.02–1 | bow speed |
//! | `bow_position` | 1 | 0.02–0.5 | β, bow distance from the bridge over the string length |
//! | `bow_glide_s` | s | 0–1 | legato glide time |
//! | `bow_vibrato_cents` | cents | 0–100 | vibrato depth at full modulation wheel |
//! | `bow_body` | bool | | the body resonance filter |

use super::drone::{
    DronePattern, CYCLE_PAUSE_RANGE_BEATS, HUMANIZE_STRENGTH_RANGE, HUMANIZE_TIMING_RANGE_S,
    MAX_DRONE_STRINGS, PLUCK_SPACING_RANGE_BEATS, STRING_FINE_TUNE_RANGE_CENTS,
    STRING_LEVEL_RANGE_DB, STRING_THREAD_OFFSET_RANGE_M, TEMPO_RANGE_BPM,
};
use super::pitch::{A4_RANGE_HZ, FINE_TUNE_RANGE_CENTS};
use super::{BowedStringKind, EngineSettings, Instrument, TanpuraOutput, OUTPUT_GAIN_RANGE_DB};
use crate::bowed::BowTier;
use crate::tanpura::excitation::Pluck;
use crate::tanpura::geometry::ThreadSettings;
use crate::tanpura::quality::Quality;
use crate::tanpura::{FirstString, VoiceSettings};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// Range of the pluck position, m from the tuning bead: past the bridge and thread, short of the
/// nut (string length 0.668 m).
pub const PLUCK_POSITION_RANGE_M: (f64, f64) = (0.05, 0.6);

/// Names of the quality tiers, as written in presets ([`Quality::name`]).
pub const QUALITY_NAMES: [&str; 4] = ["live", "fine", "studio", "reference"];

/// Names of the instruments, bowed models and bowed strings, as written in presets.
pub const INSTRUMENT_NAMES: [&str; 2] = ["tanpura", "bowed"];
pub const BOW_MODEL_NAMES: [&str; 2] = ["rounded-corner", "bow-table"];
pub const BOW_STRING_NAMES: [&str; 2] = ["violin-a", "cello-d"];
pub const BOW_VELOCITY_RANGE_M_S: (f64, f64) = (0.02, 1.0);
pub const BOW_POSITION_RANGE: (f64, f64) = (0.02, 0.5);
/// Legato glide time, s, and vibrato depth at full modulation, cents.
pub const BOW_GLIDE_RANGE_S: (f64, f64) = (0.0, 1.0);
pub const BOW_VIBRATO_RANGE_CENTS: (f64, f64) = (0.0, 100.0);

/// Names of the tanpura's outputs ([`TanpuraOutput`]), as written in presets.
pub const TANPURA_OUTPUT_NAMES: [&str; 2] = ["pickup", "radiated"];

/// Names of the first drone string's choices, as written in presets.
pub const FIRST_STRING_NAMES: [&str; 5] = ["pa", "ma", "ni", "komal-ni", "dha"];
/// Names of the drone patterns, as written in presets.
pub const DRONE_PATTERN_NAMES: [&str; 3] = ["four", "five", "six"];

fn first_string_name(first: FirstString) -> &'static str {
    let index = FirstString::ALL
        .iter()
        .position(|candidate| *candidate == first)
        .unwrap_or(0);
    FIRST_STRING_NAMES[index]
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

/// What a key's value must be.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Text,
    Switch,
    /// A number within an inclusive range.
    Number((f64, f64)),
    /// One of a few quoted words.
    Choice(&'static [&'static str]),
    /// A list of up to [`MAX_DRONE_STRINGS`] numbers, each within an inclusive range.
    Numbers((f64, f64)),
}

impl Kind {
    fn expected(self) -> String {
        match self {
            Kind::Text => "a quoted string".to_string(),
            Kind::Switch => "true or false".to_string(),
            Kind::Number((min, max)) => format!("a number from {min} to {max}"),
            Kind::Choice(choices) => format!("one of \"{}\"", choices.join("\", \"")),
            Kind::Numbers((min, max)) => {
                format!("a list of up to {MAX_DRONE_STRINGS} numbers from {min} to {max}")
            }
        }
    }
}

/// Every key and what it takes, in the order of [`PresetFile`] and of the table above.
const KEYS: [(&str, Kind); 41] = [
    ("name", Kind::Text),
    (
        "bridge_stiffness_n_m2",
        Kind::Number(VoiceSettings::BRIDGE_STIFFNESS_RANGE),
    ),
    ("thread_enabled", Kind::Switch),
    (
        "thread_position_m",
        Kind::Number(ThreadSettings::POSITION_RANGE_M),
    ),
    ("bridge_beyond_thread", Kind::Switch),
    ("gamma_per_s", Kind::Number(VoiceSettings::GAMMA_RANGE)),
    ("eta_s", Kind::Number(VoiceSettings::ETA_RANGE)),
    ("nut_pickup_weight", Kind::Number((0.0, 1.0))),
    ("tanpura_output", Kind::Choice(&TANPURA_OUTPUT_NAMES)),
    ("quality", Kind::Choice(&QUALITY_NAMES)),
    ("pluck_position_m", Kind::Number(PLUCK_POSITION_RANGE_M)),
    ("pluck_width_m", Kind::Number(Pluck::WIDTH_RANGE_M)),
    ("pluck_amplitude_m", Kind::Number(Pluck::AMPLITUDE_RANGE_M)),
    ("output_gain_db", Kind::Number(OUTPUT_GAIN_RANGE_DB)),
    ("reference_a4_hz", Kind::Number(A4_RANGE_HZ)),
    ("fine_tune_cents", Kind::Number(FINE_TUNE_RANGE_CENTS)),
    ("drone_enabled", Kind::Switch),
    ("drone_first_string", Kind::Choice(&FIRST_STRING_NAMES)),
    ("drone_pattern", Kind::Choice(&DRONE_PATTERN_NAMES)),
    ("drone_tempo_sync", Kind::Switch),
    ("drone_tempo_bpm", Kind::Number(TEMPO_RANGE_BPM)),
    (
        "drone_pluck_spacing_beats",
        Kind::Number(PLUCK_SPACING_RANGE_BEATS),
    ),
    (
        "drone_cycle_pause_beats",
        Kind::Number(CYCLE_PAUSE_RANGE_BEATS),
    ),
    (
        "drone_humanize_timing_s",
        Kind::Number(HUMANIZE_TIMING_RANGE_S),
    ),
    (
        "drone_humanize_strength",
        Kind::Number(HUMANIZE_STRENGTH_RANGE),
    ),
    ("drone_humanize_seed", Kind::Number((0.0, 4_294_967_295.0))),
    ("drone_sa_note", Kind::Number((0.0, 127.0))),
    (
        "drone_string_fine_tune_cents",
        Kind::Numbers(STRING_FINE_TUNE_RANGE_CENTS),
    ),
    (
        "drone_string_level_db",
        Kind::Numbers(STRING_LEVEL_RANGE_DB),
    ),
    (
        "drone_string_thread_offset_m",
        Kind::Numbers(STRING_THREAD_OFFSET_RANGE_M),
    ),
    ("tune_as_played", Kind::Switch),
    ("stereo_width", Kind::Number((0.0, 1.0))),
    ("instrument", Kind::Choice(&INSTRUMENT_NAMES)),
    ("bow_model", Kind::Choice(&BOW_MODEL_NAMES)),
    ("bow_string", Kind::Choice(&BOW_STRING_NAMES)),
    ("bow_pressure", Kind::Number((0.0, 1.0))),
    ("bow_velocity_m_s", Kind::Number(BOW_VELOCITY_RANGE_M_S)),
    ("bow_position", Kind::Number(BOW_POSITION_RANGE)),
    ("bow_glide_s", Kind::Number(BOW_GLIDE_RANGE_S)),
    ("bow_vibrato_cents", Kind::Number(BOW_VIBRATO_RANGE_CENTS)),
    ("bow_body", Kind::Switch),
];

fn kind_of(key: &str) -> Option<Kind> {
    KEYS.iter()
        .find(|(name, _)| *name == key)
        .map(|(_, kind)| *kind)
}

/// A preset file as TOML and serde read it: every key optional, each value with its byte span
/// in the text so that a range error can name its line. (The spans are ignored when writing.)
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct PresetFile {
    name: Option<Spanned<String>>,
    bridge_stiffness_n_m2: Option<Spanned<f64>>,
    thread_enabled: Option<Spanned<bool>>,
    thread_position_m: Option<Spanned<f64>>,
    bridge_beyond_thread: Option<Spanned<bool>>,
    gamma_per_s: Option<Spanned<f64>>,
    eta_s: Option<Spanned<f64>>,
    nut_pickup_weight: Option<Spanned<f64>>,
    tanpura_output: Option<Spanned<String>>,
    quality: Option<Spanned<String>>,
    pluck_position_m: Option<Spanned<f64>>,
    pluck_width_m: Option<Spanned<f64>>,
    pluck_amplitude_m: Option<Spanned<f64>>,
    output_gain_db: Option<Spanned<f64>>,
    reference_a4_hz: Option<Spanned<f64>>,
    fine_tune_cents: Option<Spanned<f64>>,
    drone_enabled: Option<Spanned<bool>>,
    drone_first_string: Option<Spanned<String>>,
    drone_pattern: Option<Spanned<String>>,
    drone_tempo_sync: Option<Spanned<bool>>,
    drone_tempo_bpm: Option<Spanned<f64>>,
    drone_pluck_spacing_beats: Option<Spanned<f64>>,
    drone_cycle_pause_beats: Option<Spanned<f64>>,
    drone_humanize_timing_s: Option<Spanned<f64>>,
    drone_humanize_strength: Option<Spanned<f64>>,
    drone_humanize_seed: Option<Spanned<f64>>,
    drone_sa_note: Option<Spanned<f64>>,
    drone_string_fine_tune_cents: Option<Spanned<Vec<f64>>>,
    drone_string_level_db: Option<Spanned<Vec<f64>>>,
    drone_string_thread_offset_m: Option<Spanned<Vec<f64>>>,
    tune_as_played: Option<Spanned<bool>>,
    stereo_width: Option<Spanned<f64>>,
    instrument: Option<Spanned<String>>,
    bow_model: Option<Spanned<String>>,
    bow_string: Option<Spanned<String>>,
    bow_pressure: Option<Spanned<f64>>,
    bow_velocity_m_s: Option<Spanned<f64>>,
    bow_position: Option<Spanned<f64>>,
    bow_glide_s: Option<Spanned<f64>>,
    bow_vibrato_cents: Option<Spanned<f64>>,
    bow_body: Option<Spanned<bool>>,
}

/// The 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&byte| byte == b'\n')
        .count()
        + 1
}

/// Removes a `#` comment that is not inside a quoted string (for quoting a line in an error).
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

/// Reads the values of a parsed [`PresetFile`], checking each against its [`Kind`].
struct Checker<'a> {
    text: &'a str,
    file: &'a str,
}

impl Checker<'_> {
    fn error(&self, line: usize, field: &str, expected: String) -> PresetError {
        PresetError {
            file: self.file.to_string(),
            line,
            field: field.to_string(),
            expected,
        }
    }

    /// The value at `span` is not what `key` takes.
    fn fail(&self, key: &str, span: Range<usize>) -> PresetError {
        let kind = kind_of(key).expect("every field of PresetFile is in KEYS");
        let found = self.text.get(span.clone()).unwrap_or("").trim();
        self.error(
            line_of(self.text, span.start),
            key,
            format!("{}, found `{found}`", kind.expected()),
        )
    }

    fn number(&self, key: &str, value: Option<Spanned<f64>>) -> Result<Option<f64>, PresetError> {
        let Some(value) = value else { return Ok(None) };
        let Some(Kind::Number((min, max))) = kind_of(key) else {
            unreachable!("`{key}` is a number in KEYS")
        };
        let number = *value.get_ref();
        // `!(a <= b)` rather than `a > b` so that a NaN is rejected too.
        if !(min <= number && number <= max) {
            return Err(self.fail(key, value.span()));
        }
        Ok(Some(number))
    }

    /// A list of numbers, each in its range, at most one per drone string.
    fn numbers(
        &self,
        key: &str,
        value: Option<Spanned<Vec<f64>>>,
    ) -> Result<Option<Vec<f64>>, PresetError> {
        let Some(value) = value else { return Ok(None) };
        let Some(Kind::Numbers((min, max))) = kind_of(key) else {
            unreachable!("`{key}` is a list of numbers in KEYS")
        };
        let numbers = value.get_ref();
        if numbers.len() > MAX_DRONE_STRINGS
            || !numbers.iter().all(|&number| min <= number && number <= max)
        {
            return Err(self.fail(key, value.span()));
        }
        Ok(Some(numbers.clone()))
    }

    fn choice(
        &self,
        key: &str,
        value: Option<Spanned<String>>,
    ) -> Result<Option<&'static str>, PresetError> {
        let Some(value) = value else { return Ok(None) };
        let Some(Kind::Choice(choices)) = kind_of(key) else {
            unreachable!("`{key}` is a choice in KEYS")
        };
        choices
            .iter()
            .copied()
            .find(|choice| choice == value.get_ref())
            .map(Some)
            .ok_or_else(|| self.fail(key, value.span()))
    }

    /// The parser's own error, in the preset's terms: the line its span points at and, when
    /// that line is `key = value` with a known key, what the key takes.
    fn syntax(&self, error: &toml::de::Error) -> PresetError {
        let message = error.message();
        let span = error.span().unwrap_or(0..0);
        let line = line_of(self.text, span.start);
        // For a repeated or unknown key the span is the key itself.
        let spanned_key = self
            .text
            .get(span)
            .unwrap_or("")
            .trim()
            .trim_matches(['"', '\'']);
        if message.starts_with("duplicate key") {
            return self.error(line, spanned_key, "each key at most once".to_string());
        }
        if message.starts_with("unknown field") {
            let known: Vec<&str> = KEYS.iter().map(|(name, _)| *name).collect();
            return self.error(
                line,
                spanned_key,
                format!("a known key, one of: {}", known.join(", ")),
            );
        }
        let content = self
            .text
            .lines()
            .nth(line - 1)
            .map_or("", |line| strip_comment(line).trim());
        match content.split_once('=') {
            None => self.error(line, "", format!("a `key = value` line, found `{content}`")),
            Some((key, value)) => {
                let key = key.trim();
                match kind_of(key) {
                    Some(kind) => self.error(
                        line,
                        key,
                        format!("{}, found `{}`", kind.expected(), value.trim()),
                    ),
                    None => self.error(line, key, message.trim().to_string()),
                }
            }
        }
    }
}

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
        let check = Checker { text, file };
        let read: PresetFile = toml::from_str(text).map_err(|error| check.syntax(&error))?;
        let mut preset = Preset {
            name: read
                .name
                .map_or_else(|| "unnamed".to_string(), Spanned::into_inner),
            settings: EngineSettings::default(),
        };
        let settings = &mut preset.settings;
        let voice = &mut settings.voice;
        let switch = |value: Option<Spanned<bool>>| value.map(Spanned::into_inner);
        let set = |target: &mut f64, value: Option<f64>| {
            if let Some(value) = value {
                *target = value;
            }
        };
        let set_switch = |target: &mut bool, value: Option<bool>| {
            if let Some(value) = value {
                *target = value;
            }
        };

        set(
            &mut voice.bridge_stiffness_n_m2,
            check.number("bridge_stiffness_n_m2", read.bridge_stiffness_n_m2)?,
        );
        set_switch(&mut voice.thread_enabled, switch(read.thread_enabled));
        set(
            &mut voice.thread_position_m,
            check.number("thread_position_m", read.thread_position_m)?,
        );
        set_switch(
            &mut voice.bridge_beyond_thread,
            switch(read.bridge_beyond_thread),
        );
        set(
            &mut voice.gamma_per_s,
            check.number("gamma_per_s", read.gamma_per_s)?,
        );
        set(&mut voice.eta_s, check.number("eta_s", read.eta_s)?);
        set(
            &mut voice.nut_pickup_weight,
            check.number("nut_pickup_weight", read.nut_pickup_weight)?,
        );
        if let Some(output) = check.choice("tanpura_output", read.tanpura_output)? {
            settings.tanpura_output = match output {
                "radiated" => TanpuraOutput::Radiated,
                _ => TanpuraOutput::Pickup,
            };
        }
        let voice = &mut settings.voice;
        // A preset saved while a withdrawn tier existed names it: it plays the tier that took its
        // place (`Quality::withdrawn`).
        let withdrawn = read
            .quality
            .as_ref()
            .and_then(|name| Quality::withdrawn(name.get_ref()));
        if let Some(quality) = withdrawn {
            voice.quality = quality;
        } else if let Some(name) = check.choice("quality", read.quality)? {
            voice.quality = Quality::from_name(name).expect("QUALITY_NAMES are the tiers' names");
        }
        set(
            &mut settings.pluck.position_m,
            check.number("pluck_position_m", read.pluck_position_m)?,
        );
        set(
            &mut settings.pluck.width_m,
            check.number("pluck_width_m", read.pluck_width_m)?,
        );
        set(
            &mut settings.pluck.amplitude_m,
            check.number("pluck_amplitude_m", read.pluck_amplitude_m)?,
        );
        set(
            &mut settings.output_gain_db,
            check.number("output_gain_db", read.output_gain_db)?,
        );
        set(
            &mut settings.tuning.a4_hz,
            check.number("reference_a4_hz", read.reference_a4_hz)?,
        );
        set(
            &mut settings.tuning.fine_tune_cents,
            check.number("fine_tune_cents", read.fine_tune_cents)?,
        );
        set_switch(&mut settings.drone.enabled, switch(read.drone_enabled));
        if let Some(first) = check.choice("drone_first_string", read.drone_first_string)? {
            let index = FIRST_STRING_NAMES
                .iter()
                .position(|name| *name == first)
                .unwrap_or(0);
            settings.drone.first_string = FirstString::ALL[index];
        }
        if let Some(pattern) = check.choice("drone_pattern", read.drone_pattern)? {
            let index = DRONE_PATTERN_NAMES
                .iter()
                .position(|name| *name == pattern)
                .unwrap_or(0);
            settings.drone.pattern = DronePattern::ALL[index];
        }
        set_switch(
            &mut settings.drone.tempo_sync,
            switch(read.drone_tempo_sync),
        );
        set(
            &mut settings.drone.free_tempo_bpm,
            check.number("drone_tempo_bpm", read.drone_tempo_bpm)?,
        );
        set(
            &mut settings.drone.pluck_spacing_beats,
            check.number("drone_pluck_spacing_beats", read.drone_pluck_spacing_beats)?,
        );
        set(
            &mut settings.drone.cycle_pause_beats,
            check.number("drone_cycle_pause_beats", read.drone_cycle_pause_beats)?,
        );
        set(
            &mut settings.drone.humanize_timing_s,
            check.number("drone_humanize_timing_s", read.drone_humanize_timing_s)?,
        );
        set(
            &mut settings.drone.humanize_strength,
            check.number("drone_humanize_strength", read.drone_humanize_strength)?,
        );
        if let Some(note) = check.number("drone_sa_note", read.drone_sa_note)? {
            settings.drone.sa_note = Some(note.round() as u8);
        }
        let strings = &mut settings.drone.strings;
        for (index, value) in check
            .numbers(
                "drone_string_fine_tune_cents",
                read.drone_string_fine_tune_cents,
            )?
            .unwrap_or_default()
            .into_iter()
            .enumerate()
        {
            strings[index].fine_tune_cents = value;
        }
        for (index, value) in check
            .numbers("drone_string_level_db", read.drone_string_level_db)?
            .unwrap_or_default()
            .into_iter()
            .enumerate()
        {
            strings[index].level_db = value;
        }
        for (index, value) in check
            .numbers(
                "drone_string_thread_offset_m",
                read.drone_string_thread_offset_m,
            )?
            .unwrap_or_default()
            .into_iter()
            .enumerate()
        {
            strings[index].thread_offset_m = value;
        }
        set_switch(&mut settings.tuning.as_played, switch(read.tune_as_played));
        set(
            &mut settings.stereo_width,
            check.number("stereo_width", read.stereo_width)?,
        );
        if let Some(seed) = check.number("drone_humanize_seed", read.drone_humanize_seed)? {
            // In range, so the conversion only drops a fraction.
            settings.drone.humanize_seed = seed as u32;
        }
        if let Some(instrument) = check.choice("instrument", read.instrument)? {
            settings.instrument = match instrument {
                "bowed" => Instrument::Bowed,
                _ => Instrument::Tanpura,
            };
        }
        let bowed = &mut settings.bowed;
        if let Some(model) = check.choice("bow_model", read.bow_model)? {
            bowed.player.tier = match model {
                "bow-table" => BowTier::BowTable,
                _ => BowTier::RoundedCorner,
            };
        }
        if let Some(string) = check.choice("bow_string", read.bow_string)? {
            bowed.string = match string {
                "cello-d" => BowedStringKind::CelloD,
                _ => BowedStringKind::ViolinA,
            };
        }
        set(
            &mut bowed.pressure,
            check.number("bow_pressure", read.bow_pressure)?,
        );
        set(
            &mut bowed.bow_velocity_m_s,
            check.number("bow_velocity_m_s", read.bow_velocity_m_s)?,
        );
        set(
            &mut bowed.bow_position,
            check.number("bow_position", read.bow_position)?,
        );
        set(
            &mut bowed.player.glide_time_s,
            check.number("bow_glide_s", read.bow_glide_s)?,
        );
        set(
            &mut bowed.player.max_vibrato_cents,
            check.number("bow_vibrato_cents", read.bow_vibrato_cents)?,
        );
        set_switch(&mut bowed.player.body_enabled, switch(read.bow_body));
        Ok(preset)
    }

    /// This preset with some keys set anew, each `(key, value)` written as in a preset file
    /// (`drone_pattern`, `five`; quotes around a word may be left out): what `cargo xtask render
    /// --set key=value` plays. An unknown key or a bad value is an error naming it, as in a
    /// file, with `--set` as the file's name.
    pub fn with_overrides(&self, overrides: &[(String, String)]) -> Result<Self, PresetError> {
        let mut table: toml::Table =
            toml::from_str(&self.to_text()).expect("to_text writes a TOML table");
        for (key, value) in overrides {
            let value = toml::from_str::<toml::Table>(&format!("value = {value}"))
                .ok()
                .and_then(|mut parsed| parsed.remove("value"))
                .unwrap_or_else(|| toml::Value::String(value.trim().to_string()));
            table.insert(key.trim().to_string(), value);
        }
        let text = toml::to_string(&table).expect("a table of plain values");
        Self::parse(&text, "--set")
    }

    /// The preset as TOML text that [`Preset::parse`] reads back to the same settings (every
    /// key, in the order of the table above).
    pub fn to_text(&self) -> String {
        let s = &self.settings;
        let v = &s.voice;
        let value = |value| Some(Spanned::new(0..0, value));
        let text = |text: &str| Some(Spanned::new(0..0, text.to_string()));
        let list = |values: [f64; MAX_DRONE_STRINGS]| Some(Spanned::new(0..0, values.to_vec()));
        let file = PresetFile {
            name: text(&self.name),
            bridge_stiffness_n_m2: value(v.bridge_stiffness_n_m2),
            thread_enabled: Some(Spanned::new(0..0, v.thread_enabled)),
            thread_position_m: value(v.thread_position_m),
            bridge_beyond_thread: Some(Spanned::new(0..0, v.bridge_beyond_thread)),
            gamma_per_s: value(v.gamma_per_s),
            eta_s: value(v.eta_s),
            nut_pickup_weight: value(v.nut_pickup_weight),
            tanpura_output: text(TANPURA_OUTPUT_NAMES[s.tanpura_output as usize]),
            quality: text(v.quality.name()),
            pluck_position_m: value(s.pluck.position_m),
            pluck_width_m: value(s.pluck.width_m),
            pluck_amplitude_m: value(s.pluck.amplitude_m),
            output_gain_db: value(s.output_gain_db),
            reference_a4_hz: value(s.tuning.a4_hz),
            fine_tune_cents: value(s.tuning.fine_tune_cents),
            drone_enabled: Some(Spanned::new(0..0, s.drone.enabled)),
            drone_first_string: text(first_string_name(s.drone.first_string)),
            drone_pattern: text(DRONE_PATTERN_NAMES[s.drone.pattern as usize]),
            drone_tempo_sync: Some(Spanned::new(0..0, s.drone.tempo_sync)),
            drone_tempo_bpm: value(s.drone.free_tempo_bpm),
            drone_pluck_spacing_beats: value(s.drone.pluck_spacing_beats),
            drone_cycle_pause_beats: value(s.drone.cycle_pause_beats),
            drone_humanize_timing_s: value(s.drone.humanize_timing_s),
            drone_humanize_strength: value(s.drone.humanize_strength),
            drone_humanize_seed: value(f64::from(s.drone.humanize_seed)),
            drone_sa_note: s
                .drone
                .sa_note
                .map(|note| Spanned::new(0..0, f64::from(note))),
            drone_string_fine_tune_cents: list(
                s.drone.strings.map(|string| string.fine_tune_cents),
            ),
            drone_string_level_db: list(s.drone.strings.map(|string| string.level_db)),
            drone_string_thread_offset_m: list(
                s.drone.strings.map(|string| string.thread_offset_m),
            ),
            tune_as_played: Some(Spanned::new(0..0, s.tuning.as_played)),
            stereo_width: value(s.stereo_width),
            instrument: text(INSTRUMENT_NAMES[s.instrument as usize]),
            bow_model: text(BOW_MODEL_NAMES[s.bowed.player.tier as usize]),
            bow_string: text(BOW_STRING_NAMES[s.bowed.string as usize]),
            bow_pressure: value(s.bowed.pressure),
            bow_velocity_m_s: value(s.bowed.bow_velocity_m_s),
            bow_position: value(s.bowed.bow_position),
            bow_glide_s: value(s.bowed.player.glide_time_s),
            bow_vibrato_cents: value(s.bowed.player.max_vibrato_cents),
            bow_body: Some(Spanned::new(0..0, s.bowed.player.body_enabled)),
        };
        toml::to_string(&file).expect("a flat table of numbers, strings and switches")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_keys_and_name_a_bad_one() {
        let preset = Preset {
            name: "base".to_string(),
            settings: EngineSettings::default(),
        };
        let set = |pairs: &[(&str, &str)]| {
            let pairs: Vec<(String, String)> = pairs
                .iter()
                .map(|(key, value)| (key.to_string(), value.to_string()))
                .collect();
            preset.with_overrides(&pairs)
        };
        let changed = set(&[
            ("drone_pattern", "five"),
            ("reference_a4_hz", "432"),
            ("drone_string_level_db", "[0, -3]"),
            ("tune_as_played", "false"),
            ("tanpura_output", "\"radiated\""),
        ])
        .unwrap();
        assert_eq!(changed.settings.drone.pattern, DronePattern::Five);
        assert_eq!(changed.settings.tuning.a4_hz, 432.0);
        assert_eq!(changed.settings.drone.strings[1].level_db, -3.0);
        assert!(!changed.settings.tuning.as_played);
        assert_eq!(changed.settings.tanpura_output, TanpuraOutput::Radiated);
        assert_eq!(changed.settings.voice, preset.settings.voice);
        let error = set(&[("reference_a4_hz", "500")]).unwrap_err();
        assert_eq!(
            (error.file.as_str(), error.field.as_str()),
            ("--set", "reference_a4_hz")
        );
        assert!(error.expected.contains("415"), "{error}");
        let error = set(&[("drone_strings", "4")]).unwrap_err().to_string();
        assert!(error.contains("drone_strings"), "{error}");
    }

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
        preset.settings.drone.first_string = FirstString::KomalNi;
        preset.settings.drone.pattern = DronePattern::Five;
        preset.settings.drone.humanize_seed = 4_000_000_000;
        preset.settings.drone.humanize_timing_s = 0.012;
        preset.settings.tuning.a4_hz = 432.5;
        preset.settings.tuning.fine_tune_cents = -23.0;
        preset.settings.voice.quality = Quality::Studio;
        preset.settings.tanpura_output = TanpuraOutput::Radiated;
        preset.settings.drone.sa_note = Some(55);
        preset.settings.drone.strings[2].level_db = -4.5;
        preset.settings.drone.strings[5].thread_offset_m = -0.002;
        preset.settings.tuning.as_played = false;
        preset.settings.stereo_width = 0.8;
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
                "\"live\", \"fine\", \"studio\", \"reference\"",
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
    fn errors_name_the_line_of_the_key() {
        let text = "# a comment\nname = \"x\"\ngamma_per_s = 0.5\nbridge_stifness = 1e8\n";
        let error = Preset::parse(text, "p.toml").unwrap_err();
        assert_eq!((error.line, error.field.as_str()), (4, "bridge_stifness"));
        let error = Preset::parse("eta_s = 1e-9\n\neta_s = 2e-9\n", "p.toml").unwrap_err();
        assert_eq!((error.line, error.field.as_str()), (3, "eta_s"));
        let error = Preset::parse("name = \"x\"\nbow_body = 1\n", "p.toml").unwrap_err();
        let message = error.to_string();
        assert!(message.starts_with("p.toml:2: `bow_body`: expected true or false, found `1`"));
        let error = Preset::parse("name = \"x\"\nbow_model = \"violin\"\n", "p.toml");
        let message = error.unwrap_err().to_string();
        assert!(message.starts_with("p.toml:2: `bow_model`"), "{message}");
        assert!(
            message.contains("\"rounded-corner\", \"bow-table\""),
            "{message}"
        );
    }

    #[test]
    fn integers_and_any_name_are_read() {
        let preset = Preset::parse("bow_vibrato_cents = 30\ndrone_tempo_bpm = 72\n", "p").unwrap();
        assert_eq!(preset.settings.bowed.player.max_vibrato_cents, 30.0);
        assert_eq!(preset.settings.drone.free_tempo_bpm, 72.0);
        let preset = Preset {
            name: "quote \" hash # backslash \\".to_string(),
            settings: EngineSettings::default(),
        };
        assert_eq!(Preset::parse(&preset.to_text(), "mem").unwrap(), preset);
    }

    #[test]
    fn text_lists_every_key_in_order() {
        let mut settings = EngineSettings::default();
        // `drone_sa_note` is written only when Sa is set (left out, the held note sets it).
        settings.drone.sa_note = Some(48);
        let text = Preset {
            name: "all".to_string(),
            settings,
        }
        .to_text();
        let keys: Vec<&str> = text
            .lines()
            .filter_map(|line| line.split_once(" = ").map(|(key, _)| key))
            .collect();
        let expected: Vec<&str> = KEYS.iter().map(|(key, _)| *key).collect();
        assert_eq!(keys, expected);
    }

    /// A preset saved while the draft tier existed loads with the live tier that replaced it,
    /// and is written back with live's name.
    #[test]
    fn a_preset_naming_the_withdrawn_draft_tier_loads_as_live() {
        let parsed = Preset::parse("name = \"old\"\nquality = \"draft\"\n", "old.toml").unwrap();
        assert_eq!(parsed.settings.voice.quality, Quality::Live);
        assert!(parsed.to_text().contains("quality = \"live\""));
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
