//! The built `.clap` (the `javari` cdylib that `cargo test` leaves in `target/<profile>/deps/`)
//! loaded by a CLAP host written with `clack-host`, as a DAW would: activate at several sample
//! rates and block sizes, play a note, check the pitch while it rings and that every sample is
//! finite, and round-trip the plugin state. The host offers the latency extension and records
//! restart requests and `latency.changed` calls, so the latency the plugin reports per quality
//! tier, and its changes, are checked as a DAW would see them. Corrupt, foreign and out-of-range
//! state blobs must load the defaults (or be refused, leaving them) and never crash the host.
//! The cdylib is built with `assert_process_allocs`, so an allocation in `process` aborts this
//! test.

use clack_extensions::latency::{HostLatency, HostLatencyImpl, PluginLatency};
use clack_extensions::params::{ParamInfoBuffer, PluginParams};
use clack_extensions::state::PluginState;
use clack_host::events::event_types::{NoteOnEvent, ParamValueEvent};
use clack_host::prelude::*;
use javari_core::engine::pitch::{cents, note_to_hz};
use javari_core::engine::{Engine, EngineSettings};
use javari_core::tanpura::quality::Quality;
use javari_tests::{finite_mid, peak, peak_frequency_near, plugin_library};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};

/// Requests the plugin makes from any thread, remembered until the test looks.
#[derive(Default)]
struct TestHostShared {
    restart_requested: AtomicBool,
    callback_requested: AtomicBool,
}

impl SharedHandler<'_> for TestHostShared {
    fn request_restart(&self) {
        self.restart_requested.store(true, Ordering::SeqCst);
    }
    fn request_process(&self) {}
    fn request_callback(&self) {
        self.callback_requested.store(true, Ordering::SeqCst);
    }
}

/// Main-thread callbacks: how often the plugin said its latency changed, and how often it
/// did so outside `activate` (the CLAP spec allows it only while the plugin is being
/// activated).
#[derive(Default)]
struct TestHostMainThread {
    latency_changes: Cell<u32>,
    activating: Cell<bool>,
    latency_changes_outside_activate: Cell<u32>,
}

impl MainThreadHandler<'_> for TestHostMainThread {}

impl HostLatencyImpl for TestHostMainThread {
    fn changed(&self) {
        self.latency_changes.set(self.latency_changes.get() + 1);
        if !self.activating.get() {
            self.latency_changes_outside_activate
                .set(self.latency_changes_outside_activate.get() + 1);
        }
    }
}

struct TestHost;

impl HostHandlers for TestHost {
    type Shared<'a> = TestHostShared;
    type MainThread<'a> = TestHostMainThread;
    type AudioProcessor<'a> = ();

    fn declare_extensions(builder: &mut HostExtensions<Self>, _shared: &Self::Shared<'_>) {
        builder.register::<HostLatency>();
    }
}

const PLUGIN_ID: &[u8] = b"org.javari.tanpura";

/// The plugin's entry, loaded once for every test of this file and never unloaded: tests run
/// in parallel threads, and unloading the library under another test's running instance would
/// pull its code away (as a host never does).
fn load_entry() -> &'static PluginEntry {
    static ENTRY: std::sync::OnceLock<PluginEntry> = std::sync::OnceLock::new();
    ENTRY.get_or_init(|| {
        let library = plugin_library();
        // SAFETY: the library is this repository's own plugin, built by this `cargo test`.
        unsafe { PluginEntry::load(&library) }
            .unwrap_or_else(|error| panic!("loading {}: {error:?}", library.display()))
    })
}

fn instantiate(entry: &PluginEntry) -> PluginInstance<TestHost> {
    let host_info = HostInfo::new("javari-tests", "Javari", "https://example.invalid", "1.0")
        .expect("valid host info");
    let factory = entry.get_plugin_factory().expect("a plugin factory");
    let descriptor = factory
        .plugin_descriptors()
        .find(|descriptor| descriptor.id().map(|id| id.to_bytes()) == Some(PLUGIN_ID))
        .expect("the Javari descriptor");
    assert_eq!(descriptor.name().unwrap().to_bytes(), b"Javari");
    let id = descriptor.id().unwrap();
    PluginInstance::<TestHost>::new(
        |_| TestHostShared::default(),
        |_| TestHostMainThread::default(),
        entry,
        id,
        &host_info,
    )
    .expect("instantiation")
}

/// Plays `key` at `velocity` from sample `note_at` for `seconds`, in blocks of `block_size`;
/// returns the left and right channels.
fn play(
    instance: &mut PluginInstance<TestHost>,
    sample_rate: f64,
    block_size: usize,
    key: u16,
    velocity: f64,
    note_at: usize,
    seconds: f64,
) -> (Vec<f32>, Vec<f32>) {
    play_automated(
        instance,
        sample_rate,
        block_size,
        (key, velocity, note_at),
        &[],
        seconds,
    )
}

/// As [`play`], with parameter changes `(sample, parameter id, plain value)` sent as CLAP
/// parameter events at their samples.
fn play_automated(
    instance: &mut PluginInstance<TestHost>,
    sample_rate: f64,
    block_size: usize,
    (key, velocity, note_at): (u16, f64, usize),
    automation: &[(usize, ClapId, f64)],
    seconds: f64,
) -> (Vec<f32>, Vec<f32>) {
    let configuration = PluginAudioConfiguration {
        sample_rate,
        min_frames_count: 1,
        max_frames_count: block_size as u32,
    };
    instance.access_handler(|host| host.activating.set(true));
    let processor = instance
        .activate(|_, _| (), configuration)
        .expect("activation");
    instance.access_handler(|host| host.activating.set(false));
    let mut processor = processor.start_processing().expect("start processing");
    let total = (seconds * sample_rate) as usize;
    let mut left = Vec::with_capacity(total);
    let mut right = Vec::with_capacity(total);
    let mut input_ports = AudioPorts::with_capacity(0, 0);
    let mut output_ports = AudioPorts::with_capacity(2, 1);
    let mut output_events = EventBuffer::new();
    let mut buffers = [vec![0.0f32; block_size], vec![0.0f32; block_size]];
    let mut start = 0;
    while start < total {
        let frames = block_size.min(total - start);
        let block = start..start + frames;
        let mut events = EventBuffer::new();
        if block.contains(&note_at) {
            events.push(&NoteOnEvent::new(
                (note_at - start) as u32,
                Pckn::new(0u16, 0u16, key, 0u32),
                velocity,
            ));
        }
        for &(at, id, value) in automation.iter().filter(|(at, ..)| block.contains(at)) {
            events.push(&ParamValueEvent::new(
                (at - start) as u32,
                id,
                Pckn::match_all(),
                value,
            ));
        }
        events.sort();
        let input_events = InputEvents::from_buffer(&events);
        let mut output_events = OutputEvents::from_buffer(&mut output_events);
        let input_audio = input_ports.with_input_buffers(std::iter::empty::<
            AudioPortBuffer<
                std::iter::Empty<InputChannel<f32>>,
                std::iter::Empty<InputChannel<f64>>,
            >,
        >());
        let [buffer_left, buffer_right] = &mut buffers;
        let mut output_audio = output_ports.with_output_buffers([AudioPortBuffer {
            latency: 0,
            channels: AudioPortBufferType::f32_output_only(
                [&mut buffer_left[..frames], &mut buffer_right[..frames]].into_iter(),
            ),
        }]);
        processor
            .process(
                &input_audio,
                &mut output_audio,
                &input_events,
                &mut output_events,
                None,
                None,
            )
            .expect("process");
        left.extend_from_slice(&buffers[0][..frames]);
        right.extend_from_slice(&buffers[1][..frames]);
        start += frames;
    }
    let processor = processor.stop_processing();
    instance.deactivate(processor);
    // What a host's main loop does: run the callback the plugin asked for.
    if instance.access_shared_handler(|host| host.callback_requested.swap(false, Ordering::SeqCst))
    {
        instance.call_on_main_thread_callback();
    }
    (left, right)
}

#[test]
fn clap_plays_in_tune_at_several_rates_and_block_sizes() {
    let entry = load_entry();
    let key = 57u16; // A3, 220 Hz
    for (sample_rate, block_size) in [(44_100.0, 512usize), (48_000.0, 33), (96_000.0, 1024)] {
        let mut instance = instantiate(entry);
        let note_at = 100;
        let (left, right) = play(
            &mut instance,
            sample_rate,
            block_size,
            key,
            0.4,
            note_at,
            0.6,
        );
        // Stereo: the string panned by its pitch; the mid signal is the mono output.
        let left = finite_mid(&left, &right);
        assert!(peak(&left[..note_at]) == 0.0, "silent before the note");
        let ringing = &left[(0.1 * sample_rate) as usize..];
        let level = peak(ringing);
        assert!(level > 1e-3 && level < 1.0, "level {level}");
        let expected = note_to_hz(key as u8);
        let measured = peak_frequency_near(ringing, sample_rate, expected, 60.0);
        let error = cents(measured, expected);
        println!(
            "{sample_rate} Hz, block {block_size}: {measured:.3} Hz ({error:+.2} cents), peak {level:.3}"
        );
        assert!(error.abs() < 5.0, "{error} cents at {sample_rate} Hz");
    }
}

/// The CLAP id of the parameter shown as `name`, from the params extension.
fn parameter_id(instance: &mut PluginInstance<TestHost>, name: &str) -> ClapId {
    let handle = instance.plugin_handle();
    let params = handle
        .get_extension::<PluginParams>()
        .expect("the params extension");
    let mut buffer = ParamInfoBuffer::new();
    (0..params.count(&handle))
        .filter_map(|index| {
            params
                .get_info(&handle, index, &mut buffer)
                .map(|i| (i.id, i.name.to_vec()))
        })
        .find(|(_, info_name)| {
            let end = info_name
                .iter()
                .position(|b| *b == 0)
                .unwrap_or(info_name.len());
            &info_name[..end] == name.as_bytes()
        })
        .map(|(id, _)| id)
        .unwrap_or_else(|| panic!("no parameter named {name}"))
}

/// Automation while a string rings, under the allocation guard: switching the quality tier,
/// the thread off and on, and moving k_b and the thread must neither allocate in `process`
/// nor produce a non-finite sample, and the string stays in tune.
#[test]
fn clap_automation_is_allocation_free_and_keeps_the_string_in_tune() {
    let entry = load_entry();
    let mut instance = instantiate(entry);
    let quality = parameter_id(&mut instance, "Quality");
    let thread = parameter_id(&mut instance, "Thread");
    let stiffness = parameter_id(&mut instance, "Bridge stiffness");
    let position = parameter_id(&mut instance, "Thread position");
    let rate = 44_100.0;
    let automation = [
        (2_000, stiffness, 9.0),
        (4_000, position, 35.0),
        (6_000, thread, 0.0),
        (8_000, quality, 3.0), // Reference
        (9_000, thread, 1.0),
        (10_000, quality, 0.0), // Live
        (12_000, stiffness, 8.0),
        (12_001, position, 40.0),
    ];
    let (left, _) = play_automated(&mut instance, rate, 128, (57, 0.4, 0), &automation, 0.8);
    assert!(left.iter().all(|x| x.is_finite()), "non-finite sample");
    let settled = &left[(0.4 * rate) as usize..];
    let level = peak(settled);
    let expected = note_to_hz(57);
    let error = cents(peak_frequency_near(settled, rate, expected, 60.0), expected);
    println!("after automation: peak {level:.4}, A3 {error:+.2} cents");
    assert!(level > 1e-3, "the string still rings: {level}");
    assert!(error.abs() < 5.0, "{error} cents");
}

#[test]
fn clap_state_round_trip_restores_parameters() {
    let entry = load_entry();
    let mut first = instantiate(entry);
    let state_extension = first
        .plugin_handle()
        .get_extension::<PluginState>()
        .expect("the state extension");
    let mut saved = Vec::new();
    state_extension
        .save(&first.plugin_handle(), &mut saved)
        .expect("save");
    let text = state_json(&saved);
    assert!(text.contains("\"gain\""), "parameters by stable ID: {text}");

    // Change the output gain in the saved state (0 dB → −6.02 dB), load it into a fresh
    // instance, and check that it plays half as loud and saves the new value back.
    let edited = edit_parameter(&text, "gain", -6.0206);
    let mut second = instantiate(entry);
    let extension = second
        .plugin_handle()
        .get_extension::<PluginState>()
        .unwrap();
    extension
        .load(
            &second.plugin_handle(),
            &mut state_bytes(&edited).as_slice(),
        )
        .expect("load");
    let mut resaved = Vec::new();
    extension
        .save(&second.plugin_handle(), &mut resaved)
        .expect("save again");
    let resaved = state_json(&resaved);
    assert_eq!(parameter_value(&resaved, "gain"), -6.0206);
    assert_eq!(
        resaved.replace("-6.0206", "0.0"),
        text,
        "every other parameter survives the round trip"
    );

    let (loud, _) = play(&mut first, 44_100.0, 256, 60, 0.5, 0, 0.2);
    let (quiet, _) = play(&mut second, 44_100.0, 256, 60, 0.5, 0, 0.2);
    let ratio = peak(&quiet) / peak(&loud);
    println!("gain state −6.02 dB: level ratio {ratio:.4}");
    assert!((ratio - 0.5).abs() < 0.01, "{ratio}");
}

#[test]
fn clap_state_out_of_range_is_clamped_on_load() {
    // A damaged or hand-edited project: a gain of 1e30 dB and a preset index past the last
    // preset. nice-plug alone would store both, play at +1e30 dB and panic on the next save
    // (it reads the enum's ID by index); the plugin's `filter_state` clamps them first.
    let entry = load_entry();
    let mut instance = instantiate(entry);
    let extension = instance
        .plugin_handle()
        .get_extension::<PluginState>()
        .unwrap();
    let mut saved = Vec::new();
    extension
        .save(&instance.plugin_handle(), &mut saved)
        .expect("save");
    let text = state_json(&saved);
    assert!(
        text.contains("\"preset\":{\"string\":\"custom\"}"),
        "{text}"
    );
    let damaged = edit_parameter(&text, "gain", 1e30).replace(
        "\"preset\":{\"string\":\"custom\"}",
        "\"preset\":{\"i32\":99}",
    );
    extension
        .load(
            &instance.plugin_handle(),
            &mut state_bytes(&damaged).as_slice(),
        )
        .expect("load");
    let mut resaved = Vec::new();
    extension
        .save(&instance.plugin_handle(), &mut resaved)
        .expect("save after loading the damaged state");
    let resaved = state_json(&resaved);
    assert_eq!(parameter_value(&resaved, "gain"), 24.0);
    assert!(
        resaved.contains("\"preset\":{\"string\":\"custom\"}"),
        "{resaved}"
    );
    let (signal, _) = play(&mut instance, 44_100.0, 256, 60, 0.5, 0, 0.2);
    assert!(signal.iter().all(|x| x.is_finite()));
}

/// nice-plug's CLAP state: the JSON text's length as a little-endian u64, then the JSON, in
/// which each parameter is `"id":{"f32":value}` (or `bool`, `string`).
fn state_json(bytes: &[u8]) -> String {
    let length = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    assert_eq!(length, bytes.len() - 8, "length prefix");
    String::from_utf8(bytes[8..].to_vec()).expect("UTF-8 JSON")
}

fn state_bytes(json: &str) -> Vec<u8> {
    let mut bytes = (json.len() as u64).to_le_bytes().to_vec();
    bytes.extend_from_slice(json.as_bytes());
    bytes
}

fn parameter_span(text: &str, id: &str) -> (usize, usize) {
    let key = format!("\"{id}\":{{\"f32\":");
    let start = text
        .find(&key)
        .unwrap_or_else(|| panic!("no {key} in {text}"))
        + key.len();
    let end = start + text[start..].find('}').unwrap();
    (start, end)
}

fn parameter_value(text: &str, id: &str) -> f64 {
    let (start, end) = parameter_span(text, id);
    text[start..end].trim().parse().unwrap()
}

fn edit_parameter(text: &str, id: &str, value: f64) -> String {
    let (start, end) = parameter_span(text, id);
    format!("{}{value}{}", &text[..start], &text[end..])
}

/// The latency the engine has at `quality`, in whole samples at 44.1 kHz.
fn engine_latency(quality: Quality) -> u32 {
    let mut settings = EngineSettings::default();
    settings.voice.quality = quality;
    Engine::new(&settings, 44_100.0, 1)
        .latency_samples()
        .round() as u32
}

/// The plugin reports the latency of its tier (the oversampled tiers' decimator delay, studio
/// and reference; none for the tiers at the output rate). Automating the tier while processing
/// asks the host for a restart when the latency changes (and only then); the next activation
/// adopts the new latency, and the host hears of it through `latency.changed`, called inside
/// `activate` as the CLAP spec requires (never outside: nice-plug 0.4.2 would do that for a
/// latency set from `process` that reached it after a deactivation).
#[test]
fn clap_latency_follows_the_tier_through_a_restart() {
    let entry = load_entry();
    let mut instance = instantiate(entry);
    let quality = parameter_id(&mut instance, "Quality");
    let latency = instance
        .plugin_handle()
        .get_extension::<PluginLatency>()
        .expect("the latency extension");
    let restart_requested = |instance: &PluginInstance<TestHost>| {
        instance.access_shared_handler(|host| host.restart_requested.swap(false, Ordering::SeqCst))
    };
    let changes = |instance: &PluginInstance<TestHost>| {
        instance.access_handler(|host| host.latency_changes.get())
    };
    let reference_latency = engine_latency(Quality::Reference);
    let studio_latency = engine_latency(Quality::Studio);
    println!(
        "latency at 44.1 kHz: {reference_latency} samples at the reference (4x), \
         {studio_latency} at the studio tier (4x), 0 at the tiers at the output rate"
    );
    assert!(
        studio_latency > 0 && reference_latency > 0,
        "the oversampled tiers have a decimator delay"
    );
    assert_eq!(engine_latency(Quality::Live), 0);
    assert_eq!(engine_latency(Quality::Fine), 0);

    let rate = 44_100.0;
    play(&mut instance, rate, 64, 57, 0.5, 0, 0.02);
    assert!(
        !restart_requested(&instance),
        "a restart at the default tier"
    );
    assert_eq!(
        latency.get(&instance.plugin_handle()),
        0,
        "fine, the default"
    );
    assert_eq!(changes(&instance), 0);
    // (CLAP plain value of an enum parameter: its index. Live 0, fine 1, studio 2, reference 3.)
    let tiers = [
        (2.0, Quality::Studio),
        (3.0, Quality::Reference),
        (0.0, Quality::Live),
        (1.0, Quality::Fine),
        (3.0, Quality::Reference),
    ];
    for (index, tier) in tiers {
        let before = latency.get(&instance.plugin_handle());
        let wanted = engine_latency(tier);
        play_automated(
            &mut instance,
            rate,
            64,
            (57, 0.5, 0),
            &[(100, quality, index)],
            0.02,
        );
        assert_eq!(
            restart_requested(&instance),
            wanted != before,
            "{tier:?}: restart request"
        );
        assert_eq!(latency.get(&instance.plugin_handle()), before, "{tier:?}");
        // The host restarts the plugin: its next activation adopts the tier's latency, which
        // `latency.get` returns from then on. nice-plug 0.4.2 takes a latency set in `activate`
        // only once `activate` has returned, so it asks for one more restart and calls
        // `latency.changed` inside that activation.
        let changes_before = changes(&instance);
        let changed = wanted != before;
        play(&mut instance, rate, 64, 57, 0.5, 0, 0.02);
        assert_eq!(latency.get(&instance.plugin_handle()), wanted, "{tier:?}");
        assert_eq!(
            restart_requested(&instance),
            changed,
            "{tier:?}: the restart that reports the change"
        );
        play(&mut instance, rate, 64, 57, 0.5, 0, 0.02);
        assert_eq!(
            changes(&instance),
            changes_before + u32::from(changed),
            "{tier:?}: latency.changed"
        );
        assert!(!restart_requested(&instance), "{tier:?}: a third restart");
        assert_eq!(latency.get(&instance.plugin_handle()), wanted, "{tier:?}");
    }
    assert_eq!(
        instance.access_handler(|host| host.latency_changes_outside_activate.get()),
        0,
        "latency.changed outside activate"
    );
}

/// Blobs a host might hand over that are not a Javari state: the load is refused or repaired,
/// never a crash, and a fresh instance given one still saves (and plays) its defaults.
#[test]
fn clap_corrupt_or_foreign_state_loads_the_defaults() {
    let entry = load_entry();
    let mut fresh = instantiate(entry);
    let defaults = save_state(&mut fresh);
    let mut blobs: Vec<(&str, Vec<u8>)> = vec![
        ("empty", Vec::new()),
        ("shorter than the length prefix", vec![1, 2, 3]),
        ("huge length prefix", u64::MAX.to_le_bytes().to_vec()),
        ("length prefix past the end", {
            let mut bytes = 100u64.to_le_bytes().to_vec();
            bytes.extend_from_slice(b"{}");
            bytes
        }),
        (
            "bytes that are not JSON",
            state_bytes("\u{0}\u{1}garbage\u{ff}"),
        ),
        (
            "JSON of another shape",
            state_bytes(r#"{"presets":[1,2,3]}"#),
        ),
        (
            "truncated state",
            state_bytes(&defaults[..defaults.len() / 2]),
        ),
        (
            "another plugin's state",
            state_bytes(r#"{"version":"2.1","params":{"cutoff":{"f32":880.0}},"fields":{}}"#),
        ),
    ];
    let pseudo_random: Vec<u8> = (0u32..4096)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    blobs.push(("pseudo-random bytes", pseudo_random));
    for (what, blob) in &blobs {
        let mut instance = instantiate(entry);
        let loaded = load_state(&mut instance, blob);
        assert_eq!(save_state(&mut instance), defaults, "{what}: defaults");
        let (left, _) = play(&mut instance, 44_100.0, 256, 57, 0.5, 0, 0.1);
        assert!(left.iter().all(|x| x.is_finite()), "{what}");
        assert!(peak(&left) > 1e-3, "{what}: plays");
        println!(
            "{what}: load {}",
            if loaded { "accepted" } else { "refused" }
        );
    }

    // A foreign state over an edited instance brings every parameter back to its default.
    let mut edited = instantiate(entry);
    assert!(load_state(
        &mut edited,
        &state_bytes(&edit_parameter(&defaults, "gain", -12.0))
    ));
    assert_eq!(parameter_value(&save_state(&mut edited), "gain"), -12.0);
    assert!(load_state(
        &mut edited,
        &state_bytes(r#"{"params":{"x":{"bool":true}},"fields":{}}"#)
    ));
    assert_eq!(save_state(&mut edited), defaults, "foreign state: defaults");

    // Out-of-range numbers (what an edited file or another version might hold) are clamped, and
    // the state saved afterwards loads again.
    let mut clamped = instantiate(entry);
    let wild = edit_parameter(&edit_parameter(&defaults, "gain", 1e39), "kb", -1e30);
    assert!(load_state(&mut clamped, &state_bytes(&wild)));
    let saved = save_state(&mut clamped);
    assert_eq!(parameter_value(&saved, "gain"), 24.0);
    assert_eq!(parameter_value(&saved, "kb"), 5.0);
    let mut reloaded = instantiate(entry);
    assert!(load_state(&mut reloaded, &state_bytes(&saved)));
    assert_eq!(save_state(&mut reloaded), saved);
}

/// Non-finite and out-of-range automation: the wrapper refuses the first and clamps the
/// second to the parameter's range; the output stays finite.
#[test]
fn clap_non_finite_and_out_of_range_automation_is_clamped() {
    let entry = load_entry();
    let mut instance = instantiate(entry);
    let gain = parameter_id(&mut instance, "Output gain");
    let stiffness = parameter_id(&mut instance, "Bridge stiffness");
    let damping = parameter_id(&mut instance, "Damping");
    let automation = [
        (1_000, gain, f64::NAN),
        (1_100, stiffness, f64::INFINITY),
        (1_200, damping, f64::NEG_INFINITY),
        (2_000, gain, 1e300),
        (2_100, stiffness, -1e300),
        (2_200, damping, 1e30),
    ];
    let (left, _) = play_automated(&mut instance, 44_100.0, 128, (57, 0.5, 0), &automation, 0.3);
    assert!(left.iter().all(|x| x.is_finite()), "non-finite sample");
    let saved = save_state(&mut instance);
    assert_eq!(parameter_value(&saved, "gain"), 24.0, "clamped to the top");
    assert_eq!(parameter_value(&saved, "kb"), 5.0, "clamped to the bottom");
    assert_eq!(parameter_value(&saved, "gamma"), 20.0, "clamped to the top");
}

fn save_state(instance: &mut PluginInstance<TestHost>) -> String {
    let extension = instance
        .plugin_handle()
        .get_extension::<PluginState>()
        .expect("the state extension");
    let mut saved = Vec::new();
    extension
        .save(&instance.plugin_handle(), &mut saved)
        .expect("save");
    state_json(&saved)
}

/// Loads `bytes` as the host's state; whether the plugin accepted it.
fn load_state(instance: &mut PluginInstance<TestHost>, bytes: &[u8]) -> bool {
    let extension = instance
        .plugin_handle()
        .get_extension::<PluginState>()
        .expect("the state extension");
    extension
        .load(&instance.plugin_handle(), &mut &bytes[..])
        .is_ok()
}
