//! The plugin's parameters: stable short IDs, units, ranges, and their mapping onto the engine's
//! SI settings. This is the only place where host-facing units (mm, ns, decades) appear.
//!
//! Smoothing happens in the engine, in SI units (`javari_core::engine`, 20 ms ramps at a control
//! rate), so the host parameters carry no smoother of their own.
//!
//! | ID | name | unit | range | default | meaning |
//! |---|---|---|---|---|---|
//! | `preset` | Preset | | Custom, Classic, No thread, Bright jawari, Soft, Bowed violin, Bowed cello, Sul ponticello, Flautando | Custom | factory preset; anything but Custom overrides the sound parameters below (not gain) |
//! | `thon` | Thread | on/off | | on | cotton thread (jawari) between string and bridge |
//! | `thpos` | Thread position | mm | 30–45 | 40 | thread distance from the tuning bead |
//! | `kb` | Bridge stiffness | log10(N/m²) | 5–11 | 8 | k_b = 10^value N/m² (log scale) |
//! | `brbt` | Bridge beyond thread | on/off | | on | off: k_b = 0 past the thread |
//! | `gamma` | Damping | 1/s | 0–20 | 0.6 | γ, frequency-independent loss (sustain) |
//! | `eta` | HF damping | ns | 0–1000 | 7 | η, frequency-dependent loss (darkness) |
//! | `plpos` | Pluck position | mm | 50–600 | 350 | pluck point from the tuning bead |
//! | `plwid` | Pluck width | mm | 2–40 | 10 | fingertip width |
//! | `plamp` | Pluck amplitude | mm | 0–5 | 2 | finger lift at full velocity |
//! | `tout` | Tanpura output | | Radiated, Pickup | Radiated | the body's radiated sound (the total bridge force through the tanpura body of `core/src/tanpura/body.rs`), or the pickup forces below |
//! | `pick` | Pickup | % nut | 0–100 | 100 | with output Pickup: 100: nut force, 0: bridge force |
//! | `qual` | Quality | | Live, Fine, Studio, Reference | Fine | the core's tiers (`core/src/tanpura/quality.rs`); not part of the factory presets; a state saved with the withdrawn Draft loads as Live |
//! | `gain` | Output gain | dB | −60–24 | 0 | after 2 N = full scale |
//! | `drone` | Drone | on/off | | off | a held note sets Sa and the strings play the cycle |
//! | `first` | First string | | Pa, Ma, Ni, komal Ni, Dha | Pa | first drone string: 3/4, 2/3, 15/16, 8/9 or 5/6 of Sa (just intonation) |
//! | `a4` | Reference A4 | Hz | 415–466 | 440 | the pitch of A4 every note is tuned from |
//! | `fine` | Fine tuning | cents | −100–100 | 0 | moves every note (and the drone's Sa) |
//! | `dpat` | Drone strings | | 4, 5, 6 strings | 4 strings | Pa Sa Sa sa; Pa Ni Sa Sa sa; Pa Pa Sa Sa sa sa (with the first string's note for Pa) |
//! | `dspace` | Pluck spacing | beats | 0.25–4 | 1 | gap after each pluck |
//! | `dpause` | Cycle pause | beats | 0–8 | 1 | extra gap after the cycle's last pluck |
//! | `dhtime` | Humanise timing | ms | 0–50 | 0 | largest displacement of a pluck |
//! | `dhstr` | Humanise strength | % | 0–50 | 0 | largest softening of a pluck |
//! | `dseed` | Humanise seed | | 0–9999 | 0 | the same seed plays the same way |
//! | `dsync` | Drone tempo sync | on/off | | on | follow the host's tempo |
//! | `dbpm` | Drone tempo | bpm | 20–300 | 60 | tempo without sync |
//! | `inst` | Instrument | | Tanpura, Bowed | Tanpura | plucked tanpura strings or one bowed string |
//! | `bmodel` | Bow model | | Rounded corner, Bow table | Rounded corner | the bowed tier: McIntyre–Schumacher–Woodhouse, or STK's bow table |
//! | `bstr` | Bowed string | | Violin A, Cello D | Violin A | the bowed string's tension, density and losses |
//! | `bpres` | Bow pressure | % | 0–100 | 50 | bow force as a fraction of Schelleng's range for the current bow speed and position; MIDI pressure moves it too |
//! | `bvel` | Bow speed | m/s | 0.02–1 | 0.2 | bow velocity; key velocity and CC 11 move it too |
//! | `bpos` | Bow position | β | 0.02–0.5 | 0.1 | distance from the bridge over the string length; CC 74 moves it too |
//! | `glide` | Legato glide | ms | 0–1000 | 80 | glide time between legato notes |
//! | `vib` | Vibrato depth | cents | 0–100 | 40 | vibrato at full modulation wheel (CC 1) |
//! | `body` | Body | on/off | | on | the violin-body resonance filter |

use javari_core::bowed::{BowTier, BowedPlayerSettings};
use javari_core::engine::drone::{
    DronePattern, DroneString, CYCLE_PAUSE_RANGE_BEATS, HUMANIZE_STRENGTH_RANGE,
    HUMANIZE_TIMING_RANGE_S, MAX_DRONE_STRINGS, PLUCK_SPACING_RANGE_BEATS,
    STRING_FINE_TUNE_RANGE_CENTS, STRING_LEVEL_RANGE_DB, STRING_THREAD_OFFSET_RANGE_M,
    TEMPO_RANGE_BPM,
};
use javari_core::engine::pitch::{Tuning, A4_HZ, A4_RANGE_HZ, FINE_TUNE_RANGE_CENTS};
use javari_core::engine::preset::{
    Preset, BOW_POSITION_RANGE, BOW_VELOCITY_RANGE_M_S, PLUCK_POSITION_RANGE_M,
};
use javari_core::engine::{
    BowedEngineSettings, BowedStringKind, EngineSettings, Instrument, TanpuraOutput,
    OUTPUT_GAIN_RANGE_DB,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::geometry::ThreadSettings;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{FirstString, VoiceSettings};
use nice_plug::prelude::*;
use std::sync::Arc;

/// Factory preset selector. `Custom` plays the knobs.
#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum PresetChoice {
    #[id = "custom"]
    Custom,
    #[id = "classic"]
    Classic,
    #[id = "no-thread"]
    #[name = "No thread"]
    NoThread,
    #[id = "bright-jawari"]
    #[name = "Bright jawari"]
    BrightJawari,
    #[id = "soft"]
    Soft,
    #[id = "bowed-violin"]
    #[name = "Bowed violin"]
    BowedViolin,
    #[id = "bowed-cello"]
    #[name = "Bowed cello"]
    BowedCello,
    #[id = "bowed-sul-ponticello"]
    #[name = "Sul ponticello"]
    SulPonticello,
    #[id = "bowed-flautando"]
    #[name = "Flautando"]
    Flautando,
    #[id = "male-tanpura"]
    #[name = "Male tanpura"]
    MaleTanpura,
    #[id = "female-tanpura"]
    #[name = "Female tanpura"]
    FemaleTanpura,
    #[id = "five-string-tanpura"]
    #[name = "Five-string tanpura"]
    FiveString,
    #[id = "tanpura-ma"]
    #[name = "Tanpura in Ma"]
    TanpuraMa,
}

#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum InstrumentChoice {
    #[id = "tanpura"]
    Tanpura,
    #[id = "bowed"]
    Bowed,
}

#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum BowModelChoice {
    #[id = "rounded-corner"]
    #[name = "Rounded corner"]
    RoundedCorner,
    #[id = "bow-table"]
    #[name = "Bow table"]
    BowTable,
}

#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum BowedStringChoice {
    #[id = "violin-a"]
    #[name = "Violin A"]
    ViolinA,
    #[id = "cello-d"]
    #[name = "Cello D"]
    CelloD,
}

/// The core's quality tiers (`core/src/tanpura/quality.rs`), cheapest first; each variant's ID is
/// the tier's name. The draft tier, withdrawn in stop 62, left the list: a host's automation of
/// this parameter recorded before then reads one tier up (its plain value is the variant's
/// index), and a saved state's `"draft"` is migrated to live (`state::repair`).
#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum QualityChoice {
    #[id = "live"]
    Live,
    #[id = "fine"]
    Fine,
    #[id = "studio"]
    Studio,
    #[id = "reference"]
    Reference,
}

impl QualityChoice {
    /// The core's tier this choice plays.
    pub fn quality(self) -> Quality {
        match self {
            QualityChoice::Live => Quality::Live,
            QualityChoice::Fine => Quality::Fine,
            QualityChoice::Studio => Quality::Studio,
            QualityChoice::Reference => Quality::Reference,
        }
    }
}

/// What the tanpura's output is (`javari_core::engine::TanpuraOutput`).
#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum TanpuraOutputChoice {
    #[id = "radiated"]
    Radiated,
    #[id = "pickup"]
    Pickup,
}

#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstStringChoice {
    #[id = "pa"]
    Pa,
    #[id = "ma"]
    Ma,
    #[id = "ni"]
    Ni,
    #[id = "komal-ni"]
    #[name = "komal Ni"]
    KomalNi,
    #[id = "dha"]
    Dha,
}

/// The drone's strings (`javari_core::engine::drone::DronePattern`).
#[derive(Enum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum DronePatternChoice {
    #[id = "four"]
    #[name = "4 strings"]
    Four,
    #[id = "five"]
    #[name = "5 strings"]
    Five,
    #[id = "six"]
    #[name = "6 strings"]
    Six,
}

const MM_PER_M: f64 = 1000.0;

const NOTE_NAMES: [&str; 12] = [
    "C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B",
];

/// A MIDI note's name with its octave, middle C = C4 (48: "C3").
fn note_name(note: i32) -> String {
    format!(
        "{}{}",
        NOTE_NAMES[note.rem_euclid(12) as usize],
        note.div_euclid(12) - 1
    )
}

/// A note name ("G3", "F#2", "c4") or a MIDI number back to the note.
fn parse_note_name(text: &str) -> Option<i32> {
    let text = text.trim();
    if let Ok(number) = text.parse::<i32>() {
        return Some(number);
    }
    let split = text.find(|c: char| c == '-' || c.is_ascii_digit())?;
    let (name, octave) = text.split_at(split);
    let pitch = NOTE_NAMES
        .iter()
        .position(|candidate| candidate.eq_ignore_ascii_case(name))?;
    let octave: i32 = octave.parse().ok()?;
    Some((octave + 1) * 12 + pitch as i32)
}
const NS_PER_S: f64 = 1e9;

fn millimetres(range_m: (f64, f64)) -> FloatRange {
    linear((range_m.0 * MM_PER_M, range_m.1 * MM_PER_M))
}

/// A linear parameter range over an engine's `(min, max)` range.
fn linear(range: (f64, f64)) -> FloatRange {
    FloatRange::Linear {
        min: range.0 as f32,
        max: range.1 as f32,
    }
}

/// One drone string's own fine tuning, level and thread offset (`DroneString`), shown in the
/// host as the group "Drone string N".
#[derive(Params)]
pub struct DroneStringParams {
    #[id = "stune"]
    pub fine_tune_cents: FloatParam,
    #[id = "slevel"]
    pub level_db: FloatParam,
    #[id = "sthread"]
    pub thread_offset_mm: FloatParam,
}

impl Default for DroneStringParams {
    fn default() -> Self {
        Self {
            fine_tune_cents: FloatParam::new(
                "String fine tuning",
                0.0,
                linear(STRING_FINE_TUNE_RANGE_CENTS),
            )
            .with_unit(" cents")
            .with_step_size(0.1),
            level_db: FloatParam::new("String level", 0.0, linear(STRING_LEVEL_RANGE_DB))
                .with_unit(" dB")
                .with_step_size(0.1),
            thread_offset_mm: FloatParam::new(
                "String thread offset",
                0.0,
                millimetres(STRING_THREAD_OFFSET_RANGE_M),
            )
            .with_unit(" mm")
            .with_step_size(0.01),
        }
    }
}

impl DroneStringParams {
    fn settings(&self) -> DroneString {
        DroneString {
            fine_tune_cents: f64::from(self.fine_tune_cents.value()),
            level_db: f64::from(self.level_db.value()),
            thread_offset_m: f64::from(self.thread_offset_mm.value()) / MM_PER_M,
        }
    }
}

#[derive(Params)]
pub struct JavariParams {
    #[id = "preset"]
    pub preset: EnumParam<PresetChoice>,
    #[id = "thon"]
    pub thread_enabled: BoolParam,
    #[id = "thpos"]
    pub thread_position_mm: FloatParam,
    #[id = "kb"]
    pub bridge_stiffness_log10: FloatParam,
    #[id = "brbt"]
    pub bridge_beyond_thread: BoolParam,
    #[id = "gamma"]
    pub gamma_per_s: FloatParam,
    #[id = "eta"]
    pub eta_ns: FloatParam,
    #[id = "plpos"]
    pub pluck_position_mm: FloatParam,
    #[id = "plwid"]
    pub pluck_width_mm: FloatParam,
    #[id = "plamp"]
    pub pluck_amplitude_mm: FloatParam,
    #[id = "tout"]
    pub tanpura_output: EnumParam<TanpuraOutputChoice>,
    #[id = "pick"]
    pub nut_pickup_percent: FloatParam,
    #[id = "qual"]
    pub quality: EnumParam<QualityChoice>,
    #[id = "gain"]
    pub output_gain_db: FloatParam,
    #[id = "drone"]
    pub drone_enabled: BoolParam,
    #[id = "first"]
    pub drone_first_string: EnumParam<FirstStringChoice>,
    #[id = "dsync"]
    pub drone_tempo_sync: BoolParam,
    #[id = "dbpm"]
    pub drone_tempo_bpm: FloatParam,
    #[id = "a4"]
    pub reference_a4_hz: FloatParam,
    #[id = "fine"]
    pub fine_tune_cents: FloatParam,
    #[id = "dpat"]
    pub drone_pattern: EnumParam<DronePatternChoice>,
    #[id = "dspace"]
    pub drone_spacing_beats: FloatParam,
    #[id = "dpause"]
    pub drone_pause_beats: FloatParam,
    #[id = "dhtime"]
    pub drone_humanize_ms: FloatParam,
    #[id = "dhstr"]
    pub drone_humanize_percent: FloatParam,
    #[id = "dseed"]
    pub drone_seed: IntParam,
    /// Sa set here (the drone plays whenever drone mode is on) instead of by a held note.
    #[id = "dsafix"]
    pub drone_sa_fixed: BoolParam,
    #[id = "dsa"]
    pub drone_sa_note: IntParam,
    #[nested(array, group = "Drone string")]
    pub drone_strings: [DroneStringParams; MAX_DRONE_STRINGS],
    /// Tune each string by its sustained pitch as played, and set the jawari (move its thread by
    /// up to 0.3 mm) of one whose soft and firm plucks would not settle (measured on a background
    /// thread; `javari_core::tanpura::as_played`).
    #[id = "asplay"]
    pub tune_as_played: BoolParam,
    #[id = "width"]
    pub stereo_width_percent: FloatParam,
    #[id = "inst"]
    pub instrument: EnumParam<InstrumentChoice>,
    #[id = "bmodel"]
    pub bow_model: EnumParam<BowModelChoice>,
    #[id = "bstr"]
    pub bowed_string: EnumParam<BowedStringChoice>,
    #[id = "bpres"]
    pub bow_pressure_percent: FloatParam,
    #[id = "bvel"]
    pub bow_velocity_m_s: FloatParam,
    #[id = "bpos"]
    pub bow_position: FloatParam,
    #[id = "glide"]
    pub glide_ms: FloatParam,
    #[id = "vib"]
    pub vibrato_cents: FloatParam,
    #[id = "body"]
    pub body_enabled: BoolParam,
}

impl Default for JavariParams {
    fn default() -> Self {
        let voice = VoiceSettings::default();
        let pluck = Pluck::default();
        let bowed = BowedEngineSettings::default();
        Self {
            preset: EnumParam::new("Preset", PresetChoice::Custom),
            thread_enabled: BoolParam::new("Thread", voice.thread_enabled),
            thread_position_mm: FloatParam::new(
                "Thread position",
                (voice.thread_position_m * MM_PER_M) as f32,
                millimetres(ThreadSettings::POSITION_RANGE_M),
            )
            .with_unit(" mm")
            .with_step_size(0.01),
            bridge_stiffness_log10: FloatParam::new(
                "Bridge stiffness",
                voice.bridge_stiffness_n_m2.log10() as f32,
                FloatRange::Linear {
                    min: BRIDGE_STIFFNESS_LOG10_RANGE.0,
                    max: BRIDGE_STIFFNESS_LOG10_RANGE.1,
                },
            )
            .with_value_to_string(Arc::new(|log10| {
                format!("{:.2e} N/m²", 10f64.powf(f64::from(log10)))
            }))
            .with_string_to_value(Arc::new(|text| {
                let number: f64 = text.trim().trim_end_matches("N/m²").trim().parse().ok()?;
                (number > 0.0).then(|| number.log10() as f32)
            })),
            bridge_beyond_thread: BoolParam::new(
                "Bridge beyond thread",
                voice.bridge_beyond_thread,
            ),
            gamma_per_s: FloatParam::new(
                "Damping",
                voice.gamma_per_s as f32,
                FloatRange::Skewed {
                    min: VoiceSettings::GAMMA_RANGE.0 as f32,
                    max: VoiceSettings::GAMMA_RANGE.1 as f32,
                    factor: FloatRange::skew_factor(-2.0),
                },
            )
            .with_unit(" 1/s")
            .with_step_size(0.001),
            eta_ns: FloatParam::new(
                "HF damping",
                (voice.eta_s * NS_PER_S) as f32,
                FloatRange::Skewed {
                    min: (VoiceSettings::ETA_RANGE.0 * NS_PER_S) as f32,
                    max: (VoiceSettings::ETA_RANGE.1 * NS_PER_S) as f32,
                    factor: FloatRange::skew_factor(-2.0),
                },
            )
            .with_unit(" ns")
            .with_step_size(0.01),
            pluck_position_mm: FloatParam::new(
                "Pluck position",
                (pluck.position_m * MM_PER_M) as f32,
                millimetres(PLUCK_POSITION_RANGE_M),
            )
            .with_unit(" mm")
            .with_step_size(0.1),
            pluck_width_mm: FloatParam::new(
                "Pluck width",
                (pluck.width_m * MM_PER_M) as f32,
                millimetres(Pluck::WIDTH_RANGE_M),
            )
            .with_unit(" mm")
            .with_step_size(0.1),
            pluck_amplitude_mm: FloatParam::new(
                "Pluck amplitude",
                (pluck.amplitude_m * MM_PER_M) as f32,
                millimetres(Pluck::AMPLITUDE_RANGE_M),
            )
            .with_unit(" mm")
            .with_step_size(0.01),
            nut_pickup_percent: FloatParam::new(
                "Pickup",
                (voice.nut_pickup_weight * 100.0) as f32,
                FloatRange::Linear {
                    min: 0.0,
                    max: 100.0,
                },
            )
            .with_unit(" % nut")
            .with_step_size(0.1),
            // Live by default: a DAW needs real time; the renderer defaults to Reference.
            quality: EnumParam::new("Quality", QualityChoice::Fine),
            tanpura_output: EnumParam::new("Tanpura output", TanpuraOutputChoice::Radiated),
            output_gain_db: FloatParam::new("Output gain", 0.0, linear(OUTPUT_GAIN_RANGE_DB))
                .with_unit(" dB")
                .with_step_size(0.1),
            drone_enabled: BoolParam::new("Drone", false),
            drone_first_string: EnumParam::new("First string", FirstStringChoice::Pa),
            drone_tempo_sync: BoolParam::new("Drone tempo sync", true),
            drone_tempo_bpm: FloatParam::new("Drone tempo", 60.0, linear(TEMPO_RANGE_BPM))
                .with_unit(" bpm")
                .with_step_size(0.1),
            reference_a4_hz: FloatParam::new("Reference A4", A4_HZ as f32, linear(A4_RANGE_HZ))
                .with_unit(" Hz")
                .with_step_size(0.1),
            fine_tune_cents: FloatParam::new("Fine tuning", 0.0, linear(FINE_TUNE_RANGE_CENTS))
                .with_unit(" cents")
                .with_step_size(0.1),
            drone_pattern: EnumParam::new("Drone strings", DronePatternChoice::Four),
            drone_spacing_beats: FloatParam::new(
                "Pluck spacing",
                1.0,
                linear(PLUCK_SPACING_RANGE_BEATS),
            )
            .with_unit(" beats")
            .with_step_size(0.05),
            drone_pause_beats: FloatParam::new("Cycle pause", 1.0, linear(CYCLE_PAUSE_RANGE_BEATS))
                .with_unit(" beats")
                .with_step_size(0.05),
            drone_humanize_ms: FloatParam::new(
                "Humanise timing",
                0.0,
                FloatRange::Linear {
                    min: 0.0,
                    max: (HUMANIZE_TIMING_RANGE_S.1 * 1000.0) as f32,
                },
            )
            .with_unit(" ms")
            .with_step_size(0.5),
            drone_humanize_percent: FloatParam::new(
                "Humanise strength",
                0.0,
                FloatRange::Linear {
                    min: 0.0,
                    max: (HUMANIZE_STRENGTH_RANGE.1 * 100.0) as f32,
                },
            )
            .with_unit(" %")
            .with_step_size(1.0),
            drone_seed: IntParam::new("Humanise seed", 0, IntRange::Linear { min: 0, max: 9999 }),
            drone_sa_fixed: BoolParam::new("Drone Sa set here", false),
            drone_sa_note: IntParam::new("Drone Sa", 48, IntRange::Linear { min: 24, max: 84 })
                .with_value_to_string(Arc::new(note_name))
                .with_string_to_value(Arc::new(|text: &str| parse_note_name(text))),
            drone_strings: Default::default(),
            tune_as_played: BoolParam::new("Tune as played", true),
            stereo_width_percent: FloatParam::new(
                "Stereo width",
                (javari_core::engine::DEFAULT_STEREO_WIDTH * 100.0) as f32,
                FloatRange::Linear {
                    min: 0.0,
                    max: 100.0,
                },
            )
            .with_unit(" %")
            .with_step_size(1.0),
            instrument: EnumParam::new("Instrument", InstrumentChoice::Tanpura),
            bow_model: EnumParam::new("Bow model", BowModelChoice::RoundedCorner),
            bowed_string: EnumParam::new("Bowed string", BowedStringChoice::ViolinA),
            bow_pressure_percent: FloatParam::new(
                "Bow pressure",
                (bowed.pressure * 100.0) as f32,
                FloatRange::Linear {
                    min: 0.0,
                    max: 100.0,
                },
            )
            .with_unit(" %")
            .with_step_size(0.1),
            bow_velocity_m_s: FloatParam::new(
                "Bow speed",
                bowed.bow_velocity_m_s as f32,
                FloatRange::Skewed {
                    min: BOW_VELOCITY_RANGE_M_S.0 as f32,
                    max: BOW_VELOCITY_RANGE_M_S.1 as f32,
                    factor: FloatRange::skew_factor(-1.0),
                },
            )
            .with_unit(" m/s")
            .with_step_size(0.001),
            bow_position: FloatParam::new(
                "Bow position",
                bowed.bow_position as f32,
                FloatRange::Skewed {
                    min: BOW_POSITION_RANGE.0 as f32,
                    max: BOW_POSITION_RANGE.1 as f32,
                    factor: FloatRange::skew_factor(-1.0),
                },
            )
            .with_unit(" β")
            .with_step_size(0.001),
            glide_ms: FloatParam::new(
                "Legato glide",
                (bowed.player.glide_time_s * 1000.0) as f32,
                FloatRange::Linear {
                    min: 0.0,
                    max: 1000.0,
                },
            )
            .with_unit(" ms")
            .with_step_size(1.0),
            vibrato_cents: FloatParam::new(
                "Vibrato depth",
                bowed.player.max_vibrato_cents as f32,
                FloatRange::Linear {
                    min: 0.0,
                    max: 100.0,
                },
            )
            .with_unit(" cents")
            .with_step_size(0.1),
            body_enabled: BoolParam::new("Body", bowed.player.body_enabled),
        }
    }
}

/// Range of the `kb` parameter: k_b from 1e5 to 1e11 N/m² (a soft to a very hard bridge).
pub const BRIDGE_STIFFNESS_LOG10_RANGE: (f32, f32) = (5.0, 11.0);

impl JavariParams {
    /// The engine settings the parameters describe; a factory preset other than `Custom`
    /// replaces the sound (every parameter but quality, output gain and the drone controls; a
    /// drone preset brings its drone too).
    pub fn engine_settings(&self, factory: &[Preset; FACTORY_PRESET_COUNT]) -> EngineSettings {
        let gain_db = f64::from(self.output_gain_db.value());
        let drone_from_knobs = javari_core::engine::drone::DroneSettings {
            enabled: self.drone_enabled.value(),
            first_string: match self.drone_first_string.value() {
                FirstStringChoice::Pa => FirstString::Pa,
                FirstStringChoice::Ma => FirstString::Ma,
                FirstStringChoice::Ni => FirstString::Ni,
                FirstStringChoice::KomalNi => FirstString::KomalNi,
                FirstStringChoice::Dha => FirstString::Dha,
            },
            pattern: match self.drone_pattern.value() {
                DronePatternChoice::Four => DronePattern::Four,
                DronePatternChoice::Five => DronePattern::Five,
                DronePatternChoice::Six => DronePattern::Six,
            },
            tempo_sync: self.drone_tempo_sync.value(),
            free_tempo_bpm: f64::from(self.drone_tempo_bpm.value()),
            pluck_spacing_beats: f64::from(self.drone_spacing_beats.value()),
            cycle_pause_beats: f64::from(self.drone_pause_beats.value()),
            humanize_timing_s: f64::from(self.drone_humanize_ms.value()) / 1000.0,
            humanize_strength: f64::from(self.drone_humanize_percent.value()) / 100.0,
            humanize_seed: self.drone_seed.value().max(0) as u32,
            strings: std::array::from_fn(|index| self.drone_strings[index].settings()),
            sa_note: self
                .drone_sa_fixed
                .value()
                .then(|| self.drone_sa_note.value().clamp(0, 127) as u8),
        };
        let preset = match self.preset.value() {
            PresetChoice::Custom => None,
            PresetChoice::Classic => Some(&factory[0]),
            PresetChoice::NoThread => Some(&factory[1]),
            PresetChoice::BrightJawari => Some(&factory[2]),
            PresetChoice::Soft => Some(&factory[3]),
            PresetChoice::BowedViolin => Some(&factory[4]),
            PresetChoice::BowedCello => Some(&factory[5]),
            PresetChoice::SulPonticello => Some(&factory[6]),
            PresetChoice::Flautando => Some(&factory[7]),
            PresetChoice::MaleTanpura => Some(&factory[8]),
            PresetChoice::FemaleTanpura => Some(&factory[9]),
            PresetChoice::FiveString => Some(&factory[10]),
            PresetChoice::TanpuraMa => Some(&factory[11]),
        };
        let quality = self.quality.value().quality();
        let tanpura_output = match self.tanpura_output.value() {
            TanpuraOutputChoice::Radiated => TanpuraOutput::Radiated,
            TanpuraOutputChoice::Pickup => TanpuraOutput::Pickup,
        };
        let tuning = Tuning {
            a4_hz: f64::from(self.reference_a4_hz.value()),
            fine_tune_cents: f64::from(self.fine_tune_cents.value()),
            as_played: self.tune_as_played.value(),
        };
        let stereo_width = f64::from(self.stereo_width_percent.value()) / 100.0;
        if let Some(preset) = preset {
            let mut settings = preset.settings;
            settings.tuning = tuning;
            settings.voice.quality = quality;
            settings.tanpura_output = tanpura_output;
            settings.stereo_width = stereo_width;
            settings.output_gain_db += gain_db;
            // A drone preset brings its drone (pattern, first string, cycle, strings); any other
            // keeps the drone knobs.
            if !preset.settings.drone.enabled {
                settings.drone = drone_from_knobs;
            }
            return settings;
        }
        let voice = VoiceSettings {
            thread_enabled: self.thread_enabled.value(),
            thread_position_m: f64::from(self.thread_position_mm.value()) / MM_PER_M,
            bridge_stiffness_n_m2: 10f64.powf(f64::from(self.bridge_stiffness_log10.value())),
            bridge_beyond_thread: self.bridge_beyond_thread.value(),
            gamma_per_s: f64::from(self.gamma_per_s.value()),
            eta_s: f64::from(self.eta_ns.value()) / NS_PER_S,
            nut_pickup_weight: f64::from(self.nut_pickup_percent.value()) / 100.0,
            quality,
            ..VoiceSettings::default()
        };
        EngineSettings {
            voice,
            pluck: Pluck {
                position_m: f64::from(self.pluck_position_mm.value()) / MM_PER_M,
                width_m: f64::from(self.pluck_width_mm.value()) / MM_PER_M,
                amplitude_m: f64::from(self.pluck_amplitude_mm.value()) / MM_PER_M,
            },
            output_gain_db: gain_db,
            drone: drone_from_knobs,
            tanpura_output,
            tuning,
            stereo_width,
            instrument: match self.instrument.value() {
                InstrumentChoice::Tanpura => Instrument::Tanpura,
                InstrumentChoice::Bowed => Instrument::Bowed,
            },
            bowed: BowedEngineSettings {
                player: BowedPlayerSettings {
                    tier: match self.bow_model.value() {
                        BowModelChoice::RoundedCorner => BowTier::RoundedCorner,
                        BowModelChoice::BowTable => BowTier::BowTable,
                    },
                    glide_time_s: f64::from(self.glide_ms.value()) / 1000.0,
                    max_vibrato_cents: f64::from(self.vibrato_cents.value()),
                    body_enabled: self.body_enabled.value(),
                    ..BowedPlayerSettings::default()
                },
                string: match self.bowed_string.value() {
                    BowedStringChoice::ViolinA => BowedStringKind::ViolinA,
                    BowedStringChoice::CelloD => BowedStringKind::CelloD,
                },
                pressure: f64::from(self.bow_pressure_percent.value()) / 100.0,
                bow_velocity_m_s: f64::from(self.bow_velocity_m_s.value()),
                bow_position: f64::from(self.bow_position.value()),
            },
        }
    }
}

/// Number of factory presets (`presets/*.toml`, compiled into the plugin).
pub const FACTORY_PRESET_COUNT: usize = 12;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn note_names_read_back() {
        assert_eq!(note_name(48), "C3");
        assert_eq!(note_name(55), "G3");
        assert_eq!(note_name(61), "C#4");
        for note in 0..128 {
            assert_eq!(parse_note_name(&note_name(note)), Some(note));
        }
        assert_eq!(parse_note_name("g3"), Some(55));
        assert_eq!(parse_note_name("50"), Some(50));
        assert_eq!(parse_note_name("H2"), None);
    }

    #[test]
    fn a_drone_sa_set_here_reaches_the_engine() {
        let params = JavariParams::default();
        let factory = crate::factory_presets();
        assert_eq!(params.engine_settings(&factory).drone.sa_note, None);
    }
}
