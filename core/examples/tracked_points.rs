//! Where the fine tier's contact work lies: over one second of the bench's pluck at each key
//! given, how many of the string's contact points lie within the tracking band of contact
//! (`TRACKING_BAND_M`, the points Newton sees) and how many touch, per step, the bridge's and
//! the thread's apart: `cargo run --release -p javari-core --example tracked_points -- [TIER]
//! [KEY...]` (defaults: fine, keys 36 48 53 57 62 64; any modal tier). The figures of
//! `docs/performance.md`, stop 65.

use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::modal::{ModalString, TRACKING_BAND_M};
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::VoiceSettings;

const SAMPLE_RATE: f64 = 44_100.0;

/// Per-step counts summed over the run: [bridge, thread].
#[derive(Default)]
struct Counts {
    near: [usize; 2],
    touching: [usize; 2],
}

fn main() {
    let mut args = std::env::args().skip(1).peekable();
    let quality = match args.peek().and_then(|name| Quality::from_name(name)) {
        Some(quality) => {
            args.next();
            quality
        }
        None => Quality::Fine,
    };
    let mut keys: Vec<u8> = args.map(|s| s.parse().expect("a MIDI key")).collect();
    if keys.is_empty() {
        keys = vec![36, 48, 53, 57, 62, 64];
    }
    let steps = SAMPLE_RATE as usize;
    for key in keys {
        let settings = VoiceSettings {
            quality,
            fundamental_hz: note_to_hz(key),
            ..VoiceSettings::default()
        };
        let config = settings
            .modal_config_at(quality, SAMPLE_RATE)
            .expect("a modal tier");
        let mut string = ModalString::<f32>::new(config);
        string.pluck(&Pluck::default());
        let bridge_points = string.bridge_point_count();
        let thread_points = string.point_positions_m().len() - bridge_points;
        let mut counts = Counts::default();
        for _ in 0..steps {
            string.step();
            for (i, &gap) in string.gaps_m().iter().enumerate() {
                let side = usize::from(i >= bridge_points);
                counts.near[side] += usize::from(gap > -TRACKING_BAND_M);
                counts.touching[side] += usize::from(gap > 0.0);
            }
        }
        let per_step = |n: usize| n as f64 / steps as f64;
        println!(
            "key {key}: {bridge_points} bridge and {thread_points} thread points; per step within \
             the band: bridge {:.1}, thread {:.1}; touching: bridge {:.1}, thread {:.1}",
            per_step(counts.near[0]),
            per_step(counts.near[1]),
            per_step(counts.touching[0]),
            per_step(counts.touching[1]),
        );
    }
}
