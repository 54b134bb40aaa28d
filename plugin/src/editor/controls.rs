//! The parameter panel and the top bar (presets, audition, quality indicator).
//!
//! Every parameter is a nice-plug-egui `ParamSlider`: drag to change (shift for fine steps),
//! double-click or ctrl-click to reset to the default, click the value to type one. The units
//! come from the parameters themselves (`params.rs`); the tooltips say what each does to the
//! physical string.

use super::channel::SnapshotChannel;
use crate::params::{JavariParams, PresetChoice};
use crate::FACTORY_PRESET_FILES;
use egui::{self, Color32, RichText};
use javari_core::engine::bowed_stability::{bowed_stability, BowedStability};
use javari_core::engine::pitch::note_to_hz;
use javari_core::engine::BowedStringKind;
use javari_core::snapshot::TanpuraSnapshot;
use nice_plug::prelude::{Enum, Param, ParamSetter};
use nice_plug_egui::widgets::ParamSlider;

const SLIDER_WIDTH: f32 = 130.0;
/// Real-time load above which the indicator turns amber, then red.
const LOAD_WARNING: f32 = 0.5;
const LOAD_OVERRUN: f32 = 0.9;

/// One labelled parameter row with its physical tooltip.
fn row<P: Param>(
    ui: &mut egui::Ui,
    setter: &ParamSetter,
    param: &P,
    tooltip: &str,
) -> egui::Response {
    ui.horizontal(|ui| {
        ui.add_sized([112.0, 18.0], egui::Label::new(param.name()).truncate())
            .on_hover_text(tooltip);
        ui.add(ParamSlider::for_param(param, setter).with_width(SLIDER_WIDTH))
            .on_hover_text(tooltip)
    })
    .inner
}

/// Woodhouse's stability verdict for the bow as set, at the open string, shown under the
/// bowing controls (a warning in red when the Helmholtz motion is unstable). The analysis takes
/// about 20 ms, so its result is kept in egui's memory until a bow control changes.
fn stability_line(ui: &mut egui::Ui, params: &JavariParams) {
    let bowed = params.engine_settings(&crate::factory_presets()).bowed;
    let open_string_note = match bowed.string {
        BowedStringKind::ViolinA => 69,
        BowedStringKind::CelloD => 50,
    };
    let key = (
        bowed.pressure.to_bits(),
        bowed.bow_velocity_m_s.to_bits(),
        bowed.bow_position.to_bits(),
        open_string_note,
    );
    let id = egui::Id::unique(("bow-stability", key));
    let verdict = ui
        .data_mut(|data| data.get_temp::<Option<BowedStability>>(id))
        .unwrap_or_else(|| {
            let verdict = bowed_stability(&bowed, open_string_note).ok();
            ui.data_mut(|data| data.insert_temp(id, verdict));
            verdict
        });
    let text = match verdict {
        Some(v) if v.stable => RichText::new(format!(
            "Helmholtz motion stable at the open string: bow force {:.2} N, margin {:.1}× (Woodhouse)",
            v.bow_force_n, v.margin
        ))
        .small()
        .color(Color32::from_rgb(120, 200, 120)),
        Some(v) => RichText::new(format!(
            "Warning: Helmholtz motion unstable at the open string: bow force {:.2} N above the critical {:.2} N",
            v.bow_force_n,
            v.critical_bow_force_n.unwrap_or(0.0)
        ))
        .small()
        .color(Color32::from_rgb(255, 110, 90)),
        None => RichText::new("No stability verdict for these bow settings").small(),
    };
    ui.label(text).on_hover_text(
        "Woodhouse's linear stability analysis (1993) of the Helmholtz motion for the bow force, speed and position set here: above the critical force the motion breaks into raucous or subharmonic playing.",
    );
}

fn group(ui: &mut egui::Ui, title: &str, contents: impl FnOnce(&mut egui::Ui)) {
    egui::Frame::group(ui.style()).show(ui, |ui| {
        ui.set_width(ui.available_width());
        ui.label(
            RichText::new(title)
                .strong()
                .color(Color32::from_rgb(230, 190, 120)),
        );
        contents(ui);
    });
    ui.add_space(4.0);
}

/// The parameter groups: strings and tuning, jawari, pluck, damping, bowing, quality, output.
pub fn parameter_groups(ui: &mut egui::Ui, params: &JavariParams, setter: &ParamSetter) {
    egui::ScrollArea::vertical().show(ui, |ui| {
        group(ui, "Strings and tuning", |ui| {
            ui.label(
                RichText::new("Each MIDI note plucks a string tuned to it (12-TET, A4 = 440 Hz).")
                    .small(),
            );
            row(ui, setter, &params.drone_enabled,
                "Drone mode: a held MIDI note sets Sa, and four strings (first string, Sa, Sa, low Sa) are plucked in the classic cycle.");
            row(ui, setter, &params.drone_sa_fixed,
                "On: Sa is the note below and the drone plays whenever drone mode is on, as a tanpura box does (MIDI notes leave it alone). Off: the held MIDI note sets Sa.");
            row(ui, setter, &params.drone_sa_note,
                "Sa when it is set here (C3 for a typical male voice, G3 for a female one); fine-tune it below.");
            row(ui, setter, &params.drone_first_string,
                "Tuning of the first drone string, in just intonation below Sa: Pa = 3/4 (the fifth), Ma = 2/3 (the fourth), Ni = 15/16 (major seventh), komal Ni = 8/9 (minor seventh), Dha = 5/6 (major sixth).");
            row(ui, setter, &params.drone_tempo_sync,
                "On: the drone cycle follows the host's tempo. Off: it uses the drone tempo below.");
            row(ui, setter, &params.drone_tempo_bpm,
                "Tempo of the drone cycle when not synced to the host, beats per minute.");
            row(ui, setter, &params.reference_a4_hz,
                "The pitch of A4 every note is tuned from (440 Hz; 415 to 466 Hz for other concert pitches).");
            row(ui, setter, &params.fine_tune_cents,
                "Moves every note, and so the drone's Sa, by up to a semitone: tune the drone to a voice or an instrument between two keys.");
            row(ui, setter, &params.drone_pattern,
                "How many strings: 4 (first, Sa, Sa, low Sa), 5 (first, Ni, Sa, Sa, low Sa) or 6 (first, first, Sa, Sa, low Sa, low Sa).");
            row(ui, setter, &params.drone_spacing_beats,
                "Beats between two plucks of the cycle.");
            row(ui, setter, &params.drone_pause_beats,
                "Extra beats after the last string before the cycle starts again (the classic cycle: spacing 1, pause 1).");
            row(ui, setter, &params.drone_humanize_ms,
                "Each pluck comes up to this much early or late, as a player's would (0: exactly on the beat).");
            row(ui, setter, &params.drone_humanize_percent,
                "Each pluck is up to this much softer than the full pluck.");
            row(ui, setter, &params.drone_seed,
                "The humanisation's random sequence: the same seed always plays the same way.");
            row(ui, setter, &params.tune_as_played,
                "On: each string is tuned by the pitch it sounds 0.3 to 1.5 s after a pluck, as a player tunes by ear (measured on a background thread about a second after a string's first pluck). Off: by its small-amplitude pitch only, which a firm pluck or a crest contact can move by a few cents.");
            egui::CollapsingHeader::new("Each drone string (in playing order)")
                .default_open(false)
                .show(ui, |ui| {
                    for (index, string) in params.drone_strings.iter().enumerate() {
                        ui.label(RichText::new(format!("String {}", index + 1)).strong());
                        row(ui, setter, &string.fine_tune_cents,
                            "Fine tuning of this string on top of its interval, cents.");
                        row(ui, setter, &string.level_db,
                            "Level of this string, dB: balance the strings as a player does.");
                        row(ui, setter, &string.thread_offset_mm,
                            "This string's thread, from the instrument's thread position: players set each string's jawari apart.");
                    }
                });
        });
        group(ui, "Jawari: thread and bridge", |ui| {
            row(ui, setter, &params.thread_enabled,
                "The cotton thread between string and curved bridge. It lifts the string just above the bridge crest, so the string grazes the crest on every swing: that grazing contact is the jawari buzz.");
            row(ui, setter, &params.thread_position_mm,
                "Where the thread sits, measured from the tuning bead (the bridge crest is at 46.5 mm). It sets where the speaking length starts and how much of the curved bridge the string wraps over, which moves the buzz's formant.");
            row(ui, setter, &params.bridge_stiffness_log10,
                "Contact stiffness k_b of bridge and thread (Hunt–Crossley law, force per metre of contact per metre of penetration). Harder gives a sharper collision and a brighter buzz; the seed uses 1e8 N/m².");
            row(ui, setter, &params.bridge_beyond_thread,
                "Off removes bridge contact past the thread (k_b = 0 for x > x_c): the string can no longer graze the crest, the modes decay independently and the jawari formant disappears (the seed's comparison).");
        });
        group(ui, "Pluck", |ui| {
            row(ui, setter, &params.pluck_position_mm,
                "Where the finger presses the string, from the tuning bead (the nut is at 668 mm). Closer to the bridge excites more high partials.");
            row(ui, setter, &params.pluck_width_mm,
                "Width of the fingertip that lifts the string. A wider, softer finger excites fewer high partials.");
            row(ui, setter, &params.pluck_amplitude_mm,
                "How far the finger lifts the string before letting go, at full MIDI velocity (velocity scales it). A larger swing presses harder into the bridge.");
        });
        group(ui, "Damping", |ui| {
            row(ui, setter, &params.gamma_per_s,
                "Frequency-independent loss γ (air and internal friction): every mode decays at about γ/2 per second. Lower rings longer.");
            row(ui, setter, &params.eta_ns,
                "Frequency-dependent loss η (Kelvin–Voigt on tension and stiffness): decay grows as η ω²/2, so high partials die first. Higher sounds darker.");
        });
        group(ui, "Bowing", |ui| {
            row(ui, setter, &params.instrument,
                "Tanpura: MIDI notes pluck strings. Bowed: one bowed string (McIntyre–Schumacher–Woodhouse), played legato from MIDI.");
            row(ui, setter, &params.bow_model,
                "Rounded corner: the bow sticks and slips on a friction curve, with smooth reflections at bridge and finger. Bow table: STK's cheaper reflection table.");
            row(ui, setter, &params.bowed_string,
                "The string's tension, mass and losses: a violin A string or a cello D string.");
            row(ui, setter, &params.bow_pressure_percent,
                "Bow force as a fraction of Schelleng's playable range for the current bow speed and position: too little and the string slips twice per period (surface sound), too much and it no longer releases (raucous). Channel pressure and CC 2 move it.");
            row(ui, setter, &params.bow_velocity_m_s,
                "Bow speed. Louder with faster bowing; key velocity and CC 11 move it.");
            row(ui, setter, &params.bow_position,
                "Distance of the bow from the bridge over the string length (β). Near the bridge (sul ponticello) is bright and needs more force; far (flautando) is soft. CC 74 moves it.");
            row(ui, setter, &params.glide_ms,
                "Legato: a note played while another is held glides to its pitch over this time without a new bow attack.");
            row(ui, setter, &params.vibrato_cents,
                "Vibrato depth at full modulation wheel (CC 1), at 5.5 Hz.");
            row(ui, setter, &params.body_enabled,
                "The violin body's main resonances (air mode, two body modes, bridge hill) on the bridge force.");
            stability_line(ui, params);
        });
        group(ui, "Quality", |ui| {
            row(ui, setter, &params.quality,
                "How the string is simulated. Live: the string's exact modes at the output rate with contact on a few points (fastest; for many voices on a slow machine). Fine, the default: the modes and contact points of the seed's own grid, at the output rate. Studio: the fine string stepped four times per sample, as the seed steps it (nearest the reference, about three times Fine's CPU). Reference: the seed's finite-difference scheme itself at 4x oversampling (the most CPU; watch the load meter above).");
        });
        group(ui, "Output", |ui| {
            row(ui, setter, &params.tanpura_output,
                "Radiated: the tanpura as a listener hears it, the strings' total force on the bridge through the body's resonances (fitted to the response van Walstijn, Bridges and Mehes measured on a tanpura, DAFx-16). Pickup: the raw string forces chosen below.");
            row(ui, setter, &params.nut_pickup_percent,
                "With output Pickup: 100 % is the force the string exerts on the nut (eq. 13, the seed's signal), 0 % the force on bridge and thread (eq. 12), in between a mix.");
            row(ui, setter, &params.output_gain_db,
                "Output level. At 0 dB a pickup force of 2 N is digital full scale.");
            row(ui, setter, &params.stereo_width_percent,
                "How far the strings spread from left to right (drone strings in playing order, notes by pitch). The two channels always sum to the mono sound; 0 % is mono.");
        });
        ui.label(
            RichText::new("Double-click a slider to reset it; click its value to type one.")
                .small()
                .weak(),
        );
    });
}

/// Preset browser, audition button and the quality indicator.
pub fn top_bar(
    ui: &mut egui::Ui,
    params: &JavariParams,
    setter: &ParamSetter,
    snapshot: &TanpuraSnapshot,
    channel: &SnapshotChannel,
    audition_note: &mut u8,
) {
    ui.horizontal(|ui| {
        ui.label(RichText::new("Javari").heading().strong());
        ui.separator();
        preset_browser(ui, params, setter);
        ui.separator();
        let name = note_name(*audition_note);
        ui.add(
            egui::DragValue::new(audition_note)
                .range(24..=96)
                .custom_formatter(|value, _| note_name(value as u8)),
        )
        .on_hover_text("The note the Pluck button plays (drag to change).");
        if ui
            .button("Pluck")
            .on_hover_text(format!(
                "Plucks the string tuned to {name} ({:.1} Hz) with the pluck settings, as a MIDI note would.",
                note_to_hz(*audition_note)
            ))
            .clicked()
        {
            channel.request_audition(*audition_note);
        }
        ui.separator();
        quality_indicator(ui, params, snapshot, channel);
    });
}

fn preset_browser(ui: &mut egui::Ui, params: &JavariParams, setter: &ParamSetter) {
    let names = PresetChoice::variants();
    let current = params.preset.value().to_index();
    let choose = |index: usize| {
        setter.begin_set_parameter(&params.preset);
        setter.set_parameter(&params.preset, PresetChoice::from_index(index));
        setter.end_set_parameter(&params.preset);
    };
    ui.label("Preset");
    if ui
        .small_button("<")
        .on_hover_text("Previous preset")
        .clicked()
    {
        choose((current + names.len() - 1) % names.len());
    }
    egui::ComboBox::from_id_salt("javari-preset")
        .selected_text(names[current])
        .width(130.0)
        .show_ui(ui, |ui| {
            for (index, name) in names.iter().enumerate() {
                let hover = match index.checked_sub(1).and_then(|i| FACTORY_PRESET_FILES.get(i)) {
                    Some((file, _)) => format!("Factory preset from {file}"),
                    None => "Custom: the sliders on the left play".to_string(),
                };
                if ui
                    .selectable_label(index == current, *name)
                    .on_hover_text(hover)
                    .clicked()
                {
                    choose(index);
                }
            }
        })
        .response
        .on_hover_text(
            "Factory presets (presets/*.toml); < and > step through them. Anything but Custom overrides the sound parameters; gain and drone stay yours.",
        );
    if ui.small_button(">").on_hover_text("Next preset").clicked() {
        choose((current + 1) % names.len());
    }
}

fn quality_indicator(
    ui: &mut egui::Ui,
    params: &JavariParams,
    snapshot: &TanpuraSnapshot,
    channel: &SnapshotChannel,
) {
    let load = snapshot.realtime_load;
    let load_colour = if load >= LOAD_OVERRUN {
        Color32::from_rgb(240, 80, 70)
    } else if load >= LOAD_WARNING {
        Color32::from_rgb(240, 180, 60)
    } else {
        Color32::from_rgb(110, 210, 120)
    };
    let discretisation = if snapshot.modal {
        format!(
            "The string runs in {} exact modes at the output rate, with the contact on a few points of bridge and thread",
            snapshot.grid_intervals
        )
    } else {
        format!(
            "The string runs at {}× the output rate on a grid of N = {} intervals",
            snapshot.oversample, snapshot.grid_intervals
        )
    };
    ui.label(format!("Quality: {}", params.quality))
        .on_hover_text(format!(
            "{discretisation}; Newton stops at {:.0e} m or after {} updates per step.",
            snapshot.newton_tolerance_m, snapshot.newton_cap
        ));
    ui.label(RichText::new(format!("load {:.0} %", 100.0 * load)).color(load_colour))
        .on_hover_text(
            "Real-time load measured on the audio thread: the time process() took over the block's duration (largest in the last 20 ms). Above 100 % the audio drops out.",
        );
    let caps = snapshot.cap_hits_since_last_frame;
    let cap_colour = if caps > 0 {
        Color32::from_rgb(240, 80, 70)
    } else {
        ui.visuals().text_color()
    };
    ui.label(
        RichText::new(format!(
            "Newton {:.2} it/step, cap hits {} ({} total)",
            snapshot.mean_iterations_since_last_frame, caps, snapshot.newton.cap_hits
        ))
        .color(cap_colour),
    )
    .on_hover_text(
        "Newton updates per time step in the last 20 ms, and steps that hit the iteration cap without converging (they continue with the last iterate).",
    );
    ui.label(
        RichText::new(format!(
            "frames {} / dropped {}",
            channel.published(),
            channel.dropped()
        ))
        .small()
        .weak(),
    )
    .on_hover_text(
        "Snapshots the audio thread published, and those it dropped rather than wait for a busy editor.",
    );
}

/// "D3"-style name of a MIDI note (60 = C4).
pub fn note_name(note: u8) -> String {
    const NAMES: [&str; 12] = [
        "C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B",
    ];
    let octave = i32::from(note) / 12 - 1;
    format!("{}{}", NAMES[usize::from(note) % 12], octave)
}

#[cfg(test)]
mod tests {
    use super::note_name;

    #[test]
    fn note_names_follow_c4_is_60() {
        assert_eq!(note_name(60), "C4");
        assert_eq!(note_name(69), "A4");
        assert_eq!(note_name(50), "D3");
        assert_eq!(note_name(24), "C1");
    }
}
