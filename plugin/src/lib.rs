//! Javari as a CLAP and VST3 instrument (and a standalone app with the `standalone` feature).
//!
//! The plugin is a thin wrapper: it turns the host's parameters into engine settings
//! ([`params`]), its note events into [`TimedEvent`]s, and hands both to the same
//! [`javari_core::engine::Engine`] that `cargo xtask render` drives. The engine splits the block
//! at every event, so events are sample-accurate.
//!
//! MIDI: note-on plucks the string tuned to that note (12-TET, A4 = 440 Hz) with the pluck
//! amplitude scaled by velocity; note-off releases the note (the string rings on; in drone mode
//! releasing the last held note stops the cycle); CC 120 silences every string; CC 123 releases
//! every note. The output is stereo: the strings spread over the image by *Stereo width*
//! (`Engine::process_stereo`; the mono sum is exactly the mono output).
//!
//! With the `inst` parameter on Bowed, the same events play one bowed string
//! (`javari_core::bowed::instrument` documents that mapping): CCs, channel and per-note pressure
//! and pitch bend reach it too.
//!
//! Towards the host: the latency of the quality tier in use (the decimator's delay at the studio
//! and reference tiers, 29 samples at 44.1 kHz; none for the other tiers and the bowed string), set
//! at activation (`Engine::adopt_tier_latency`). When the tier changes while the plugin is active,
//! `process` asks the host to restart it once, and the next activation reports the new latency:
//! CLAP through `request_restart`, then `latency.changed` inside `activate` (never from the audio
//! thread's change itself: nice-plug 0.4.2 would call it after a deactivation that raced it,
//! outside `activate`, which the CLAP spec forbids); VST3 through
//! `restartComponent(kLatencyChanged)`. Until the restart, a string keeps sounding at the latency
//! reported (a modal string plucked at an FD latency is delayed to it). A state blob is repaired
//! before it loads ([`state`]);
//! `process` runs with subnormals flushed to zero (`javari_core::denormals`).
//!
//! Each string is tuned by its sustained pitch as played once [`tuning_worker`] has measured
//! it on its own thread (a string plucked before that plays with its linearised tuning).

pub mod editor;
pub mod params;
pub mod state;
pub mod tuning_worker;

use editor::channel::{SnapshotChannel, SnapshotPublisher, QUEUE_FRAMES};
use javari_core::denormals::FlushDenormals;
use javari_core::engine::preset::Preset;
use javari_core::engine::render::DEFAULT_VOICE_COUNT;
use javari_core::engine::{Engine, EngineEvent, EngineSettings, TimedEvent};
use nice_plug::midi::Key;
use nice_plug::prelude::*;
use params::JavariParams;
use std::num::NonZeroU32;
use std::sync::Arc;
use std::time::Instant;
use tuning_worker::TuningWorker;

/// The factory presets, compiled in from `presets/` (the files `render --preset` reads).
pub const FACTORY_PRESET_FILES: [(&str, &str); params::FACTORY_PRESET_COUNT] = [
    (
        "presets/classic.toml",
        include_str!("../../presets/classic.toml"),
    ),
    (
        "presets/no-thread.toml",
        include_str!("../../presets/no-thread.toml"),
    ),
    (
        "presets/bright-jawari.toml",
        include_str!("../../presets/bright-jawari.toml"),
    ),
    ("presets/soft.toml", include_str!("../../presets/soft.toml")),
    (
        "presets/bowed-violin.toml",
        include_str!("../../presets/bowed-violin.toml"),
    ),
    (
        "presets/bowed-cello.toml",
        include_str!("../../presets/bowed-cello.toml"),
    ),
    (
        "presets/bowed-sul-ponticello.toml",
        include_str!("../../presets/bowed-sul-ponticello.toml"),
    ),
    (
        "presets/bowed-flautando.toml",
        include_str!("../../presets/bowed-flautando.toml"),
    ),
    (
        "presets/male-tanpura.toml",
        include_str!("../../presets/male-tanpura.toml"),
    ),
    (
        "presets/female-tanpura.toml",
        include_str!("../../presets/female-tanpura.toml"),
    ),
    (
        "presets/five-string-tanpura.toml",
        include_str!("../../presets/five-string-tanpura.toml"),
    ),
    (
        "presets/tanpura-ma.toml",
        include_str!("../../presets/tanpura-ma.toml"),
    ),
];

/// Parses the compiled-in factory presets (a test checks that they parse).
pub fn factory_presets() -> [Preset; params::FACTORY_PRESET_COUNT] {
    FACTORY_PRESET_FILES.map(|(file, text)| {
        Preset::parse(text, file).unwrap_or_else(|_| Preset {
            name: file.to_string(),
            settings: EngineSettings::default(),
        })
    })
}

/// The engine's latency as the host takes it: whole samples at the output rate.
fn latency_in_samples(engine: &Engine) -> u32 {
    engine.latency_samples().round() as u32
}

/// Most note events handled in one block (the wrapper's own queue holds as many).
const EVENT_CAPACITY: usize = 1024;

pub struct Javari {
    params: Arc<JavariParams>,
    factory: [Preset; params::FACTORY_PRESET_COUNT],
    /// Built in `activate` (it allocates the strings); `None` before.
    engine: Option<Engine>,
    events: Vec<TimedEvent>,
    /// The left channel, then the mid signal the editor is shown.
    mono: Vec<f32>,
    /// The right channel.
    right: Vec<f32>,
    /// The audio thread's end of the editor channel (measures load, publishes snapshots).
    snapshots: SnapshotPublisher,
    editor_state: Arc<editor::EguiEditorState>,
    /// Measures the strings' as-played tuning off the audio thread; started in `activate`.
    tuning: Option<TuningWorker>,
    /// Whether `process` has asked the host for a restart since the last activation (the
    /// tier's latency differs from the reported one).
    restart_requested: bool,
}

impl Default for Javari {
    fn default() -> Self {
        Self {
            params: Arc::new(JavariParams::default()),
            factory: factory_presets(),
            engine: None,
            events: Vec::with_capacity(EVENT_CAPACITY),
            mono: Vec::new(),
            right: Vec::new(),
            snapshots: SnapshotPublisher::new(SnapshotChannel::new(QUEUE_FRAMES)),
            editor_state: editor::default_state(),
            tuning: None,
            restart_requested: false,
        }
    }
}

impl Plugin for Javari {
    const NAME: &'static str = "Javari";
    const VENDOR: &'static str = "Javari developers";
    const URL: &'static str = "https://example.invalid/javari";
    const EMAIL: &'static str = "javari@example.invalid";
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");

    const AUDIO_IO_LAYOUTS: &'static [AudioIOLayout] = &[AudioIOLayout {
        main_input_channels: None,
        main_output_channels: NonZeroU32::new(2),
        ..AudioIOLayout::const_default()
    }];
    const MIDI_INPUT: MidiConfig = MidiConfig::MidiCCs;
    const SAMPLE_ACCURATE_AUTOMATION: bool = false;
    const INPUT_EVENT_CAPACITY: usize = EVENT_CAPACITY;

    type Editor = editor::JavariEditor;
    type SysExMessage = ();
    type BackgroundTask = ();

    fn params(&self) -> Arc<dyn Params> {
        self.params.clone()
    }

    /// A saved state from the host is repaired before it is applied ([`state::repair`]).
    fn filter_state(state: &mut PluginState) {
        state::repair(state);
    }

    fn editor(&mut self, _async_executor: AsyncExecutor<Self>) -> Option<Self::Editor> {
        editor::create(
            self.params.clone(),
            self.snapshots.channel().clone(),
            self.editor_state.clone(),
        )
    }

    fn activate(
        &mut self,
        _audio_io_layout: &AudioIOLayout,
        buffer_config: &BufferConfig,
        context: &mut impl ActivateContext<Self>,
    ) -> bool {
        let settings = self.params.engine_settings(&self.factory);
        let rate = f64::from(buffer_config.sample_rate);
        let mut engine = match self.engine.take() {
            Some(mut engine) if engine.sample_rate_hz() == rate => {
                engine.set_settings(&settings);
                engine
            }
            _ => Engine::new(&settings, rate, DEFAULT_VOICE_COUNT),
        };
        engine.adopt_tier_latency();
        // Off the audio thread: every playable note's tension, so that a note-on configures its
        // string instead of tuning it (`javari_core::engine::tuning_memory`).
        engine.prepare_tunings();
        context.set_latency_samples(latency_in_samples(&engine));
        self.restart_requested = false;
        self.engine = Some(engine);
        if self.tuning.is_none() {
            self.tuning = Some(TuningWorker::start());
        }
        self.snapshots.prepare(rate);
        self.mono
            .resize(buffer_config.max_buffer_size.max(1) as usize, 0.0);
        self.right
            .resize(buffer_config.max_buffer_size.max(1) as usize, 0.0);
        true
    }

    fn reset(&mut self) {
        let settings = self.params.engine_settings(&self.factory);
        if let Some(engine) = &mut self.engine {
            engine.set_settings(&settings);
            engine.reset();
        }
    }

    fn process(
        &mut self,
        buffer: &mut Buffer,
        _aux: &mut AuxiliaryBuffers,
        context: &mut impl ProcessContext<Self>,
    ) -> ProcessStatus {
        let started = Instant::now();
        let _flush_denormals = FlushDenormals::enable();
        let Some(engine) = &mut self.engine else {
            return ProcessStatus::Error("process called before activate");
        };
        engine.set_settings(&self.params.engine_settings(&self.factory));
        let tier_latency = engine.tier_latency_samples().round() as u32;
        if tier_latency != latency_in_samples(engine) && !self.restart_requested {
            // The tier's latency is adopted at the next activation; ask the host for one.
            self.restart_requested = true;
            match context.plugin_api() {
                // kLatencyChanged: the host reads the new latency and restarts the plugin.
                PluginApi::Vst3 => context.set_latency_samples(tier_latency),
                _ => context.request_restart(),
            }
        }
        engine.set_host_tempo(context.transport().tempo);

        self.events.clear();
        if let Some(note) = self.snapshots.channel().take_audition() {
            self.events.push(TimedEvent::note_on(0, note, 1.0));
        }
        while let Some(event) = context.next_event() {
            let offset = event.timing() as usize;
            let engine_event = match event {
                NoteEvent::NoteOn {
                    key: Key::Number(note),
                    velocity,
                    ..
                } => EngineEvent::NoteOn { note, velocity },
                NoteEvent::NoteOff {
                    key: Key::Number(note),
                    ..
                } => EngineEvent::NoteOff { note },
                // A CLAP wildcard note-off releases every note.
                NoteEvent::NoteOff {
                    key: Key::Wildcard, ..
                } => EngineEvent::AllNotesOff,
                NoteEvent::MidiCC { cc: 120, .. } => EngineEvent::AllSoundOff,
                NoteEvent::MidiCC { cc: 123, .. } => EngineEvent::AllNotesOff,
                NoteEvent::MidiCC { cc, value, .. } => {
                    EngineEvent::Controller { number: cc, value }
                }
                NoteEvent::MidiChannelPressure { pressure, .. } => {
                    EngineEvent::ChannelPressure(pressure)
                }
                NoteEvent::PolyPressure {
                    key: Key::Number(note),
                    pressure,
                    ..
                } => EngineEvent::PolyPressure {
                    note,
                    value: pressure,
                },
                // nice-plug gives the bend normalised to 0–1 with 0.5 at rest.
                NoteEvent::MidiPitchBend { value, .. } => EngineEvent::PitchBend(2.0 * value - 1.0),
                _ => continue,
            };
            if self.events.len() < self.events.capacity() {
                self.events.push(TimedEvent {
                    offset,
                    event: engine_event,
                });
            }
        }

        let samples = buffer.samples();
        // Hosts may pass longer buffers than announced; render those in announced-size chunks
        // so that nothing is allocated here.
        let chunk = self.mono.len().max(1);
        let channels = buffer.as_slice();
        let mut start = 0;
        let mut next_event = 0;
        while start < samples {
            let end = (start + chunk).min(samples);
            let first_event = next_event;
            while next_event < self.events.len() && self.events[next_event].offset < end {
                self.events[next_event].offset -= start.min(self.events[next_event].offset);
                next_event += 1;
            }
            let left = &mut self.mono[..end - start];
            let right = &mut self.right[..end - start];
            engine.process_stereo(&self.events[first_event..next_event], left, right);
            for (index, channel) in channels.iter_mut().enumerate() {
                let source: &[f32] = if index % 2 == 0 { left } else { right };
                channel[start..end].copy_from_slice(source);
            }
            // The editor shows the mid signal (the mono output).
            for (left, right) in left.iter_mut().zip(right.iter()) {
                *left = 0.5 * (*left + *right);
            }
            self.snapshots.record_output(left);
            start = end;
        }
        if let Some(tuning) = &self.tuning {
            tuning.exchange(engine);
        }
        self.snapshots.end_block(engine, samples, started.elapsed());
        ProcessStatus::KeepAlive
    }
}

impl ClapPlugin for Javari {
    const CLAP_ID: &'static str = "org.javari.tanpura";
    const CLAP_DESCRIPTION: Option<&'static str> =
        Some("Physically modelled tanpura: strings colliding with a curved bridge and a thread");
    const CLAP_MANUAL_URL: Option<&'static str> = None;
    const CLAP_SUPPORT_URL: Option<&'static str> = None;
    const CLAP_FEATURES: &'static [ClapFeature] = &[
        ClapFeature::Instrument,
        ClapFeature::Synthesizer,
        ClapFeature::Stereo,
    ];
}

impl Vst3Plugin for Javari {
    const VST3_CLASS_ID: [u8; 16] = *b"JavariTanpura001";
    const VST3_SUBCATEGORIES: &'static [Vst3SubCategory] =
        &[Vst3SubCategory::Instrument, Vst3SubCategory::Synth];
}

nice_export_clap!(Javari);
nice_export_vst3!(Javari);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factory_presets_parse_and_have_their_names() {
        let names: Vec<String> = FACTORY_PRESET_FILES
            .iter()
            .map(|(file, text)| Preset::parse(text, file).unwrap().name)
            .collect();
        assert_eq!(
            names,
            [
                "Classic",
                "No thread",
                "Bright jawari",
                "Soft",
                "Bowed violin",
                "Bowed cello",
                "Sul ponticello",
                "Flautando (bow table)",
                "Male tanpura",
                "Female tanpura",
                "Five-string tanpura",
                "Tanpura in Ma"
            ]
        );
    }

    #[test]
    fn default_parameters_give_the_default_engine_settings() {
        let params = JavariParams::default();
        let settings = params.engine_settings(&factory_presets());
        let expected = EngineSettings::default();
        assert_eq!(settings.pluck.width_m, expected.pluck.width_m);
        assert!((settings.voice.bridge_stiffness_n_m2 / 1e8 - 1.0).abs() < 1e-6);
        assert!((settings.voice.thread_position_m - 0.040).abs() < 1e-9);
        assert!((settings.voice.eta_s / 7e-9 - 1.0).abs() < 1e-6);
        assert_eq!(
            settings.voice.quality,
            javari_core::tanpura::quality::Quality::default()
        );
        assert_eq!(settings.drone, expected.drone);
    }

    #[test]
    fn classic_preset_matches_the_default_sound() {
        let classic = &factory_presets()[0].settings;
        let default = EngineSettings::default();
        assert_eq!(classic.voice, default.voice);
        assert_eq!(
            classic.voice.quality,
            javari_core::tanpura::quality::Quality::Reference,
            "a preset without a quality key keeps the default tier"
        );
        assert_eq!(classic.pluck, default.pluck);
    }
}
