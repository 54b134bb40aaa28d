//! PNG figures without system libraries: a small RGB rasteriser, a built-in 5×7 bitmap font, line
//! plots with axes and ticks (linear or log₁₀, an optional right-hand axis), and heat maps for
//! spectrograms. Encoding is the pure-Rust `png` crate; nothing here needs fontconfig.

use std::fmt;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

/// An RGB colour.
pub type Rgb = [u8; 3];

pub const WHITE: Rgb = [255, 255, 255];
pub const BLACK: Rgb = [0, 0, 0];
pub const GREY: Rgb = [200, 200, 200];
/// Distinguishable series colours (Okabe–Ito palette).
pub const PALETTE: [Rgb; 7] = [
    [0, 114, 178],
    [213, 94, 0],
    [0, 158, 115],
    [204, 121, 167],
    [230, 159, 0],
    [86, 180, 233],
    [120, 120, 120],
];

/// A failure to draw or write a figure; the message names the file or the bad input.
#[derive(Debug)]
pub struct PlotError(pub String);

impl fmt::Display for PlotError {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        formatter.write_str(&self.0)
    }
}

impl std::error::Error for PlotError {}

/// An RGB pixel buffer.
pub struct Canvas {
    width: usize,
    height: usize,
    pixels: Vec<u8>,
}

impl Canvas {
    /// A canvas filled with `background`.
    pub fn new(width: usize, height: usize, background: Rgb) -> Self {
        let mut pixels = Vec::with_capacity(width * height * 3);
        for _ in 0..width * height {
            pixels.extend_from_slice(&background);
        }
        Self {
            width,
            height,
            pixels,
        }
    }

    /// Sets one pixel; coordinates outside the canvas are ignored.
    pub fn set(&mut self, x: i64, y: i64, colour: Rgb) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let index = 3 * (y as usize * self.width + x as usize);
            self.pixels[index..index + 3].copy_from_slice(&colour);
        }
    }

    /// A filled rectangle, corners inclusive.
    pub fn fill_rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, colour: Rgb) {
        for y in y0.min(y1)..=y0.max(y1) {
            for x in x0.min(x1)..=x0.max(x1) {
                self.set(x, y, colour);
            }
        }
    }

    /// A line `thickness` pixels wide; `dash` = (on, off) lengths in pixels, or `None` for solid.
    pub fn line(
        &mut self,
        from: (f64, f64),
        to: (f64, f64),
        colour: Rgb,
        thickness: i64,
        dash: Option<(f64, f64)>,
    ) {
        let (dx, dy) = (to.0 - from.0, to.1 - from.1);
        let length = dx.hypot(dy);
        let steps = length.ceil().max(1.0) as usize;
        let half = thickness / 2;
        for step in 0..=steps {
            let travelled = length * step as f64 / steps as f64;
            if let Some((on, off)) = dash {
                if travelled % (on + off) > on {
                    continue;
                }
            }
            let t = step as f64 / steps as f64;
            let (x, y) = (
                (from.0 + t * dx).round() as i64,
                (from.1 + t * dy).round() as i64,
            );
            self.fill_rect(
                x - half,
                y - half,
                x - half + thickness - 1,
                y - half + thickness - 1,
                colour,
            );
        }
    }

    /// A hollow circle of radius `radius`, used to ring marked points.
    pub fn ring(&mut self, centre: (f64, f64), radius: f64, colour: Rgb) {
        let steps = (radius * 8.0).ceil() as usize;
        for step in 0..steps {
            let angle = std::f64::consts::TAU * step as f64 / steps as f64;
            self.set(
                (centre.0 + radius * angle.cos()).round() as i64,
                (centre.1 + radius * angle.sin()).round() as i64,
                colour,
            );
        }
    }

    /// Text in the built-in 5×7 font magnified by `scale`; returns the width drawn.
    pub fn text(&mut self, x: i64, y: i64, text: &str, colour: Rgb, scale: i64) -> i64 {
        let mut cursor = x;
        for character in text.chars() {
            let rows = glyph(character);
            for (row, bits) in rows.iter().enumerate() {
                for column in 0..5 {
                    if bits & (0b10000 >> column) != 0 {
                        let (px, py) = (cursor + column * scale, y + row as i64 * scale);
                        self.fill_rect(px, py, px + scale - 1, py + scale - 1, colour);
                    }
                }
            }
            cursor += 6 * scale;
        }
        cursor - x
    }

    /// Text rotated a quarter turn anticlockwise (for a y-axis label), starting at the bottom.
    pub fn text_vertical(&mut self, x: i64, y: i64, text: &str, colour: Rgb, scale: i64) {
        let mut cursor = y;
        for character in text.chars() {
            let rows = glyph(character);
            for (row, bits) in rows.iter().enumerate() {
                for column in 0..5 {
                    if bits & (0b10000 >> column) != 0 {
                        let (px, py) = (x + row as i64 * scale, cursor - column * scale);
                        self.fill_rect(px, py, px + scale - 1, py + scale - 1, colour);
                    }
                }
            }
            cursor -= 6 * scale;
        }
    }

    /// Writes the canvas as an 8-bit RGB PNG.
    pub fn save_png(&self, path: &Path) -> Result<(), PlotError> {
        let io_error = |error: &dyn fmt::Display| PlotError(format!("{}: {error}", path.display()));
        let file = File::create(path).map_err(|error| io_error(&error))?;
        let mut encoder =
            png::Encoder::new(BufWriter::new(file), self.width as u32, self.height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|error| io_error(&error))?;
        writer
            .write_image_data(&self.pixels)
            .map_err(|error| io_error(&error))?;
        writer.finish().map_err(|error| io_error(&error))
    }
}

/// Width in pixels of `text` at `scale`.
pub fn text_width(text: &str, scale: i64) -> i64 {
    6 * scale * text.chars().count() as i64
}

/// The 5×7 glyph of `character` (rows top to bottom, bit 4 = leftmost column). Lower case is
/// drawn as upper case; an unknown character is drawn as a box.
fn glyph(character: char) -> [u8; 7] {
    match character.to_ascii_uppercase() {
        ' ' => [0; 7],
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        '.' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C],
        ',' => [0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08],
        '-' => [0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00],
        '+' => [0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00],
        '=' => [0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00],
        ':' => [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00],
        ';' => [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x04, 0x08],
        '\'' => [0x04, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00],
        '/' => [0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '[' => [0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E],
        ']' => [0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E],
        '_' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '*' => [0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00],
        '<' => [0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02],
        '>' => [0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08],
        '|' => [0x04; 7],
        '^' => [0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00],
        _ => [0x1F, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1F],
    }
}

/// How an axis maps data to pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AxisScale {
    Linear,
    /// log₁₀; non-positive values are not drawn.
    Log10,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SeriesStyle {
    Solid,
    Dashed,
    /// Small filled squares at the points, no line.
    #[allow(dead_code)] // Part of the shared plotting API; the stability sweeps draw lines.
    Points,
}

/// One data series.
#[derive(Debug, Clone)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub colour: Rgb,
    pub style: SeriesStyle,
    /// Plot against the right-hand axis instead of the left one.
    pub right_axis: bool,
    /// Points to ring with a circle (e.g. the Helmholtz cases of Fig. 10).
    pub ringed: Vec<(f64, f64)>,
}

impl Series {
    /// A solid series on the left axis, nothing ringed.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, colour: Rgb) -> Self {
        Self {
            label: label.into(),
            points,
            colour,
            style: SeriesStyle::Solid,
            right_axis: false,
            ringed: Vec::new(),
        }
    }
}

/// A line plot.
#[derive(Debug, Clone)]
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub y_scale: AxisScale,
    /// Label of the right-hand (linear) axis, when a series uses it.
    pub right_label: Option<String>,
    pub series: Vec<Series>,
}

/// Figure geometry.
const WIDTH: usize = 1000;
const HEIGHT: usize = 640;
const LEFT: i64 = 110;
const RIGHT_MARGIN: i64 = 110;
const TOP: i64 = 60;
const BOTTOM: i64 = 90;
const FONT: i64 = 2;

/// An axis range and its ticks.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    pub scale: AxisScale,
    pub min: f64,
    pub max: f64,
    pub ticks: Vec<f64>,
}

impl Axis {
    /// A range covering `values` with "nice" ticks (1, 2, 5 × 10ⁿ, or decades for log₁₀).
    pub fn fit(values: impl Iterator<Item = f64>, scale: AxisScale) -> Result<Self, PlotError> {
        let usable: Vec<f64> = values
            .filter(|value| value.is_finite() && (scale == AxisScale::Linear || *value > 0.0))
            .collect();
        let (low, high) = usable
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(low, high), &value| {
                (low.min(value), high.max(value))
            });
        if !low.is_finite() {
            return Err(PlotError("plot: no finite data to draw".into()));
        }
        Ok(match scale {
            AxisScale::Linear => {
                let (low, high) = if high > low {
                    (low, high)
                } else {
                    (low - 0.5, high + 0.5)
                };
                let step = nice_step((high - low) / 6.0);
                let min = (low / step).floor() * step;
                let max = (high / step).ceil() * step;
                let count = ((max - min) / step).round() as usize;
                let ticks = (0..=count).map(|index| min + step * index as f64).collect();
                Self {
                    scale,
                    min,
                    max,
                    ticks,
                }
            }
            AxisScale::Log10 => {
                let min_decade = low.log10().floor() as i32;
                let max_decade = (high.log10().ceil() as i32).max(min_decade + 1);
                let ticks = (min_decade..=max_decade)
                    .map(|decade| 10f64.powi(decade))
                    .collect();
                Self {
                    scale,
                    min: 10f64.powi(min_decade),
                    max: 10f64.powi(max_decade),
                    ticks,
                }
            }
        })
    }

    /// Position of `value` in [0, 1] along the axis (outside for values beyond the range).
    pub fn fraction(&self, value: f64) -> f64 {
        match self.scale {
            AxisScale::Linear => (value - self.min) / (self.max - self.min),
            AxisScale::Log10 => {
                (value.log10() - self.min.log10()) / (self.max.log10() - self.min.log10())
            }
        }
    }
}

fn nice_step(rough: f64) -> f64 {
    let magnitude = 10f64.powf(rough.log10().floor());
    let mantissa = rough / magnitude;
    let nice = if mantissa <= 1.0 {
        1.0
    } else if mantissa <= 2.0 {
        2.0
    } else if mantissa <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * magnitude
}

/// Tick label: short, no trailing zeros.
pub fn tick_label(value: f64) -> String {
    if value == 0.0 {
        return "0".into();
    }
    let magnitude = value.abs().log10();
    if !(-3.0..5.0).contains(&magnitude) {
        return format!("1e{}", magnitude.round() as i32);
    }
    let text = format!("{value:.4}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Draws `plot` into a PNG at `path`.
pub fn line_plot(path: &Path, plot: &LinePlot) -> Result<(), PlotError> {
    let left_series = plot.series.iter().filter(|series| !series.right_axis);
    let y_axis = Axis::fit(
        left_series.flat_map(|series| series.points.iter().map(|point| point.1)),
        plot.y_scale,
    )?;
    let x_axis = Axis::fit(
        plot.series
            .iter()
            .flat_map(|series| series.points.iter().map(|point| point.0)),
        AxisScale::Linear,
    )?;
    let right_axis = if plot.series.iter().any(|series| series.right_axis) {
        Some(Axis::fit(
            plot.series
                .iter()
                .filter(|series| series.right_axis)
                .flat_map(|series| series.points.iter().map(|point| point.1)),
            AxisScale::Linear,
        )?)
    } else {
        None
    };

    let mut canvas = Canvas::new(WIDTH, HEIGHT, WHITE);
    let (x0, x1) = (LEFT, WIDTH as i64 - RIGHT_MARGIN);
    let (y0, y1) = (HEIGHT as i64 - BOTTOM, TOP);
    let to_pixel = |axis_x: &Axis, axis_y: &Axis, point: (f64, f64)| {
        (
            x0 as f64 + axis_x.fraction(point.0) * (x1 - x0) as f64,
            y0 as f64 + axis_y.fraction(point.1) * (y1 - y0) as f64,
        )
    };

    // Grid and ticks.
    for &tick in &x_axis.ticks {
        let x = to_pixel(&x_axis, &y_axis, (tick, y_axis.min)).0;
        canvas.line((x, y0 as f64), (x, y1 as f64), GREY, 1, None);
        let label = tick_label(tick);
        canvas.text(
            x.round() as i64 - text_width(&label, FONT) / 2,
            y0 + 10,
            &label,
            BLACK,
            FONT,
        );
    }
    for &tick in &y_axis.ticks {
        let y = to_pixel(&x_axis, &y_axis, (x_axis.min, tick)).1;
        canvas.line((x0 as f64, y), (x1 as f64, y), GREY, 1, None);
        let label = tick_label(tick);
        canvas.text(
            x0 - 8 - text_width(&label, FONT),
            y.round() as i64 - 7,
            &label,
            BLACK,
            FONT,
        );
    }
    if let Some(axis) = &right_axis {
        for &tick in &axis.ticks {
            let y = to_pixel(&x_axis, axis, (x_axis.min, tick)).1;
            canvas.line((x1 as f64, y), (x1 as f64 + 6.0, y), BLACK, 1, None);
            canvas.text(
                x1 + 10,
                y.round() as i64 - 7,
                &tick_label(tick),
                BLACK,
                FONT,
            );
        }
    }
    // Frame.
    for (from, to) in [
        ((x0, y0), (x1, y0)),
        ((x1, y0), (x1, y1)),
        ((x1, y1), (x0, y1)),
        ((x0, y1), (x0, y0)),
    ] {
        canvas.line(
            (from.0 as f64, from.1 as f64),
            (to.0 as f64, to.1 as f64),
            BLACK,
            2,
            None,
        );
    }
    // Labels.
    canvas.text(
        (WIDTH as i64 - text_width(&plot.title, FONT)) / 2,
        18,
        &plot.title,
        BLACK,
        FONT,
    );
    canvas.text(
        (x0 + x1 - text_width(&plot.x_label, FONT)) / 2,
        y0 + 40,
        &plot.x_label,
        BLACK,
        FONT,
    );
    canvas.text_vertical(
        14,
        (y0 + y1 + text_width(&plot.y_label, FONT)) / 2,
        &plot.y_label,
        BLACK,
        FONT,
    );
    if let Some(label) = &plot.right_label {
        canvas.text_vertical(
            WIDTH as i64 - 30,
            (y0 + y1 + text_width(label, FONT)) / 2,
            label,
            BLACK,
            FONT,
        );
    }

    // Data, clipped to the frame.
    let inside = |(x, y): (f64, f64)| {
        x >= x0 as f64 - 0.5 && x <= x1 as f64 + 0.5 && y <= y0 as f64 + 0.5 && y >= y1 as f64 - 0.5
    };
    for series in &plot.series {
        let axis_y = if series.right_axis {
            right_axis.as_ref().unwrap_or(&y_axis)
        } else {
            &y_axis
        };
        let drawable = |point: &(f64, f64)| {
            point.0.is_finite()
                && point.1.is_finite()
                && (axis_y.scale == AxisScale::Linear || point.1 > 0.0)
        };
        let pixels: Vec<Option<(f64, f64)>> = series
            .points
            .iter()
            .map(|point| drawable(point).then(|| to_pixel(&x_axis, axis_y, *point)))
            .collect();
        match series.style {
            SeriesStyle::Points => {
                for pixel in pixels.iter().flatten().filter(|pixel| inside(**pixel)) {
                    let (x, y) = (pixel.0.round() as i64, pixel.1.round() as i64);
                    canvas.fill_rect(x - 2, y - 2, x + 2, y + 2, series.colour);
                }
            }
            SeriesStyle::Solid | SeriesStyle::Dashed => {
                let dash = (series.style == SeriesStyle::Dashed).then_some((8.0, 6.0));
                for pair in pixels.windows(2) {
                    if let [Some(from), Some(to)] = pair {
                        if inside(*from) && inside(*to) {
                            canvas.line(*from, *to, series.colour, 2, dash);
                        }
                    }
                }
            }
        }
        for point in series.ringed.iter().filter(|point| drawable(point)) {
            let pixel = to_pixel(&x_axis, axis_y, *point);
            if inside(pixel) {
                canvas.ring(pixel, 7.0, series.colour);
                canvas.ring(pixel, 8.0, series.colour);
            }
        }
    }
    // Legend, top right inside the frame.
    let mut legend_y = y1 + 10;
    for series in plot.series.iter().filter(|series| !series.label.is_empty()) {
        let width = text_width(&series.label, FONT);
        let x = x1 - 20 - width - 40;
        match series.style {
            SeriesStyle::Points => {
                canvas.fill_rect(x + 13, legend_y + 4, x + 19, legend_y + 10, series.colour)
            }
            SeriesStyle::Solid | SeriesStyle::Dashed => canvas.line(
                (x as f64, legend_y as f64 + 7.0),
                (x as f64 + 32.0, legend_y as f64 + 7.0),
                series.colour,
                2,
                (series.style == SeriesStyle::Dashed).then_some((8.0, 6.0)),
            ),
        }
        canvas.text(x + 40, legend_y, &series.label, BLACK, FONT);
        legend_y += 20;
    }
    canvas.save_png(path)
}

/// A heat map (e.g. a spectrogram): `values[row * columns + column]`, row 0 at the bottom,
/// mapped linearly from `value_range` onto a dark-to-bright colour ramp and clamped. The x and y
/// ranges label the axes (e.g. seconds and hertz).
#[allow(clippy::too_many_arguments)]
pub fn heatmap(
    path: &Path,
    values: &[f64],
    rows: usize,
    columns: usize,
    x_range: (f64, f64),
    y_range: (f64, f64),
    value_range: (f64, f64),
    labels: (&str, &str, &str),
) -> Result<(), PlotError> {
    if rows == 0 || columns == 0 || values.len() != rows * columns {
        return Err(PlotError(format!(
            "heatmap: {} values do not fill {rows} rows x {columns} columns",
            values.len()
        )));
    }
    if value_range.1.partial_cmp(&value_range.0) != Some(std::cmp::Ordering::Greater) {
        return Err(PlotError(format!(
            "heatmap: value range {value_range:?} must be increasing"
        )));
    }
    let (title, x_label, y_label) = labels;
    let mut canvas = Canvas::new(WIDTH, HEIGHT, WHITE);
    let (x0, x1) = (LEFT, WIDTH as i64 - RIGHT_MARGIN);
    let (y0, y1) = (HEIGHT as i64 - BOTTOM, TOP);
    for py in y1..=y0 {
        let row_fraction = (y0 - py) as f64 / (y0 - y1 + 1) as f64;
        let row = ((row_fraction * rows as f64) as usize).min(rows - 1);
        for px in x0..=x1 {
            let column_fraction = (px - x0) as f64 / (x1 - x0 + 1) as f64;
            let column = ((column_fraction * columns as f64) as usize).min(columns - 1);
            let value = values[row * columns + column];
            let level = ((value - value_range.0) / (value_range.1 - value_range.0)).clamp(0.0, 1.0);
            canvas.set(
                px,
                py,
                colour_ramp(if value.is_finite() { level } else { 0.0 }),
            );
        }
    }
    let x_axis = Axis::fit([x_range.0, x_range.1].into_iter(), AxisScale::Linear)?;
    let y_axis = Axis::fit([y_range.0, y_range.1].into_iter(), AxisScale::Linear)?;
    let span = |range: (f64, f64), value: f64| (value - range.0) / (range.1 - range.0);
    for &tick in x_axis
        .ticks
        .iter()
        .filter(|tick| (x_range.0..=x_range.1).contains(*tick))
    {
        let x = x0 as f64 + span(x_range, tick) * (x1 - x0) as f64;
        canvas.line((x, y0 as f64), (x, y0 as f64 + 6.0), BLACK, 1, None);
        let label = tick_label(tick);
        canvas.text(
            x.round() as i64 - text_width(&label, FONT) / 2,
            y0 + 10,
            &label,
            BLACK,
            FONT,
        );
    }
    for &tick in y_axis
        .ticks
        .iter()
        .filter(|tick| (y_range.0..=y_range.1).contains(*tick))
    {
        let y = y0 as f64 + span(y_range, tick) * (y1 - y0) as f64;
        canvas.line((x0 as f64 - 6.0, y), (x0 as f64, y), BLACK, 1, None);
        let label = tick_label(tick);
        canvas.text(
            x0 - 10 - text_width(&label, FONT),
            y.round() as i64 - 7,
            &label,
            BLACK,
            FONT,
        );
    }
    // Colour bar on the right.
    for py in y1..=y0 {
        let level = (y0 - py) as f64 / (y0 - y1) as f64;
        canvas.fill_rect(x1 + 20, py, x1 + 40, py, colour_ramp(level));
    }
    canvas.text(x1 + 44, y1, &tick_label(value_range.1), BLACK, FONT);
    canvas.text(x1 + 44, y0 - 14, &tick_label(value_range.0), BLACK, FONT);
    canvas.text(
        (WIDTH as i64 - text_width(title, FONT)) / 2,
        18,
        title,
        BLACK,
        FONT,
    );
    canvas.text(
        (x0 + x1 - text_width(x_label, FONT)) / 2,
        y0 + 40,
        x_label,
        BLACK,
        FONT,
    );
    canvas.text_vertical(
        14,
        (y0 + y1 + text_width(y_label, FONT)) / 2,
        y_label,
        BLACK,
        FONT,
    );
    canvas.save_png(path)
}

/// Dark blue → magenta → orange → pale yellow, for levels in [0, 1].
#[allow(dead_code)] // Used by `heatmap`.
pub fn colour_ramp(level: f64) -> Rgb {
    const STOPS: [(f64, Rgb); 5] = [
        (0.0, [0, 0, 4]),
        (0.25, [59, 15, 112]),
        (0.5, [140, 41, 129]),
        (0.75, [241, 96, 93]),
        (1.0, [252, 253, 191]),
    ];
    let level = level.clamp(0.0, 1.0);
    for pair in STOPS.windows(2) {
        let ((low, from), (high, to)) = (pair[0], pair[1]);
        if level <= high {
            let t = (level - low) / (high - low);
            let mix = |a: u8, b: u8| (a as f64 + t * (b as f64 - a as f64)).round() as u8;
            return [
                mix(from[0], to[0]),
                mix(from[1], to[1]),
                mix(from[2], to[2]),
            ];
        }
    }
    STOPS[STOPS.len() - 1].1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_axis_has_nice_ticks_covering_the_data() {
        let axis = Axis::fit([0.13, 0.94].into_iter(), AxisScale::Linear).unwrap();
        assert!(axis.min <= 0.13 && axis.max >= 0.94);
        assert_eq!(axis.ticks.first().copied(), Some(axis.min));
        let step = axis.ticks[1] - axis.ticks[0];
        assert!(
            (step - 0.2).abs() < 1e-12 || (step - 0.1).abs() < 1e-12,
            "{step}"
        );
    }

    #[test]
    fn log_axis_spans_whole_decades() {
        let axis = Axis::fit([0.7, 35.0, -1.0].into_iter(), AxisScale::Log10).unwrap();
        assert_eq!((axis.min, axis.max), (0.1, 100.0));
        assert_eq!(axis.ticks.len(), 4);
        assert!((axis.fraction(1.0) - 1.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(20.0), "20");
        assert_eq!(tick_label(1e-5), "1e-5");
    }

    #[test]
    fn empty_plot_is_an_error() {
        let plot = LinePlot {
            title: "empty".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            y_scale: AxisScale::Linear,
            right_label: None,
            series: vec![Series::new("nothing", vec![(f64::NAN, 1.0)], BLACK)],
        };
        let path = std::env::temp_dir().join("javari-plot-empty.png");
        assert!(line_plot(&path, &plot).is_err());
    }

    #[test]
    fn plots_and_heatmaps_are_written_as_png() {
        let directory = std::env::temp_dir();
        let mut series = Series::new("sine", Vec::new(), PALETTE[0]);
        series.points = (0..50)
            .map(|i| (i as f64, (i as f64 / 8.0).sin()))
            .collect();
        series.ringed = vec![(10.0, (10.0f64 / 8.0).sin())];
        let plot = LinePlot {
            title: "test plot".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            y_scale: AxisScale::Linear,
            right_label: None,
            series: vec![series],
        };
        let line_path = directory.join("javari-plot-line.png");
        line_plot(&line_path, &plot).unwrap();
        let heat_path = directory.join("javari-plot-heat.png");
        let values: Vec<f64> = (0..12).map(f64::from).collect();
        heatmap(
            &heat_path,
            &values,
            3,
            4,
            (0.0, 1.0),
            (0.0, 100.0),
            (0.0, 11.0),
            ("t", "x", "y"),
        )
        .unwrap();
        for path in [line_path, heat_path] {
            let bytes = std::fs::read(&path).unwrap();
            assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
            let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
            let reader = decoder.read_info().unwrap();
            assert_eq!(reader.info().width as usize, WIDTH);
            std::fs::remove_file(path).unwrap();
        }
        assert!(heatmap(
            &directory.join("x.png"),
            &values,
            5,
            4,
            (0.0, 1.0),
            (0.0, 1.0),
            (0.0, 1.0),
            ("", "", "")
        )
        .is_err());
    }
}
