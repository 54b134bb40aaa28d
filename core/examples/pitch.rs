use javari_core::analysis::*;
use javari_core::excitation::Pluck;
use javari_core::tanpura::*;
fn main() {
    let sr = 44100.0;
    for (thread, f0) in [
        (true, 189.0),
        (false, 189.0),
        (true, 100.0),
        (true, 400.0),
        (true, 800.0),
    ] {
        let mut s = VoiceSettings::default();
        s.fundamental_hz = f0;
        s.thread_enabled = thread;
        let mut v = TanpuraVoice::new(&s, sr);
        v.pluck(&Pluck::default());
        let t = std::time::Instant::now();
        let out: Vec<f64> = (0..(sr as usize)).map(|_| v.next_sample() as f64).collect();
        let el = t.elapsed().as_secs_f64();
        let early = peak_frequency_hz(&out[2205..22050], sr, f0 * 0.9, f0 * 1.1);
        let late = peak_frequency_hz(&out[22050..], sr, f0 * 0.9, f0 * 1.1);
        let peak = out.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        println!("thread {thread} target {f0}: early {early:.3} ({:+.1} c) late {late:.3} ({:+.1} c) peak {peak:.3} N  rtf {:.2} newton mean {:.2}", cents(early, f0), cents(late, f0), 1.0/el, v.newton_stats().mean_iterations());
    }
}
