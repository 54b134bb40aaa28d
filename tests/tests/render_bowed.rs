//! The bowed phrase fixture (`tests/fixtures/bowed.mid`: a slur, a detached note, bow pressure
//! and bow position controllers) rendered with the `presets/bowed-violin.toml` preset through
//! `javari_core::engine::render`, the path of `cargo xtask render`, and written to WAV: length,
//! finite samples, peak below 0 dBFS, each note's pitch within 5 cents once its glide is over,
//! a silent string before the first note, bit-identical re-render and block sizes 1, 64 and 4096
//! giving the same output. The notes sound 1.8 to 4.5 cents flat: bow force lowers the pitch of
//! Helmholtz motion (the flattening effect), most on the slurred C4, bowed hardest.

use javari_core::engine::midi_file;
use javari_core::engine::pitch::{cents, note_to_hz};
use javari_core::engine::preset::Preset;
use javari_core::engine::render::{render, rendered_length, RenderOptions, Score};
use javari_core::engine::wav::{read_wav, write_wav};
use javari_core::engine::{EngineSettings, Instrument};
use javari_tests::{fixtures_dir, peak, peak_frequency_near, repository_root, BOWED_PHRASE};

const RATE: f64 = 44_100.0;
const TICKS_PER_SECOND: f64 = 960.0;

fn violin() -> EngineSettings {
    let preset = Preset::load(&repository_root().join("presets/bowed-violin.toml")).unwrap();
    assert_eq!(preset.settings.instrument, Instrument::Bowed);
    preset.settings
}

fn score() -> Score {
    midi_file::load(&fixtures_dir().join("bowed.mid"))
        .unwrap()
        .score
}

fn options(block_size: usize) -> RenderOptions {
    RenderOptions {
        sample_rate_hz: RATE,
        block_size,
        tail_s: 0.5,
        ..RenderOptions::default()
    }
}

#[test]
fn bowed_phrase_renders_in_tune_and_sane() {
    let score = score();
    let options = options(512);
    let signal = render(&violin(), &score, &options, &mut |_, _| {});
    let path = std::env::temp_dir().join(format!("javari-bowed-{}.wav", std::process::id()));
    write_wav(&path, &signal, RATE).unwrap();
    let (read, rate) = read_wav(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!((read.len(), rate), (signal.len(), RATE));
    assert_eq!(signal.len(), rendered_length(&score, &options));
    assert!(signal.iter().all(|x| x.is_finite()));
    let peak_dbfs = 20.0 * f64::from(peak(&signal)).log10();
    assert!(
        peak_dbfs < 0.0 && peak_dbfs > -40.0,
        "peak {peak_dbfs} dBFS"
    );
    let first_start = (BOWED_PHRASE[0].0 as f64 / TICKS_PER_SECOND * RATE) as usize;
    assert!(
        signal[..first_start].iter().all(|&x| x == 0.0),
        "sound before the bow"
    );
    for (start_tick, length_ticks, key) in BOWED_PHRASE {
        // From 0.3 s into the note (attack and the 80 ms slur glide are over) to its end.
        let from = ((start_tick as f64 / TICKS_PER_SECOND + 0.3) * RATE) as usize;
        let to = (((start_tick + length_ticks) as f64 / TICKS_PER_SECOND) * RATE) as usize;
        let expected = note_to_hz(key);
        let found = peak_frequency_near(&signal[from..to], RATE, expected, 50.0);
        let error = cents(found, expected);
        println!("note {key}: {found:.3} Hz, {error:+.2} cents");
        assert!(error.abs() < 5.0, "note {key}: {error} cents");
    }
}

#[test]
fn bowed_phrase_is_bit_identical_across_renders_and_block_sizes() {
    let score = score();
    let reference = render(&violin(), &score, &options(4096), &mut |_, _| {});
    for block_size in [4096, 64, 1] {
        let other = render(&violin(), &score, &options(block_size), &mut |_, _| {});
        assert!(
            other
                .iter()
                .map(|x| x.to_bits())
                .eq(reference.iter().map(|x| x.to_bits())),
            "block size {block_size} differs"
        );
    }
}
