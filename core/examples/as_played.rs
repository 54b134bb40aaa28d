//! The sustained pitch as played (0.3–1.5 s after the pluck) against each key's target, for one
//! tier, with the linearised tuning alone and with the as-played calibration
//! (`tanpura/as_played.rs`): `cargo run --release -p javari-core --example as_played -- TIER KEY…`
//! (TIER: live, fine, studio or reference; keys default to 36–64; an argument such as `41mm`
//! moves the thread from its 40 mm, one such as `pluck=0.20` plucks at 0.20 m from the bead
//! instead of the default 0.35 m). One row per key: the calibration's offset (cents) and thread
//! move (mm), then one column per MIDI velocity, cents from the key's pitch, with the linearised
//! tuning and as played; each block's last column is the largest deviation at velocities 40–110.

use javari_core::analysis::cents;
use javari_core::engine::pitch::note_to_hz;
use javari_core::tanpura::as_played::{
    sustained_pitch_of_pluck_hz, Calibration, CalibrationRequest, NOTE_VELOCITIES,
};
use javari_core::tanpura::excitation::Pluck;
use javari_core::tanpura::quality::Quality;
use javari_core::tanpura::{TanpuraVoice, VoiceSettings};
use rayon::prelude::*;

const SAMPLE_RATE: f64 = 44_100.0;
const VELOCITIES: [u8; 6] = [1, 40, 60, 80, 110, 127];

fn row(voice: &mut TanpuraVoice, pluck: &Pluck, key: u8, offset_cents: f64) -> (String, f64) {
    let nominal = note_to_hz(key);
    let mut text = String::new();
    let mut worst: f64 = 0.0;
    for velocity in VELOCITIES {
        let heard = sustained_pitch_of_pluck_hz(
            voice,
            nominal * (offset_cents / 1200.0).exp2(),
            nominal,
            pluck,
            f64::from(velocity) / 127.0,
            SAMPLE_RATE,
        );
        let off = cents(heard, nominal);
        if (40..=110).contains(&velocity) {
            worst = worst.max(off.abs());
        }
        text += &format!("{off:>8.2}");
    }
    (text, worst)
}

fn main() {
    let arguments: Vec<String> = std::env::args().skip(1).collect();
    let quality = arguments
        .first()
        .and_then(|name| Quality::from_name(name))
        .unwrap_or(Quality::Live);
    let mut keys: Vec<u8> = arguments
        .iter()
        .skip(1)
        .filter_map(|key| key.parse().ok())
        .collect();
    let thread_position_m = arguments
        .iter()
        .find_map(|argument| argument.strip_suffix("mm")?.parse::<f64>().ok())
        .map_or(VoiceSettings::default().thread_position_m, |mm| mm / 1000.0);
    let pluck = Pluck {
        position_m: arguments
            .iter()
            .find_map(|argument| argument.strip_prefix("pluck=")?.parse::<f64>().ok())
            .unwrap_or(Pluck::default().position_m),
        ..Pluck::default()
    }
    .clamped();
    let pluck = &pluck;
    if keys.is_empty() {
        keys = (36..=64).collect();
    }
    // One job per key on all cores (rayon); the rows come back in the keys' order.
    let rows: Vec<_> = keys
        .par_iter()
        .map(|&key| {
            let settings = VoiceSettings {
                fundamental_hz: note_to_hz(key),
                quality,
                thread_position_m,
                ..VoiceSettings::default()
            };
            // As the engine measures it: the studio with the reference's jawari.
            let as_played = Calibration::measure(
                &CalibrationRequest {
                    settings,
                    pluck: *pluck,
                    velocities: NOTE_VELOCITIES,
                },
                SAMPLE_RATE,
            );
            let mut voice = TanpuraVoice::new(&settings, SAMPLE_RATE);
            let linearised = row(&mut voice, pluck, key, 0.0);
            voice.set_settings(&VoiceSettings {
                thread_position_m: settings.thread_position_m + as_played.thread_offset_m,
                ..settings
            });
            let played = row(&mut voice, pluck, key, as_played.offset_cents);
            (
                key,
                as_played.offset_cents,
                as_played.thread_offset_m,
                linearised,
                played,
            )
        })
        .collect();
    println!(
        "{} tier, thread at {:.1} mm, plucked at {:.2} m, cents from the key's pitch at MIDI \
         velocities {VELOCITIES:?}",
        quality.name(),
        thread_position_m * 1000.0,
        pluck.position_m
    );
    println!("key  offset thread | linearised tuning                                | worst | as played                                        | worst");
    let (mut worst_linearised, mut worst_played): (f64, f64) = (0.0, 0.0);
    for (key, offset, thread_m, linearised, played) in rows {
        println!(
            "{key:>3} {offset:>7.2} {:>+6.2} |{}| {:>5.2} |{}| {:>5.2}",
            thread_m * 1000.0,
            linearised.0,
            linearised.1,
            played.0,
            played.1
        );
        worst_linearised = worst_linearised.max(linearised.1);
        worst_played = worst_played.max(played.1);
    }
    println!(
        "largest deviation at velocities 40-110: linearised {worst_linearised:.2} cents, as played {worst_played:.2} cents"
    );
}
