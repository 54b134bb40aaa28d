//! What moving the thread does to a string's sound: the formant's course (spectral centroid
//! above 5.5 f₀ over time, `analysis/listening.rs`) and the level above 2 kHz of single plucks
//! with the thread at several positions, on one tier:
//! `cargo run --release -p javari-core --example jawari_moves -- TIER KEY VELOCITY MM…`
//! (defaults: studio, key 51, velocity 80, threads 39, 40 and 41 mm). It measures why the
//! as-played tuning (`tanpura/as_played.rs`) settles a note whose pitch depends on how hard it
//! is plucked by moving its thread a fraction of a millimetre and no further: those strings sit
//! at the jawari's sweet spot, and a millimetre either way also takes most of their brightness.

use javari_core::analysis::listening::centroid_course_hz;
use javari_core::analysis::{band_power, power_spectrum};
use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};

const SAMPLE_RATE: f64 = 44_100.0;
const SECONDS: f64 = 1.6;

fn main() {
    let arguments: Vec<String> = std::env::args().skip(1).collect();
    let quality = arguments
        .first()
        .and_then(|name| Quality::from_name(name))
        .unwrap_or(Quality::Studio);
    let numbers: Vec<f64> = arguments
        .iter()
        .skip(1)
        .filter_map(|text| text.parse().ok())
        .collect();
    let key = numbers.first().map_or(51, |&key| key as u8);
    let velocity = numbers.get(1).map_or(80.0, |&velocity| velocity);
    let mut threads_mm: Vec<f64> = numbers.iter().skip(2).copied().collect();
    if threads_mm.is_empty() {
        threads_mm = vec![39.0, 40.0, 41.0];
    }
    let fundamental_hz = note_to_hz(key);
    println!(
        "{} tier, key {key}, velocity {velocity}: formant centre (Hz) at 0.1 / 0.3 / 0.6 / 1.2 s, \
         level above 2 kHz relative to the whole (dB) over 0–0.3 s and 0.6–1.2 s",
        quality.name()
    );
    for thread_mm in threads_mm {
        let settings = VoiceSettings {
            fundamental_hz,
            quality,
            thread_position_m: thread_mm / 1000.0,
            ..VoiceSettings::default()
        };
        let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
        let pluck = Pluck::default();
        voice.pluck(&Pluck {
            amplitude_m: pluck.amplitude_m * velocity / 127.0,
            ..pluck
        });
        let samples = (SECONDS * SAMPLE_RATE) as usize;
        let signal: Vec<f64> = (0..samples)
            .map(|_| f64::from(voice.next_sample()))
            .collect();
        let course = centroid_course_hz(&signal, SAMPLE_RATE, fundamental_hz);
        let at = |seconds: f64| {
            let index = (seconds / SECONDS * course.len() as f64) as usize;
            course[index.min(course.len() - 1)]
        };
        let high_share_db = |from_s: f64, to_s: f64| {
            let start = (from_s * SAMPLE_RATE) as usize;
            let length = ((to_s - from_s) * SAMPLE_RATE) as usize;
            let frame = length.next_power_of_two() / 2;
            let spectrum = power_spectrum(&signal, start, frame, frame);
            let bin = SAMPLE_RATE / frame as f64;
            let high = band_power(&spectrum, bin, 2000.0, 20_000.0);
            let all = band_power(&spectrum, bin, 20.0, 20_000.0);
            10.0 * (high / all).log10()
        };
        println!(
            "thread {thread_mm:>5.2} mm: {:>6.0} {:>6.0} {:>6.0} {:>6.0} Hz | {:>6.1} {:>6.1} dB",
            at(0.1),
            at(0.3),
            at(0.6),
            at(1.2),
            high_share_db(0.0, 0.3),
            high_share_db(0.6, 1.2)
        );
    }
}
