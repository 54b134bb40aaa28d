use javari_core::analysis::listening::sustained_pitch_hz;
use javari_core::analysis::{band_power, cents, power_spectrum};
use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::as_played::{
    as_played_offset_cents, CALIBRATION_SECONDS, NOTE_VELOCITIES,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
const SR: f64 = 44_100.0;
const VELS: [u8; 7] = [1, 40, 60, 75, 90, 110, 127];
fn render(voice: &mut TanpuraVoice, target: f64, vel: f64, seconds: f64) -> Vec<f64> {
    let s = VoiceSettings {
        fundamental_hz: target,
        ..*voice.settings()
    };
    voice.set_settings(&s);
    voice.reset();
    let p = Pluck::default();
    voice.pluck(&Pluck {
        amplitude_m: p.amplitude_m * vel,
        ..p
    });
    (0..(seconds * SR) as usize)
        .map(|_| f64::from(voice.next_sample()))
        .collect()
}
fn high(signal: &[f64], a: f64, b: f64) -> f64 {
    let start = (a * SR) as usize;
    let frame = (((b - a) * SR) as usize).next_power_of_two() / 2;
    let sp = power_spectrum(signal, start, frame, frame);
    let bin = SR / frame as f64;
    10.0 * (band_power(&sp, bin, 2000.0, 20000.0) / band_power(&sp, bin, 20.0, 20000.0)).log10()
}
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let q = Quality::from_name(&args[0]).unwrap();
    let keys: Vec<u8> = args[1..].iter().filter_map(|k| k.parse().ok()).collect();
    let deltas = [0.0, 0.05, -0.05, 0.1, -0.1, 0.2, -0.2];
    let jobs: Vec<(u8, f64)> = keys
        .iter()
        .flat_map(|&k| deltas.iter().map(move |&d| (k, d)))
        .collect();
    let rows = Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    std::thread::scope(|sc| {
        for _ in 0..2 {
            sc.spawn(|| {
                while let Some(&(key, d)) = jobs.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let nominal = note_to_hz(key);
                    let settings = VoiceSettings { fundamental_hz: nominal, quality: q, thread_position_m: 0.040 + d / 1000.0, ..VoiceSettings::default() };
                    let off = as_played_offset_cents(&settings, &Pluck::default(), NOTE_VELOCITIES, SR);
                    let mut voice = TanpuraVoice::new(&settings, SR);
                    let target = nominal * (off / 1200.0f64).exp2();
                    let mut text = String::new();
                    let mut worst: f64 = 0.0;
                    let mut bright = String::new();
                    for v in VELS {
                        let sig = render(&mut voice, target, f64::from(v) / 127.0, CALIBRATION_SECONDS);
                        let c = cents(sustained_pitch_hz(&sig, SR, nominal), nominal);
                        if (40..=110).contains(&v) { worst = worst.max(c.abs()); }
                        text += &format!("{c:>7.2}");
                        if v == 40 || v == 110 { bright += &format!(" {:>6.1} {:>6.1}", high(&sig, 0.0, 0.3), high(&sig, 0.6, 1.2)); }
                    }
                    rows.lock().unwrap().push((key, (d * 1000.0) as i64, format!("{key} {d:+.2}mm off {off:>6.2} |{text} | worst {worst:>5.2} | bright{bright}")));
                }
            });
        }
    });
    let mut rows = rows.into_inner().unwrap();
    rows.sort_by_key(|r| (r.0, r.1));
    println!("vel {VELS:?}; bright: v40 0-0.3 0.6-1.2, v110 0-0.3 0.6-1.2");
    for r in rows {
        println!("{}", r.2);
    }
}
