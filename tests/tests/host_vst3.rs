//! The built plugin library loaded through its VST3 entry points with the `vst3` crate's
//! bindings, as a VST3 host would: `ModuleEntry`, `GetPluginFactory`, the audio-module class,
//! `IComponent` + `IAudioProcessor`, bus activation, `setupProcessing`, notes through an
//! `IEventList`, and the state through an `IBStream`. The host also hands the edit controller an
//! `IComponentHandler` that records `restartComponent` flags, so the latency the plugin reports
//! (`getLatencySamples`) per quality tier and its `kLatencyChanged` restarts are checked; corrupt,
//! foreign and out-of-range state blobs must load the defaults (or be refused, leaving them) and
//! never crash the host. The library is the same cdylib the CLAP test loads (with
//! `assert_process_allocs`), the one `cargo xtask bundle` copies into
//! `javari.vst3/Contents/x86_64-linux/`.

use javari_core::engine::pitch::{cents, note_to_hz};
use javari_core::engine::{Engine, EngineSettings};
use javari_core::tanpura::quality::Quality;
use javari_tests::{finite_mid, peak, peak_frequency_near, plugin_library};
use std::cell::RefCell;
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicI32, Ordering};
use vst3::Steinberg::Vst::{
    AudioBusBuffers, AudioBusBuffers__type0, BusDirections_, Event, Event_, Event__type0,
    IAudioProcessor, IAudioProcessorTrait, IComponent, IComponentHandler, IComponentHandlerTrait,
    IComponentTrait, IEditController, IEditControllerTrait, IEventList, IEventListTrait,
    MediaTypes_, NoteOnEvent, ParamID, ParamValue, ParameterInfo, ProcessData, ProcessModes_,
    ProcessSetup, RestartFlags_, SymbolicSampleSizes_,
};
use vst3::Steinberg::{
    int32, int64, kInvalidArgument, kResultFalse, kResultOk, tresult, IBStream, IBStreamTrait,
    IPluginBaseTrait, IPluginFactory, IPluginFactoryTrait, PClassInfo,
};
use vst3::{Class, ComPtr, ComWrapper, Interface};

/// Notes for one process call.
struct EventList {
    events: Vec<Event>,
}

impl Class for EventList {
    type Interfaces = (IEventList,);
}

impl IEventListTrait for EventList {
    unsafe fn getEventCount(&self) -> int32 {
        self.events.len() as int32
    }

    unsafe fn getEvent(&self, index: int32, event: *mut Event) -> tresult {
        match self.events.get(index as usize) {
            Some(found) if !event.is_null() => {
                *event = *found;
                kResultOk
            }
            _ => kInvalidArgument,
        }
    }

    unsafe fn addEvent(&self, _event: *mut Event) -> tresult {
        kResultFalse
    }
}

/// The host side of the edit controller: parameter edits are ignored, restart requests are
/// recorded (the flags of every `restartComponent` call, OR-ed, until the test takes them).
#[derive(Default)]
struct ComponentHandler {
    restart_flags: AtomicI32,
}

impl Class for ComponentHandler {
    type Interfaces = (IComponentHandler,);
}

impl IComponentHandlerTrait for ComponentHandler {
    unsafe fn beginEdit(&self, _id: ParamID) -> tresult {
        kResultOk
    }

    unsafe fn performEdit(&self, _id: ParamID, _value: ParamValue) -> tresult {
        kResultOk
    }

    unsafe fn endEdit(&self, _id: ParamID) -> tresult {
        kResultOk
    }

    unsafe fn restartComponent(&self, flags: int32) -> tresult {
        self.restart_flags.fetch_or(flags, Ordering::SeqCst);
        kResultOk
    }
}

/// An in-memory `IBStream`.
struct MemoryStream {
    bytes: RefCell<Vec<u8>>,
    position: RefCell<usize>,
}

impl Class for MemoryStream {
    type Interfaces = (IBStream,);
}

impl IBStreamTrait for MemoryStream {
    unsafe fn read(&self, buffer: *mut c_void, count: int32, read: *mut int32) -> tresult {
        let bytes = self.bytes.borrow();
        let mut position = self.position.borrow_mut();
        let available = bytes.len() - *position;
        let count = (count.max(0) as usize).min(available);
        std::ptr::copy_nonoverlapping(bytes[*position..].as_ptr(), buffer as *mut u8, count);
        *position += count;
        if !read.is_null() {
            *read = count as int32;
        }
        kResultOk
    }

    unsafe fn write(&self, buffer: *mut c_void, count: int32, written: *mut int32) -> tresult {
        let slice = std::slice::from_raw_parts(buffer as *const u8, count.max(0) as usize);
        let mut bytes = self.bytes.borrow_mut();
        let mut position = self.position.borrow_mut();
        let end = *position + slice.len();
        if bytes.len() < end {
            bytes.resize(end, 0);
        }
        bytes[*position..end].copy_from_slice(slice);
        *position = end;
        if !written.is_null() {
            *written = slice.len() as int32;
        }
        kResultOk
    }

    unsafe fn seek(&self, offset: int64, mode: int32, result: *mut int64) -> tresult {
        let length = self.bytes.borrow().len() as i64;
        let current = *self.position.borrow() as i64;
        // kIBSeekSet = 0, kIBSeekCur = 1, kIBSeekEnd = 2.
        let target = match mode {
            0 => offset,
            1 => current + offset,
            2 => length + offset,
            _ => return kInvalidArgument,
        };
        if !(0..=length).contains(&target) {
            return kResultFalse;
        }
        *self.position.borrow_mut() = target as usize;
        if !result.is_null() {
            *result = target;
        }
        kResultOk
    }

    unsafe fn tell(&self, position: *mut int64) -> tresult {
        if !position.is_null() {
            *position = *self.position.borrow() as int64;
        }
        kResultOk
    }
}

struct Module {
    library: libloading::Library,
}

impl Module {
    fn load() -> Self {
        let path = plugin_library();
        // SAFETY: the library is this repository's own plugin, built by this `cargo test`.
        let library = unsafe { libloading::Library::new(&path) }
            .unwrap_or_else(|error| panic!("loading {}: {error}", path.display()));
        unsafe {
            let entry: libloading::Symbol<unsafe extern "C" fn(*mut c_void) -> bool> =
                library.get(b"ModuleEntry").expect("ModuleEntry");
            assert!(entry(std::ptr::null_mut()), "ModuleEntry failed");
        }
        Self { library }
    }

    fn factory(&self) -> ComPtr<IPluginFactory> {
        unsafe {
            let get: libloading::Symbol<unsafe extern "system" fn() -> *mut c_void> = self
                .library
                .get(b"GetPluginFactory")
                .expect("GetPluginFactory");
            ComPtr::from_raw(get() as *mut IPluginFactory).expect("a plugin factory")
        }
    }

    /// A new, initialised instance of the audio-module class.
    fn instantiate(&self) -> (ComPtr<IComponent>, ComPtr<IAudioProcessor>) {
        let factory = self.factory();
        unsafe {
            let count = factory.countClasses();
            let mut found = None;
            for index in 0..count {
                let mut info: PClassInfo = std::mem::zeroed();
                assert_eq!(factory.getClassInfo(index, &mut info), kResultOk);
                let category = CStr::from_ptr(info.category.as_ptr()).to_string_lossy();
                let name = CStr::from_ptr(info.name.as_ptr()).to_string_lossy();
                if category == "Audio Module Class" && name == "Javari" {
                    found = Some(info.cid);
                }
            }
            let cid = found.expect("the Javari audio module class");
            let mut object: *mut c_void = std::ptr::null_mut();
            let result = factory.createInstance(
                cid.as_ptr(),
                IComponent::IID.as_ptr() as *const _,
                &mut object,
            );
            assert_eq!(result, kResultOk, "createInstance");
            let component = ComPtr::from_raw(object as *mut IComponent).expect("IComponent");
            assert_eq!(component.initialize(std::ptr::null_mut()), kResultOk);
            let processor = component
                .cast::<IAudioProcessor>()
                .expect("IAudioProcessor on the component");
            (component, processor)
        }
    }
}

/// The module, entered once for every test of this file and never exited or unloaded: tests
/// run in parallel threads, and `ModuleExit` or unloading under another test's running instance
/// would pull the plugin away from it (as a host never does).
fn module() -> &'static Module {
    static MODULE: std::sync::OnceLock<Module> = std::sync::OnceLock::new();
    MODULE.get_or_init(Module::load)
}

fn note_on(offset: i32, key: i16, velocity: f32) -> Event {
    Event {
        busIndex: 0,
        sampleOffset: offset,
        ppqPosition: 0.0,
        flags: 0,
        r#type: Event_::EventTypes_::kNoteOnEvent as u16,
        __field0: Event__type0 {
            noteOn: NoteOnEvent {
                channel: 0,
                pitch: key,
                tuning: 0.0,
                velocity,
                length: 0,
                noteId: -1,
            },
        },
    }
}

/// Activates the instance at `sample_rate` and plays `key` from sample `note_at`.
fn play(
    component: &ComPtr<IComponent>,
    processor: &ComPtr<IAudioProcessor>,
    sample_rate: f64,
    block_size: usize,
    key: i16,
    note_at: usize,
    seconds: f64,
) -> (Vec<f32>, Vec<f32>) {
    play_automated(
        component,
        processor,
        (sample_rate, block_size),
        (key, note_at),
        &[],
        seconds,
    )
}

/// As [`play`], with parameter changes `(sample, parameter ID, normalised value)` made through
/// the edit controller before the block holding the sample, as a host's editor thread would
/// between blocks (processing paused, since nice-plug takes `setParamNormalized` only then).
fn play_automated(
    component: &ComPtr<IComponent>,
    processor: &ComPtr<IAudioProcessor>,
    (sample_rate, block_size): (f64, usize),
    (key, note_at): (i16, usize),
    automation: &[(usize, ParamID, f64)],
    seconds: f64,
) -> (Vec<f32>, Vec<f32>) {
    let controller = component
        .cast::<IEditController>()
        .expect("IEditController on the component");
    unsafe {
        let audio = MediaTypes_::kAudio as i32;
        let event = MediaTypes_::kEvent as i32;
        let output = BusDirections_::kOutput as i32;
        let input = BusDirections_::kInput as i32;
        assert_eq!(component.getBusCount(audio, output), 1);
        assert_eq!(component.getBusCount(event, input), 1);
        assert_eq!(component.activateBus(audio, output, 0, 1), kResultOk);
        assert_eq!(component.activateBus(event, input, 0, 1), kResultOk);
        let mut setup = ProcessSetup {
            processMode: ProcessModes_::kRealtime as i32,
            symbolicSampleSize: SymbolicSampleSizes_::kSample32 as i32,
            maxSamplesPerBlock: block_size as i32,
            sampleRate: sample_rate,
        };
        assert_eq!(processor.setupProcessing(&mut setup), kResultOk);
        assert_eq!(component.setActive(1), kResultOk);
        processor.setProcessing(1);

        let total = (seconds * sample_rate) as usize;
        let (mut left, mut right) = (Vec::with_capacity(total), Vec::with_capacity(total));
        let mut channel_left = vec![0.0f32; block_size];
        let mut channel_right = vec![0.0f32; block_size];
        let mut start = 0;
        while start < total {
            let frames = block_size.min(total - start);
            let block = start..start + frames;
            if automation.iter().any(|(at, ..)| block.contains(at)) {
                processor.setProcessing(0);
                for &(_, id, value) in automation.iter().filter(|(at, ..)| block.contains(at)) {
                    controller.setParamNormalized(id, value);
                }
                processor.setProcessing(1);
            }
            let events = if (start..start + frames).contains(&note_at) {
                vec![note_on((note_at - start) as i32, key, 0.4)]
            } else {
                Vec::new()
            };
            let event_list = ComWrapper::new(EventList { events });
            let event_pointer = event_list.to_com_ptr::<IEventList>().unwrap();
            let mut channels = [channel_left.as_mut_ptr(), channel_right.as_mut_ptr()];
            let mut bus = AudioBusBuffers {
                numChannels: 2,
                silenceFlags: 0,
                __field0: AudioBusBuffers__type0 {
                    channelBuffers32: channels.as_mut_ptr(),
                },
            };
            let mut data = ProcessData {
                processMode: ProcessModes_::kRealtime as i32,
                symbolicSampleSize: SymbolicSampleSizes_::kSample32 as i32,
                numSamples: frames as i32,
                numInputs: 0,
                numOutputs: 1,
                inputs: std::ptr::null_mut(),
                outputs: &mut bus,
                inputParameterChanges: std::ptr::null_mut(),
                outputParameterChanges: std::ptr::null_mut(),
                inputEvents: event_pointer.as_ptr(),
                outputEvents: std::ptr::null_mut(),
                processContext: std::ptr::null_mut(),
            };
            assert_eq!(processor.process(&mut data), kResultOk, "process");
            left.extend_from_slice(&channel_left[..frames]);
            right.extend_from_slice(&channel_right[..frames]);
            start += frames;
        }
        processor.setProcessing(0);
        assert_eq!(component.setActive(0), kResultOk);
        (left, right)
    }
}

#[test]
fn vst3_plays_in_tune_at_several_rates_and_block_sizes() {
    let module = module();
    let key = 57; // A3, 220 Hz
    for (sample_rate, block_size) in [(44_100.0, 256usize), (48_000.0, 100), (88_200.0, 2048)] {
        let (component, processor) = module.instantiate();
        let note_at = 77;
        let (left, right) = play(
            &component,
            &processor,
            sample_rate,
            block_size,
            key,
            note_at,
            0.6,
        );
        // Stereo: the string panned by its pitch; the mid signal is the mono output.
        let left = finite_mid(&left, &right);
        assert_eq!(peak(&left[..note_at]), 0.0, "silent before the note");
        let ringing = &left[(0.1 * sample_rate) as usize..];
        let level = peak(ringing);
        assert!(level > 1e-3 && level < 1.0, "level {level}");
        let expected = note_to_hz(key as u8);
        let measured = peak_frequency_near(ringing, sample_rate, expected, 60.0);
        let error = cents(measured, expected);
        println!("VST3 {sample_rate} Hz, block {block_size}: {measured:.3} Hz ({error:+.2} cents)");
        assert!(error.abs() < 5.0, "{error} cents");
        unsafe {
            component.terminate();
        }
    }
}

#[test]
fn vst3_state_round_trip() {
    let module = module();
    let (first, first_processor) = module.instantiate();
    let saved = ComWrapper::new(MemoryStream {
        bytes: RefCell::new(Vec::new()),
        position: RefCell::new(0),
    });
    unsafe {
        let stream = saved.to_com_ptr::<IBStream>().unwrap();
        assert_eq!(first.getState(stream.as_ptr()), kResultOk);
    }
    let text = String::from_utf8(saved.bytes.borrow().clone()).expect("JSON state");
    assert!(text.contains("\"gain\":{\"f32\":0.0}"), "{text}");

    // Load an edited state (gain −12 dB, thread off) into a second instance and read it back.
    let edited = text
        .replace("\"gain\":{\"f32\":0.0}", "\"gain\":{\"f32\":-12.0}")
        .replace("\"thon\":{\"bool\":true}", "\"thon\":{\"bool\":false}");
    assert_ne!(edited, text);
    let (second, second_processor) = module.instantiate();
    let input = ComWrapper::new(MemoryStream {
        bytes: RefCell::new(edited.clone().into_bytes()),
        position: RefCell::new(0),
    });
    let output = ComWrapper::new(MemoryStream {
        bytes: RefCell::new(Vec::new()),
        position: RefCell::new(0),
    });
    unsafe {
        let input_stream = input.to_com_ptr::<IBStream>().unwrap();
        assert_eq!(second.setState(input_stream.as_ptr()), kResultOk);
        let output_stream = output.to_com_ptr::<IBStream>().unwrap();
        assert_eq!(second.getState(output_stream.as_ptr()), kResultOk);
    }
    let resaved = String::from_utf8(output.bytes.borrow().clone()).unwrap();
    assert_eq!(resaved, edited);
    let (quiet, _) = play(&second, &second_processor, 44_100.0, 512, 60, 0, 0.2);
    let (loud, _) = play(&first, &first_processor, 44_100.0, 512, 60, 0, 0.2);
    assert!(
        peak(&quiet) < 0.5 * peak(&loud),
        "the loaded −12 dB gain applies"
    );
    unsafe {
        first.terminate();
        second.terminate();
    }
}

/// The latency the engine has at `quality`, in whole samples at 44.1 kHz.
fn engine_latency(quality: Quality) -> u32 {
    let mut settings = EngineSettings::default();
    settings.voice.quality = quality;
    Engine::new(&settings, 44_100.0, 1)
        .latency_samples()
        .round() as u32
}

/// The ID of the parameter titled `title`.
fn parameter_id(component: &ComPtr<IComponent>, title: &str) -> ParamID {
    let controller = component.cast::<IEditController>().unwrap();
    unsafe {
        (0..controller.getParameterCount())
            .find_map(|index| {
                let mut info: ParameterInfo = std::mem::zeroed();
                controller.getParameterInfo(index, &mut info);
                let end = info.title.iter().position(|c| *c == 0).unwrap_or(128);
                (String::from_utf16_lossy(&info.title[..end]) == title).then_some(info.id)
            })
            .unwrap_or_else(|| panic!("no parameter titled {title}"))
    }
}

/// The plugin reports the latency of its tier (the oversampled tiers' decimator delay, studio and
/// reference; none for the others): automating the tier while it processes asks the host to restart
/// it with `kLatencyChanged` when the latency changes (and only then), `getLatencySamples` returns
/// the new latency, and the restart's activation adopts it without asking again.
#[test]
fn vst3_latency_follows_the_tier_through_a_restart() {
    let module = module();
    let (component, processor) = module.instantiate();
    let handler = ComWrapper::new(ComponentHandler::default());
    let controller = component.cast::<IEditController>().unwrap();
    unsafe {
        let handler_pointer = handler.to_com_ptr::<IComponentHandler>().unwrap();
        assert_eq!(
            controller.setComponentHandler(handler_pointer.as_ptr()),
            kResultOk
        );
    }
    let quality = parameter_id(&component, "Quality");
    let latency_restart =
        || handler.restart_flags.swap(0, Ordering::SeqCst) & RestartFlags_::kLatencyChanged != 0;
    let latency = || unsafe { processor.getLatencySamples() };
    let reference_latency = engine_latency(Quality::Reference);
    assert!(reference_latency > 0, "the reference has a decimator delay");
    assert!(
        engine_latency(Quality::Studio) > 0,
        "so has the studio tier"
    );
    assert_eq!(engine_latency(Quality::Live), 0);
    assert_eq!(engine_latency(Quality::Fine), 0);

    play(&component, &processor, 44_100.0, 64, 57, 0, 0.02);
    assert!(!latency_restart(), "a restart at the default tier");
    assert_eq!(latency(), 0, "fine, the default");

    // Normalised enum values: live 0, fine 1/3, studio 2/3, reference 1.
    for (tier, value) in [
        (Quality::Studio, 2.0 / 3.0),
        (Quality::Reference, 1.0),
        (Quality::Live, 0.0),
        (Quality::Fine, 1.0 / 3.0),
        (Quality::Reference, 1.0),
    ] {
        let before = latency();
        let wanted = engine_latency(tier);
        play_automated(
            &component,
            &processor,
            (44_100.0, 64),
            (57, 0),
            &[(640, quality, value)],
            0.05,
        );
        let restarted = latency_restart();
        println!(
            "{tier:?}: latency {} samples, restart {restarted}",
            latency()
        );
        assert_eq!(restarted, wanted != before, "{tier:?}: kLatencyChanged");
        assert_eq!(latency(), wanted, "{tier:?}");
        // The host restarts the plugin; that activation adopts the latency and asks no more.
        play(&component, &processor, 44_100.0, 64, 57, 0, 0.02);
        assert!(!latency_restart(), "{tier:?}: a second restart");
        assert_eq!(latency(), wanted, "{tier:?}");
    }
    unsafe {
        controller.setComponentHandler(std::ptr::null_mut());
        component.terminate();
    }
}

fn get_state(component: &ComPtr<IComponent>) -> String {
    let stream = ComWrapper::new(MemoryStream {
        bytes: RefCell::new(Vec::new()),
        position: RefCell::new(0),
    });
    unsafe {
        let pointer = stream.to_com_ptr::<IBStream>().unwrap();
        assert_eq!(component.getState(pointer.as_ptr()), kResultOk);
    }
    let bytes = stream.bytes.borrow().clone();
    String::from_utf8(bytes).expect("JSON state")
}

/// Loads `bytes` as the state; whether the plugin accepted it.
fn set_state(component: &ComPtr<IComponent>, bytes: &[u8]) -> bool {
    let stream = ComWrapper::new(MemoryStream {
        bytes: RefCell::new(bytes.to_vec()),
        position: RefCell::new(0),
    });
    unsafe {
        let pointer = stream.to_com_ptr::<IBStream>().unwrap();
        component.setState(pointer.as_ptr()) == kResultOk
    }
}

/// Blobs a host might hand over that are not a Javari state: refused or repaired, never a
/// crash; a fresh instance given one saves (and plays) its defaults, and a foreign state over
/// an edited instance brings back every default.
#[test]
fn vst3_corrupt_or_foreign_state_loads_the_defaults() {
    let module = module();
    let (fresh, _) = module.instantiate();
    let defaults = get_state(&fresh);
    let pseudo_random: Vec<u8> = (0u32..4096)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    let blobs: [(&str, Vec<u8>); 6] = [
        ("empty", Vec::new()),
        ("bytes that are not JSON", b"\x00\x01garbage\xff".to_vec()),
        ("JSON of another shape", br#"{"presets":[1,2,3]}"#.to_vec()),
        (
            "truncated state",
            defaults.as_bytes()[..defaults.len() / 2].to_vec(),
        ),
        (
            "another plugin's state",
            br#"{"version":"2.1","params":{"cutoff":{"f32":880.0}},"fields":{}}"#.to_vec(),
        ),
        ("pseudo-random bytes", pseudo_random),
    ];
    for (what, blob) in &blobs {
        let (component, processor) = module.instantiate();
        let accepted = set_state(&component, blob);
        println!("{what}: {}", if accepted { "accepted" } else { "refused" });
        assert_eq!(get_state(&component), defaults, "{what}: defaults");
        let (left, _) = play(&component, &processor, 44_100.0, 256, 57, 0, 0.1);
        assert!(left.iter().all(|x| x.is_finite()), "{what}");
        assert!(peak(&left) > 1e-3, "{what}: plays");
        unsafe {
            component.terminate();
        }
    }

    let (edited, _) = module.instantiate();
    let quiet = defaults.replace("\"gain\":{\"f32\":0.0}", "\"gain\":{\"f32\":-12.0}");
    assert!(set_state(&edited, quiet.as_bytes()));
    assert_eq!(get_state(&edited), quiet);
    assert!(set_state(
        &edited,
        br#"{"params":{"x":{"bool":true}},"fields":{}}"#
    ));
    assert_eq!(get_state(&edited), defaults, "foreign state: defaults");

    // Out-of-range numbers are clamped, and the state saved afterwards loads again.
    let wild = defaults
        .replace("\"gain\":{\"f32\":0.0}", "\"gain\":{\"f32\":1e39}")
        .replace("\"kb\":{\"f32\":8.0}", "\"kb\":{\"f32\":-1e30}");
    assert_ne!(wild, defaults);
    assert!(set_state(&edited, wild.as_bytes()));
    let saved = get_state(&edited);
    assert!(saved.contains("\"gain\":{\"f32\":24.0}"), "{saved}");
    assert!(saved.contains("\"kb\":{\"f32\":5.0}"), "{saved}");
    let (reloaded, _) = module.instantiate();
    assert!(set_state(&reloaded, saved.as_bytes()));
    assert_eq!(get_state(&reloaded), saved);
    unsafe {
        fresh.terminate();
        edited.terminate();
        reloaded.terminate();
    }
}

/// Non-finite automation is refused and out-of-range automation clamped to the range; the
/// output stays finite.
#[test]
fn vst3_non_finite_and_out_of_range_automation_is_clamped() {
    let module = module();
    let (component, processor) = module.instantiate();
    let gain = parameter_id(&component, "Output gain");
    let stiffness = parameter_id(&component, "Bridge stiffness");
    let controller = component.cast::<IEditController>().unwrap();
    unsafe {
        assert_ne!(controller.setParamNormalized(gain, f64::NAN), kResultOk);
        assert_ne!(
            controller.setParamNormalized(gain, f64::INFINITY),
            kResultOk
        );
        assert_eq!(controller.setParamNormalized(gain, 1e30), kResultOk);
        assert_eq!(controller.setParamNormalized(stiffness, -1e30), kResultOk);
        assert_eq!(controller.getParamNormalized(gain), 1.0);
        assert_eq!(controller.getParamNormalized(stiffness), 0.0);
    }
    let automation = [(3_000, gain, f64::NAN), (3_000, stiffness, 1e30)];
    let (left, _) = play_automated(
        &component,
        &processor,
        (44_100.0, 128),
        (57, 0),
        &automation,
        0.3,
    );
    assert!(left.iter().all(|x| x.is_finite()), "non-finite sample");
    let state = get_state(&component);
    assert!(state.contains("\"gain\":{\"f32\":24.0}"), "{state}");
    assert!(state.contains("\"kb\":{\"f32\":11.0}"), "{state}");
    unsafe {
        component.terminate();
    }
}
