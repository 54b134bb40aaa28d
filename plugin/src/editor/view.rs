//! The live view, after the seed's Figure 3: the whole string with its displacement (vertical
//! scale exaggerated, the factor printed), a close-up of the bridge and thread drawn from their
//! own grids with the points in contact marked, the pickup-force strip, its spectrum and a
//! spectrogram with the formant centroid, so the jawari formant can be watched as it falls.

use super::spectrum::{ForceAnalysis, DYNAMIC_RANGE_DB, MAX_SHOWN_HZ, SPECTROGRAM_ROWS};
use crate::params::JavariParams;
use egui::{self, pos2, vec2, Align2, Color32, FontId, Painter, Pos2, Rect, Sense, Shape, Stroke};
use javari_core::snapshot::{BarrierView, BowedView, TanpuraSnapshot, MAX_BRIDGE_POINTS};

const STRING_COLOUR: Color32 = Color32::from_rgb(240, 220, 140);
const REST_COLOUR: Color32 = Color32::from_rgb(110, 110, 120);
const BRIDGE_COLOUR: Color32 = Color32::from_rgb(150, 110, 70);
const THREAD_COLOUR: Color32 = Color32::from_rgb(220, 220, 235);
const CONTACT_COLOUR: Color32 = Color32::from_rgb(255, 70, 60);
const FORCE_COLOUR: Color32 = Color32::from_rgb(120, 200, 255);
const GRID_COLOUR: Color32 = Color32::from_rgb(55, 55, 62);
const LABEL_FONT: f32 = 11.0;

/// Close-up window around the bridge crest, m from the tuning bead.
const CLOSE_UP_X_M: (f64, f64) = (0.030, 0.060);
/// Close-up vertical range below the crest, m (the string moves a fraction of a millimetre
/// here; the bridge falls away by millimetres and is cut off below this).
const CLOSE_UP_BELOW_CREST_M: f64 = 0.4e-3;
const CLOSE_UP_ABOVE_CREST_M: f64 = 0.25e-3;
/// Smallest half-range of the whole-string plot, m.
const MIN_STRING_RANGE_M: f64 = 0.5e-3;

/// Linear map from a physical window to a screen rectangle.
struct Axes {
    rect: Rect,
    x: (f64, f64),
    y: (f64, f64),
}

impl Axes {
    fn point(&self, x: f64, y: f64) -> Pos2 {
        let u = (x - self.x.0) / (self.x.1 - self.x.0);
        let v = (y - self.y.0) / (self.y.1 - self.y.0);
        pos2(
            self.rect.left() + u as f32 * self.rect.width(),
            self.rect.bottom() - v as f32 * self.rect.height(),
        )
    }

    /// Screen pixels per unit in y over pixels per unit in x: the vertical exaggeration when
    /// both axes are in metres.
    fn exaggeration(&self) -> f64 {
        let x_scale = f64::from(self.rect.width()) / (self.x.1 - self.x.0);
        let y_scale = f64::from(self.rect.height()) / (self.y.1 - self.y.0);
        y_scale / x_scale
    }
}

fn frame(painter: &Painter, rect: Rect, title: &str) {
    painter.rect_filled(rect, 4.0, Color32::from_rgb(24, 24, 28));
    painter.text(
        rect.left_top() + vec2(6.0, 4.0),
        Align2::LEFT_TOP,
        title,
        FontId::proportional(LABEL_FONT + 1.0),
        Color32::from_rgb(230, 190, 120),
    );
}

fn label(painter: &Painter, pos: Pos2, anchor: Align2, text: impl ToString) {
    painter.text(
        pos,
        anchor,
        text,
        FontId::proportional(LABEL_FONT),
        Color32::from_gray(170),
    );
}

/// Lays out and paints the four panes.
pub fn live_view(
    ui: &mut egui::Ui,
    snapshot: &TanpuraSnapshot,
    analysis: &mut ForceAnalysis,
    params: &JavariParams,
) {
    let size = ui.available_size();
    let (_, painter) = ui.allocate_painter(size, Sense::hover());
    let area = painter
        .clip_rect()
        .intersect(Rect::from_min_size(ui.min_rect().min, size));
    let gap = 8.0;
    let top_height = area.height() * 0.27;
    let middle_height = area.height() * 0.33;
    let bottom_height = area.height() - top_height - middle_height - 2.0 * gap;
    let string_rect = Rect::from_min_size(area.min, vec2(area.width(), top_height));
    let close_up_rect = Rect::from_min_size(
        pos2(area.left(), string_rect.bottom() + gap),
        vec2(area.width(), middle_height),
    );
    let bottom_top = close_up_rect.bottom() + gap;
    let third = (area.width() - 2.0 * gap) / 3.0;
    let force_rect = Rect::from_min_size(pos2(area.left(), bottom_top), vec2(third, bottom_height));
    let spectrum_rect = Rect::from_min_size(
        pos2(force_rect.right() + gap, bottom_top),
        vec2(third, bottom_height),
    );
    let spectrogram_rect = Rect::from_min_size(
        pos2(spectrum_rect.right() + gap, bottom_top),
        vec2(third, bottom_height),
    );

    let pluck_position_m = f64::from(params.pluck_position_mm.value()) / 1000.0;
    whole_string(&painter, string_rect, snapshot, pluck_position_m);
    if snapshot.bowed.active {
        bow_view(&painter, close_up_rect, &snapshot.bowed);
    } else {
        close_up(&painter, close_up_rect, snapshot);
    }
    force_strip(&painter, force_rect, snapshot);
    spectrum(&painter, spectrum_rect, analysis);
    spectrogram(ui, &painter, spectrogram_rect, analysis);
}

const STICK_COLOUR: Color32 = Color32::from_rgb(120, 220, 120);
const SLIP_COLOUR: Color32 = Color32::from_rgb(255, 120, 90);

/// The bowed string: the bow's place on the string (bridge left, finger right), the stick/slip
/// state now, and the bow-point velocity over the last samples, green where the string sticks to
/// the bow and red where it slips.
fn bow_view(painter: &Painter, rect: Rect, bowed: &BowedView) {
    let state = if bowed.bow_force_n <= 0.0 {
        "bow lifted"
    } else if bowed.sticking_now() {
        "sticking"
    } else {
        "slipping"
    };
    frame(
        painter,
        rect,
        &format!(
            "Bowed string: β = {:.3}, F_b = {:.3} N, v_b = {:.3} m/s, {:.1} Hz: {state}",
            bowed.bow_position, bowed.bow_force_n, bowed.bow_velocity_m_s, bowed.pitch_hz
        ),
    );
    let plot = inner(rect);
    // The string and the bow, to scale along its length.
    let string_y = plot.top() + 14.0;
    painter.line_segment(
        [pos2(plot.left(), string_y), pos2(plot.right(), string_y)],
        Stroke::new(2.0, STRING_COLOUR),
    );
    label(
        painter,
        pos2(plot.left(), string_y + 4.0),
        Align2::LEFT_TOP,
        "bridge",
    );
    label(
        painter,
        pos2(plot.right(), string_y + 4.0),
        Align2::RIGHT_TOP,
        "finger",
    );
    let bow_x = plot.left() + bowed.bow_position as f32 * plot.width();
    let bow_colour = if bowed.sticking_now() {
        STICK_COLOUR
    } else {
        SLIP_COLOUR
    };
    painter.rect_filled(
        Rect::from_center_size(pos2(bow_x, string_y), vec2(6.0, 22.0)),
        1.0,
        bow_colour,
    );
    // Bow-point velocity waveform.
    let wave = Rect::from_min_max(pos2(plot.left(), string_y + 24.0), plot.max);
    let peak = bowed
        .velocity_m_s
        .iter()
        .fold(1e-6f32, |m, v| m.max(v.abs()))
        * 1.1;
    let axes = Axes {
        rect: wave,
        x: (0.0, bowed.velocity_m_s.len() as f64),
        y: (-f64::from(peak), f64::from(peak)),
    };
    painter.line_segment(
        [
            axes.point(0.0, 0.0),
            axes.point(bowed.velocity_m_s.len() as f64, 0.0),
        ],
        Stroke::new(1.0, GRID_COLOUR),
    );
    for (i, pair) in bowed.velocity_m_s.windows(2).enumerate() {
        let colour = if bowed.sticking[i + 1] {
            STICK_COLOUR
        } else {
            SLIP_COLOUR
        };
        painter.line_segment(
            [
                axes.point(i as f64, f64::from(pair[0])),
                axes.point(i as f64 + 1.0, f64::from(pair[1])),
            ],
            Stroke::new(1.2, colour),
        );
    }
    label(
        painter,
        pos2(wave.left() - 4.0, wave.top()),
        Align2::RIGHT_TOP,
        format!("{peak:.2} m/s"),
    );
    label(
        painter,
        pos2(wave.left() - 4.0, wave.bottom()),
        Align2::RIGHT_BOTTOM,
        format!("{:.2} m/s", -peak),
    );
    label(
        painter,
        pos2(wave.right(), wave.bottom()),
        Align2::RIGHT_BOTTOM,
        "bow-point velocity, last 1024 samples (green: sticking, red: slipping)",
    );
}

fn inner(rect: Rect) -> Rect {
    Rect::from_min_max(rect.min + vec2(60.0, 20.0), rect.max - vec2(8.0, 16.0))
}

fn whole_string(painter: &Painter, rect: Rect, snapshot: &TanpuraSnapshot, pluck_m: f64) {
    frame(painter, rect, "String: displacement over its length");
    let count = snapshot.node_count;
    if count < 2 {
        label(
            painter,
            rect.center(),
            Align2::CENTER_CENTER,
            "waiting for the audio thread…",
        );
        return;
    }
    let plot = inner(rect);
    let nodes = &snapshot.displacement_m[..count];
    let rest = &snapshot.rest_displacement_m[..count];
    let extreme = nodes
        .iter()
        .chain(rest)
        .fold(MIN_STRING_RANGE_M, |m, &y| m.max(f64::from(y).abs()));
    let half = extreme * 1.15;
    let axes = Axes {
        rect: plot,
        x: (0.0, snapshot.length_m),
        y: (-half, half),
    };
    painter.line_segment(
        [axes.point(0.0, 0.0), axes.point(snapshot.length_m, 0.0)],
        Stroke::new(1.0, GRID_COLOUR),
    );
    // The close-up's window, so the eye can find it.
    painter.rect_stroke(
        Rect::from_two_pos(
            axes.point(CLOSE_UP_X_M.0, -half),
            axes.point(CLOSE_UP_X_M.1, half),
        ),
        0.0,
        Stroke::new(1.0, BRIDGE_COLOUR),
        egui::StrokeKind::Inside,
    );
    let pluck = axes.point(pluck_m, -half);
    painter.line_segment(
        [pluck, axes.point(pluck_m, half)],
        Stroke::new(1.0, Color32::from_rgb(90, 120, 90)),
    );
    label(
        painter,
        pluck + vec2(3.0, -2.0),
        Align2::LEFT_BOTTOM,
        "pluck",
    );
    let positions = &snapshot.node_positions_m[..count];
    let line = |values: &[f32]| -> Vec<Pos2> {
        positions
            .iter()
            .zip(values)
            .map(|(&x, &y)| axes.point(f64::from(x), f64::from(y)))
            .collect()
    };
    painter.line(line(rest), Stroke::new(1.0, REST_COLOUR));
    painter.line(line(nodes), Stroke::new(2.0, STRING_COLOUR));
    label(
        painter,
        plot.left_bottom() + vec2(0.0, 2.0),
        Align2::LEFT_TOP,
        "tuning bead",
    );
    label(
        painter,
        plot.right_bottom() + vec2(0.0, 2.0),
        Align2::RIGHT_TOP,
        format!("nut, {:.0} mm", snapshot.length_m * 1e3),
    );
    label(
        painter,
        pos2(plot.left() - 4.0, plot.top()),
        Align2::RIGHT_TOP,
        format!("{:+.2} mm", half * 1e3),
    );
    label(
        painter,
        pos2(plot.left() - 4.0, plot.bottom()),
        Align2::RIGHT_BOTTOM,
        format!("{:+.2} mm", -half * 1e3),
    );
    label(
        painter,
        rect.right_top() + vec2(-6.0, 4.0),
        Align2::RIGHT_TOP,
        format!(
            "vertical scale ×{:.0}   grey: rest shape   {} string(s) ringing, showing {:.1} Hz",
            axes.exaggeration(),
            snapshot.active_voices,
            snapshot.fundamental_hz
        ),
    );
}

fn close_up(painter: &Painter, rect: Rect, snapshot: &TanpuraSnapshot) {
    frame(
        painter,
        rect,
        "Bridge and thread, to scale (contact in red)",
    );
    if snapshot.node_count < 2 {
        return;
    }
    let plot = inner(rect);
    let string_top = snapshot.bridge.string_m[..snapshot.bridge.len]
        .iter()
        .chain(&snapshot.thread.string_m[..snapshot.thread.len])
        .fold(0.0f64, |m, &y| m.max(f64::from(y)));
    let axes = Axes {
        rect: plot,
        x: CLOSE_UP_X_M,
        y: (
            -CLOSE_UP_BELOW_CREST_M,
            CLOSE_UP_ABOVE_CREST_M.max(string_top * 1.1),
        ),
    };
    let clip = painter.with_clip_rect(plot);
    let bottom = axes.y.0;

    // Bridge: the body under its surface points.
    let bridge = &snapshot.bridge;
    if bridge.len > 1 {
        // One vertical strip per pair of neighbouring points, as a plain mesh (no
        // anti-aliasing seams between strips).
        let mut body = egui::Mesh::default();
        for i in 0..bridge.len {
            let x = f64::from(bridge.positions_m[i]);
            body.colored_vertex(
                axes.point(x, f64::from(bridge.heights_m[i]).max(bottom)),
                BRIDGE_COLOUR,
            );
            body.colored_vertex(axes.point(x, bottom), BRIDGE_COLOUR);
        }
        for i in 1..bridge.len as u32 {
            let (top_left, base_left, top_right, base_right) =
                (2 * i - 2, 2 * i - 1, 2 * i, 2 * i + 1);
            body.add_triangle(top_left, base_left, top_right);
            body.add_triangle(top_right, base_left, base_right);
        }
        clip.add(Shape::mesh(body));
    } else {
        label(
            painter,
            plot.center_bottom(),
            Align2::CENTER_BOTTOM,
            "no bridge contact (k_b = 0)",
        );
    }
    // Thread: its cap, drawn where it stands above the bridge surface (elsewhere it is
    // inside the bridge body and the string cannot reach it).
    let thread = &snapshot.thread;
    if thread.len > 1 {
        let above_bridge = |i: usize| {
            let x = thread.positions_m[i];
            let surface = bridge_height_at(bridge, x).unwrap_or(f32::NEG_INFINITY);
            thread.heights_m[i] >= surface
        };
        let top: Vec<Pos2> = (0..thread.len)
            .filter(|&i| above_bridge(i))
            .map(|i| {
                axes.point(
                    f64::from(thread.positions_m[i]),
                    f64::from(thread.heights_m[i]),
                )
            })
            .collect();
        let crown = (0..thread.len)
            .max_by(|&a, &b| thread.heights_m[a].total_cmp(&thread.heights_m[b]))
            .unwrap_or(0);
        clip.line(top, Stroke::new(3.0, THREAD_COLOUR));
        label(
            painter,
            axes.point(
                f64::from(thread.positions_m[crown]),
                f64::from(thread.heights_m[crown]),
            ) + vec2(0.0, 18.0),
            Align2::CENTER_TOP,
            "thread",
        );
    }
    // The string as the contact law sees it: interpolated at the barrier points, plus the
    // grid nodes in the window.
    let mut string: Vec<(f64, f64)> = Vec::new();
    for i in 0..bridge.len {
        string.push((
            f64::from(bridge.positions_m[i]),
            f64::from(bridge.string_m[i]),
        ));
    }
    for i in 0..thread.len {
        string.push((
            f64::from(thread.positions_m[i]),
            f64::from(thread.string_m[i]),
        ));
    }
    for m in 0..snapshot.node_count {
        let x = f64::from(snapshot.node_positions_m[m]);
        if (CLOSE_UP_X_M.0 - 0.005..=CLOSE_UP_X_M.1 + 0.005).contains(&x) {
            string.push((x, f64::from(snapshot.displacement_m[m])));
        }
    }
    string.sort_by(|a, b| a.0.total_cmp(&b.0));
    clip.line(
        string.iter().map(|&(x, y)| axes.point(x, y)).collect(),
        Stroke::new(2.0, STRING_COLOUR),
    );
    let mut contacts = 0;
    for (len, positions, heights, contact) in [
        (
            bridge.len,
            &bridge.positions_m[..],
            &bridge.heights_m[..],
            &bridge.in_contact[..],
        ),
        (
            thread.len,
            &thread.positions_m[..],
            &thread.heights_m[..],
            &thread.in_contact[..],
        ),
    ] {
        for i in (0..len).filter(|&i| contact[i]) {
            contacts += 1;
            clip.circle_filled(
                axes.point(f64::from(positions[i]), f64::from(heights[i])),
                3.0,
                CONTACT_COLOUR,
            );
        }
    }
    // Crest and millimetre ticks.
    for mm in (30..=60).step_by(5) {
        let p = axes.point(f64::from(mm) * 1e-3, bottom);
        painter.line_segment([p, p - vec2(0.0, 4.0)], Stroke::new(1.0, GRID_COLOUR));
        label(
            painter,
            p + vec2(0.0, 2.0),
            Align2::CENTER_TOP,
            format!("{mm} mm"),
        );
    }
    label(
        painter,
        pos2(plot.left() - 4.0, plot.top()),
        Align2::RIGHT_TOP,
        format!("{:+.0} µm", axes.y.1 * 1e6),
    );
    label(
        painter,
        pos2(plot.left() - 4.0, plot.bottom()),
        Align2::RIGHT_BOTTOM,
        format!("{:+.0} µm", axes.y.0 * 1e6),
    );
    label(
        painter,
        rect.right_top() + vec2(-6.0, 4.0),
        Align2::RIGHT_TOP,
        format!(
            "vertical scale ×{:.0}   points in contact {}   deepest penetration {:.2} µm",
            axes.exaggeration(),
            contacts,
            snapshot.max_penetration_m * 1e6
        ),
    );
}

fn force_strip(painter: &Painter, rect: Rect, snapshot: &TanpuraSnapshot) {
    let duration_ms = if snapshot.sample_rate_hz > 0.0 {
        snapshot.force_len as f64 / snapshot.sample_rate_hz * 1e3
    } else {
        0.0
    };
    frame(
        painter,
        rect,
        &format!("Pickup force, last {duration_ms:.0} ms"),
    );
    let force = snapshot.force_history_n();
    if force.len() < 2 {
        return;
    }
    let plot = inner(rect);
    let peak = force.iter().fold(1e-6f32, |m, f| m.max(f.abs())) * 1.1;
    let axes = Axes {
        rect: plot,
        x: (0.0, force.len() as f64),
        y: (-f64::from(peak), f64::from(peak)),
    };
    painter.line_segment(
        [axes.point(0.0, 0.0), axes.point(force.len() as f64, 0.0)],
        Stroke::new(1.0, GRID_COLOUR),
    );
    painter.line(
        force
            .iter()
            .enumerate()
            .map(|(i, &f)| axes.point(i as f64, f64::from(f)))
            .collect(),
        Stroke::new(1.0, FORCE_COLOUR),
    );
    label(
        painter,
        pos2(plot.left() - 4.0, plot.top()),
        Align2::RIGHT_TOP,
        format!("{peak:.3} N"),
    );
    label(
        painter,
        pos2(plot.left() - 4.0, plot.bottom()),
        Align2::RIGHT_BOTTOM,
        format!("{:.3} N", -peak),
    );
    label(
        painter,
        plot.right_bottom() + vec2(0.0, 2.0),
        Align2::RIGHT_TOP,
        "now",
    );
}

fn spectrum(painter: &Painter, rect: Rect, analysis: &ForceAnalysis) {
    frame(painter, rect, "Spectrum (Hann, 2048 samples)");
    if analysis.bin_hz <= 0.0 {
        return;
    }
    let plot = inner(rect);
    let axes = Axes {
        rect: plot,
        x: (0.0, MAX_SHOWN_HZ),
        y: (-DYNAMIC_RANGE_DB, 0.0),
    };
    for khz in (0..=8).step_by(2) {
        let p = axes.point(f64::from(khz) * 1000.0, -DYNAMIC_RANGE_DB);
        painter.line_segment(
            [p, axes.point(f64::from(khz) * 1000.0, 0.0)],
            Stroke::new(1.0, GRID_COLOUR),
        );
        label(
            painter,
            p + vec2(0.0, 2.0),
            Align2::CENTER_TOP,
            format!("{khz} kHz"),
        );
    }
    painter.line(
        analysis
            .spectrum_db()
            .map(|(f, db)| axes.point(f, db.max(-DYNAMIC_RANGE_DB)))
            .collect(),
        Stroke::new(1.0, FORCE_COLOUR),
    );
    if let Some(&centroid) = analysis.centroid_hz.last() {
        if centroid.is_finite() && centroid > 0.0 {
            let top = axes.point(centroid, 0.0);
            painter.line_segment(
                [top, axes.point(centroid, -DYNAMIC_RANGE_DB)],
                Stroke::new(1.0, CONTACT_COLOUR),
            );
            label(
                painter,
                top + vec2(3.0, 0.0),
                Align2::LEFT_TOP,
                format!("centroid {centroid:.0} Hz"),
            );
        }
    }
    label(
        painter,
        pos2(plot.left() - 4.0, plot.top()),
        Align2::RIGHT_TOP,
        "0 dB",
    );
    label(
        painter,
        pos2(plot.left() - 4.0, plot.bottom()),
        Align2::RIGHT_BOTTOM,
        format!("−{DYNAMIC_RANGE_DB:.0}"),
    );
}

fn spectrogram(ui: &egui::Ui, painter: &Painter, rect: Rect, analysis: &mut ForceAnalysis) {
    frame(painter, rect, "Spectrogram, 6 s, 0–8 kHz (red: centroid)");
    let frames = analysis.spectrogram_db.len();
    if frames == 0 {
        return;
    }
    let plot = inner(rect);
    let width = super::spectrum::SPECTROGRAM_FRAMES;
    let texture_id = egui::Id::unique("javari-spectrogram");
    let texture: Option<egui::TextureHandle> = ui.ctx().data(|data| data.get_temp(texture_id));
    let texture = match texture {
        Some(mut texture) if !analysis.changed => {
            let _ = &mut texture;
            texture
        }
        existing => {
            let mut image = egui::ColorImage::filled([width, SPECTROGRAM_ROWS], Color32::BLACK);
            let offset = width - frames;
            for (column, rows) in analysis.spectrogram_db.iter().enumerate() {
                for (row, &level) in rows.iter().enumerate() {
                    image[(offset + column, SPECTROGRAM_ROWS - 1 - row)] = heat(level);
                }
            }
            analysis.changed = false;
            let texture = match existing {
                Some(mut texture) => {
                    texture.set(image, egui::TextureOptions::LINEAR);
                    texture
                }
                None => {
                    ui.ctx()
                        .load_texture("javari-spectrogram", image, egui::TextureOptions::LINEAR)
                }
            };
            ui.ctx()
                .data_mut(|data| data.insert_temp(texture_id, texture.clone()));
            texture
        }
    };
    painter.image(
        texture.id(),
        plot,
        Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0)),
        Color32::WHITE,
    );
    let axes = Axes {
        rect: plot,
        x: (0.0, width as f64),
        y: (0.0, MAX_SHOWN_HZ),
    };
    let offset = width - frames;
    let trace: Vec<Pos2> = analysis
        .centroid_hz
        .iter()
        .enumerate()
        .filter(|(_, c)| c.is_finite() && **c > 0.0)
        .map(|(column, &c)| axes.point((offset + column) as f64 + 0.5, c))
        .collect();
    if trace.len() > 1 {
        painter.line(trace, Stroke::new(1.5, CONTACT_COLOUR));
    }
    label(
        painter,
        pos2(plot.left() - 4.0, plot.top()),
        Align2::RIGHT_TOP,
        "8 kHz",
    );
    label(
        painter,
        pos2(plot.left() - 4.0, plot.bottom()),
        Align2::RIGHT_BOTTOM,
        "0",
    );
    label(
        painter,
        plot.right_bottom() + vec2(0.0, 2.0),
        Align2::RIGHT_TOP,
        "now",
    );
}

/// The bridge surface at `x_m`, linearly between its grid points (None outside the grid).
fn bridge_height_at(bridge: &BarrierView<MAX_BRIDGE_POINTS>, x_m: f32) -> Option<f32> {
    let positions = &bridge.positions_m[..bridge.len];
    let after = positions.iter().position(|&x| x >= x_m)?;
    if after == 0 {
        return (positions[0] == x_m).then_some(bridge.heights_m[0]);
    }
    let (x0, x1) = (positions[after - 1], positions[after]);
    let (y0, y1) = (bridge.heights_m[after - 1], bridge.heights_m[after]);
    Some(y0 + (y1 - y0) * (x_m - x0) / (x1 - x0))
}

/// Black → blue → orange → white for levels 0..1.
fn heat(level: f32) -> Color32 {
    let l = level.clamp(0.0, 1.0);
    let r = (l * 2.0 - 0.6).clamp(0.0, 1.0);
    let g = (l * 1.6 - 0.7).clamp(0.0, 1.0);
    let b = if l < 0.5 {
        l * 1.6
    } else {
        (1.6 - l * 1.6).max(g)
    };
    Color32::from_rgb((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
}
