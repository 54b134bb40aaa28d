//! The engine at the extremes a host can throw at it: block sizes from 1 to 8192, output rates
//! from 22.05 kHz to 384 kHz, both instruments. The output must not depend on the block size
//! (events sit at absolute sample times) and must stay finite and below full scale.

use javari_core::engine::render::{render, RenderOptions, Score};
use javari_core::engine::{EngineSettings, Instrument};
use javari_core::tanpura::quality::Quality;

fn score() -> Score {
    let mut score = Score::default();
    for (index, note) in [45u8, 57, 64, 52].into_iter().enumerate() {
        score.note(0.013 + 0.11 * index as f64, 0.2, note, 0.8);
    }
    score
}

fn settings(instrument: Instrument) -> EngineSettings {
    let mut settings = EngineSettings {
        instrument,
        ..EngineSettings::default()
    };
    settings.voice.quality = Quality::Draft;
    settings
}

fn render_with(instrument: Instrument, sample_rate_hz: f64, block_size: usize) -> Vec<f32> {
    let options = RenderOptions {
        sample_rate_hz,
        block_size,
        tail_s: 0.1,
        ..RenderOptions::default()
    };
    render(&settings(instrument), &score(), &options, &mut |_, _| {})
}

#[test]
fn block_sizes_from_1_to_8192_give_the_same_output() {
    for instrument in [Instrument::Tanpura, Instrument::Bowed] {
        let reference = render_with(instrument, 44_100.0, 8192);
        assert!(reference.iter().any(|&x| x != 0.0));
        for block_size in [1, 3, 64, 1000] {
            let other = render_with(instrument, 44_100.0, block_size);
            assert!(
                other
                    .iter()
                    .map(|x| x.to_bits())
                    .eq(reference.iter().map(|x| x.to_bits())),
                "{instrument:?}: block size {block_size} differs from 8192"
            );
        }
    }
}

#[test]
fn output_rates_from_22050_to_384000_stay_finite_and_below_full_scale() {
    for instrument in [Instrument::Tanpura, Instrument::Bowed] {
        for rate in [22_050.0, 48_000.0, 96_000.0, 192_000.0, 384_000.0] {
            let output = render_with(instrument, rate, 512);
            assert!(
                output.iter().all(|x| x.is_finite()),
                "{instrument:?} at {rate}"
            );
            let peak = output.iter().fold(0.0f32, |a, x| a.max(x.abs()));
            assert!(
                peak > 1e-4 && peak < 1.0,
                "{instrument:?} at {rate}: peak {peak}"
            );
        }
    }
}
