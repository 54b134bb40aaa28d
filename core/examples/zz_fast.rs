use javari_core::analysis::refined::refined_reference_pluck;
use javari_core::analysis::{cents, first_partials_hz};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
fn main() {
    let f0 = VoiceSettings::default().fundamental_hz;
    for velocity in [127.0, 1.0] {
        let p = Pluck::default();
        let pluck = Pluck {
            amplitude_m: p.amplitude_m * velocity / 127.0,
            ..p
        };
        let yard = first_partials_hz(
            &refined_reference_pluck(&VoiceSettings::default(), 4, &pluck, 3.0, 44100.0)
                .unwrap()
                .output,
            44100.0,
            f0,
            10,
        );
        for rate in [44100.0, 88200.0, 176400.0] {
            let s = VoiceSettings {
                quality: Quality::Live,
                ..VoiceSettings::default()
            };
            let mut v = TanpuraVoice::new(&s, rate);
            v.pluck(&pluck);
            let out: Vec<f64> = (0..(3.0 * rate) as usize)
                .map(|_| f64::from(v.next_sample()))
                .collect();
            let parts = first_partials_hz(&out, rate, f0, 10);
            let c: Vec<String> = parts
                .iter()
                .zip(&yard)
                .map(|(a, b)| format!("{:+.2}", cents(*a, *b)))
                .collect();
            println!("v{velocity} rate {rate}: {}", c.join(" "));
        }
    }
}
