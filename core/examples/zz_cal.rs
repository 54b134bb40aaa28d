use javari_core::analysis::playing_range::calibrate;
use javari_core::tanpura::quality::Quality;
fn main() {
    let jobs: Vec<(Quality, u8, f64)> = [Quality::Reference, Quality::Studio, Quality::Live]
        .iter()
        .flat_map(|&q| [(q, 51u8, 0.35), (q, 54, 0.20), (q, 51, 0.20), (q, 54, 0.35)])
        .collect();
    std::thread::scope(|s| {
        let hs: Vec<_> = jobs
            .chunks(6)
            .map(|c| {
                s.spawn(move || {
                    c.iter()
                        .map(|&(q, k, p)| {
                            let c = calibrate(q, k, p, 44100.0);
                            format!(
                                "{:?} key {k} pluck {p}: offset {:.2} thread {:+.2} mm",
                                q,
                                c.offset_cents,
                                c.thread_offset_m * 1e3
                            )
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in hs {
            for l in h.join().unwrap() {
                println!("{l}");
            }
        }
    });
}
