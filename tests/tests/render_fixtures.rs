//! The committed MIDI fixtures rendered through `javari_core::engine::render` (the path of
//! `cargo xtask render`) and written to WAV, then checked: length, finite samples, peak below
//! 0 dBFS, pitch of each note within 5 cents, onsets within 1 ms of the MIDI, bit-identical
//! re-render, and block sizes 1, 64 and 4096 agreeing within 1e-6.

use javari_core::engine::midi_file;
use javari_core::engine::pitch::{cents, note_to_hz};
use javari_core::engine::render::{render, rendered_length, time_to_sample, RenderOptions, Score};
use javari_core::engine::wav::{read_wav, write_wav};
use javari_core::engine::EngineSettings;
use javari_tests::{first_above, fixtures, fixtures_dir, peak, peak_frequency_near, Fixture};
use std::path::PathBuf;

const RATE: f64 = 44_100.0;

fn fixture(name: &str) -> (Fixture, Score) {
    let fixture = fixtures()
        .into_iter()
        .find(|fixture| fixture.file_name == name)
        .unwrap();
    let score = midi_file::load(&fixtures_dir().join(name)).unwrap().score;
    (fixture, score)
}

fn options(block_size: usize, tail_s: f64) -> RenderOptions {
    RenderOptions {
        sample_rate_hz: RATE,
        block_size,
        tail_s,
        ..RenderOptions::default()
    }
}

fn output_path(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("javari-test-{}-{name}", std::process::id()))
}

/// Renders, writes the WAV file and reads it back, as `cargo xtask render` and a listener would.
fn render_to_wav(score: &Score, options: &RenderOptions, name: &str) -> Vec<f32> {
    let signal = render(&EngineSettings::default(), score, options, &mut |_, _| {});
    let path = output_path(name);
    write_wav(&path, &signal, options.sample_rate_hz).unwrap();
    let (read, rate) = read_wav(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(rate, options.sample_rate_hz);
    assert_eq!(read, signal, "WAV round trip");
    read
}

fn assert_sane(signal: &[f32], score: &Score, options: &RenderOptions) {
    assert_eq!(signal.len(), rendered_length(score, options));
    let expected = ((score.end_s + options.tail_s) * RATE).round() as usize + 1;
    assert_eq!(signal.len(), expected);
    assert!(signal.iter().all(|x| x.is_finite()), "NaN or Inf in output");
    let peak_dbfs = 20.0 * f64::from(peak(signal)).log10();
    println!("peak {peak_dbfs:.2} dBFS");
    assert!(peak_dbfs < 0.0, "peak {peak_dbfs} dBFS");
    assert!(peak_dbfs > -40.0, "suspiciously quiet: {peak_dbfs} dBFS");
}

#[test]
fn scale_notes_have_their_pitch_and_onset() {
    let (fixture, score) = fixture("scale.mid");
    let options = options(512, 0.2);
    let signal = render_to_wav(&score, &options, "scale.wav");
    assert_sane(&signal, &score, &options);
    for note in &fixture.notes {
        let key = note.key;
        let onset_expected = time_to_sample(note.start_s(), RATE);
        // Everything before the note is silent (the previous one was silenced by CC 120).
        let quiet_before = &signal[onset_expected.saturating_sub(400)..onset_expected];
        assert!(
            peak(quiet_before) < 1e-6,
            "note {key}: not silent before its onset"
        );
        let note_end = onset_expected + (0.55 * RATE) as usize;
        let note_signal = &signal[onset_expected..note_end];
        let threshold = 0.01 * peak(note_signal);
        let onset = first_above(&signal, onset_expected.saturating_sub(441), threshold).unwrap();
        let onset_error_ms = (onset as f64 - onset_expected as f64) / RATE * 1e3;

        // Pitch over 0.1–0.55 s after the pluck, past the attack.
        let window = &signal[onset_expected + (0.1 * RATE) as usize..note_end];
        let expected_hz = note_to_hz(key);
        let measured_hz = peak_frequency_near(window, RATE, expected_hz, 60.0);
        let error_cents = cents(measured_hz, expected_hz);
        println!(
            "note {key}: expected {expected_hz:.3} Hz, measured {measured_hz:.3} Hz \
             ({error_cents:+.2} cents), onset {onset_error_ms:+.3} ms"
        );
        assert!(
            onset_error_ms.abs() <= 1.0,
            "note {key}: onset {onset_error_ms} ms"
        );
        assert!(error_cents.abs() < 5.0, "note {key}: {error_cents} cents");
    }
}

#[test]
fn polyphony_is_finite_below_full_scale_and_bit_identical_twice() {
    let (_, score) = fixture("polyphony.mid");
    let options = options(256, 0.3);
    let first = render_to_wav(&score, &options, "poly-1.wav");
    assert_sane(&first, &score, &options);
    let second = render_to_wav(&score, &options, "poly-2.wav");
    assert!(
        first
            .iter()
            .map(|x| x.to_bits())
            .eq(second.iter().map(|x| x.to_bits())),
        "second render differs"
    );
}

#[test]
fn block_sizes_1_64_and_4096_agree_within_1e_6() {
    let (_, score) = fixture("polyphony.mid");
    let reference = render(
        &EngineSettings::default(),
        &score,
        &options(4096, 0.1),
        &mut |_, _| {},
    );
    for block_size in [1, 64] {
        let other = render(
            &EngineSettings::default(),
            &score,
            &options(block_size, 0.1),
            &mut |_, _| {},
        );
        assert_eq!(other.len(), reference.len());
        let largest = other
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        println!("block size {block_size}: largest difference to 4096 is {largest:e}");
        assert!(largest <= 1e-6, "block size {block_size}: {largest}");
    }
}

/// A hard pluck (full velocity, 2 mm) on E3 sounds flat while its amplitude is large, then
/// glides to its tuned pitch: the contact with bridge and thread makes the pitch depend on the
/// amplitude. Measured: −6.5 cents over 0.1–0.6 s, −1.1 cents over 1.6–2.1 s (0.76 mm: −0.4).
#[test]
fn full_velocity_pitch_glides_in() {
    let mut score = Score::default();
    score.note(0.0, 0.1, 52, 1.0);
    let signal = render(
        &EngineSettings::default(),
        &score,
        &options(512, 2.1),
        &mut |_, _| {},
    );
    let expected_hz = note_to_hz(52);
    let measure = |from_s: f64, to_s: f64| {
        let window = &signal[(from_s * RATE) as usize..(to_s * RATE) as usize];
        cents(
            peak_frequency_near(window, RATE, expected_hz, 60.0),
            expected_hz,
        )
    };
    let early = measure(0.1, 0.6);
    let late = measure(1.6, 2.1);
    println!("E3 at full velocity: {early:+.2} cents early, {late:+.2} cents late");
    assert!((-9.0..=-4.0).contains(&early), "{early}");
    assert!(late.abs() < 2.0, "{late}");
}

#[test]
fn every_factory_preset_loads_and_plays_in_tune() {
    let presets = ["classic", "no-thread", "bright-jawari", "soft"];
    for name in presets {
        let path = javari_tests::repository_root()
            .join("presets")
            .join(format!("{name}.toml"));
        let preset = javari_core::engine::preset::Preset::load(&path).unwrap();
        let mut score = Score::default();
        score.note(0.0, 0.2, 57, 0.4);
        let options = options(512, 0.6);
        let signal = render(&preset.settings, &score, &options, &mut |_, _| {});
        assert!(signal.iter().all(|x| x.is_finite()), "{name}: NaN or Inf");
        let peak_dbfs = 20.0 * f64::from(peak(&signal)).log10();
        let window = &signal[(0.1 * RATE) as usize..];
        let measured = peak_frequency_near(window, RATE, note_to_hz(57), 60.0);
        let error = cents(measured, note_to_hz(57));
        println!("{name}: peak {peak_dbfs:.2} dBFS, A3 {error:+.2} cents");
        assert!(
            (-40.0..0.0).contains(&peak_dbfs),
            "{name}: {peak_dbfs} dBFS"
        );
        assert!(error.abs() < 5.0, "{name}: {error} cents");
    }
}
