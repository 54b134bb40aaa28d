//! PNG figures with `plotters` (bitmap backend, text by `ab_glyph`): line plots (linear or log₁₀
//! y, an optional right-hand axis, dashed series, ringed points) and heat maps for spectrograms.
//! The font is compiled in (`epaint_default_fonts`' Ubuntu Light, Ubuntu Font Licence) and the
//! pixels are encoded by the `png` crate, so nothing here needs fontconfig or system fonts.

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::error::Error;
use std::fmt;
use std::fs::File;
use std::io::BufWriter;
use std::ops::Range;
use std::path::Path;
use std::sync::Once;

/// An RGB colour.
pub type Rgb = [u8; 3];

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

impl Error for PlotError {}

/// How the y axis maps data to pixels.
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

/// Figure size, pixels.
pub const WIDTH: u32 = 1000;
pub const HEIGHT: u32 = 640;
const FONT: &str = "sans-serif";

fn rgb(colour: Rgb) -> RGBColor {
    RGBColor(colour[0], colour[1], colour[2])
}

/// Registers the compiled-in font under the family name the figures use.
fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT)
            .unwrap_or_else(|_| panic!("the compiled-in font is a valid TrueType font"));
    });
}

/// The range of the finite `values` (positive ones only for log₁₀): exact for a linear axis
/// (plotters picks the ticks), widened to whole decades for log₁₀.
fn data_range(
    values: impl Iterator<Item = f64>,
    scale: AxisScale,
) -> Result<Range<f64>, PlotError> {
    let (low, high) = values
        .filter(|value| value.is_finite() && (scale == AxisScale::Linear || *value > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(low, high), value| {
            (low.min(value), high.max(value))
        });
    if !low.is_finite() {
        return Err(PlotError("plot: no finite data to draw".into()));
    }
    Ok(match scale {
        AxisScale::Linear if high > low => low..high,
        AxisScale::Linear => low - 0.5..high + 0.5,
        AxisScale::Log10 => {
            let low_decade = low.log10().floor() as i32;
            let high_decade = (high.log10().ceil() as i32).max(low_decade + 1);
            10f64.powi(low_decade)..10f64.powi(high_decade)
        }
    })
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

/// Draws into an RGB buffer of the figure's size and writes it to `path` as an 8-bit PNG.
fn write_png(
    path: &Path,
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), Box<dyn Error>>,
) -> Result<(), PlotError> {
    register_fonts();
    let context = |error: &dyn fmt::Display| PlotError(format!("{}: {error}", path.display()));
    let mut pixels = vec![0u8; 3 * WIDTH as usize * HEIGHT as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|error| context(&error))?;
        draw(&root).map_err(|error| context(&error))?;
        root.present().map_err(|error| context(&error))?;
    }
    let file = File::create(path).map_err(|error| context(&error))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), WIDTH, HEIGHT);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|error| context(&error))?;
    writer
        .write_image_data(&pixels)
        .map_err(|error| context(&error))?;
    writer.finish().map_err(|error| context(&error))
}

/// Draws `plot` into a PNG at `path`.
pub fn line_plot(path: &Path, plot: &LinePlot) -> Result<(), PlotError> {
    let y_values = |right: bool| {
        plot.series
            .iter()
            .filter(move |series| series.right_axis == right)
            .flat_map(|series| series.points.iter().map(|point| point.1))
    };
    let x_range = data_range(
        plot.series
            .iter()
            .flat_map(|series| series.points.iter().map(|point| point.0)),
        AxisScale::Linear,
    )?;
    let y_range = data_range(y_values(false), plot.y_scale)?;
    let right_range = if plot.series.iter().any(|series| series.right_axis) {
        Some(data_range(y_values(true), AxisScale::Linear)?)
    } else {
        None
    };
    write_png(path, |root| match plot.y_scale {
        AxisScale::Linear => draw_lines(root, plot, x_range, y_range, right_range),
        AxisScale::Log10 => draw_lines(root, plot, x_range, y_range.log_scale(), right_range),
    })
}

/// The line plot on a y axis of type `Y` (linear or logarithmic).
fn draw_lines<Y>(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    plot: &LinePlot,
    x_range: Range<f64>,
    y_range: Y,
    right_range: Option<Range<f64>>,
) -> Result<(), Box<dyn Error>>
where
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64> + 'static,
{
    let log_y = plot.y_scale == AxisScale::Log10;
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, (FONT, 24))
        .margin(16)
        .x_label_area_size(60)
        .y_label_area_size(90)
        .right_y_label_area_size(if right_range.is_some() { 80 } else { 0 })
        .build_cartesian_2d(x_range.clone(), y_range)?
        .set_secondary_coord(x_range, right_range.clone().unwrap_or(0.0..1.0));
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .label_style((FONT, 18))
        .axis_desc_style((FONT, 20))
        .x_label_formatter(&|value| tick_label(*value))
        .y_label_formatter(&|value| tick_label(*value))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    if let (Some(_), Some(label)) = (&right_range, &plot.right_label) {
        chart
            .configure_secondary_axes()
            .y_desc(label)
            .label_style((FONT, 18))
            .axis_desc_style((FONT, 20))
            .y_label_formatter(&|value| tick_label(*value))
            .draw()?;
    }
    for series in &plot.series {
        let colour = rgb(series.colour);
        let style = colour.stroke_width(2);
        let drawable = |point: &&(f64, f64)| {
            point.0.is_finite()
                && point.1.is_finite()
                && (series.right_axis || !log_y || point.1 > 0.0)
        };
        // A gap in the data (a point that cannot be drawn) breaks the line.
        let runs: Vec<Vec<(f64, f64)>> = series
            .points
            .split(|point| !drawable(&point))
            .filter(|run| !run.is_empty())
            .map(<[(f64, f64)]>::to_vec)
            .collect();
        let ringed: Vec<(f64, f64)> = series.ringed.iter().filter(drawable).copied().collect();
        let mut labelled = false;
        for run in runs {
            let annotation = match (series.style, series.right_axis) {
                (SeriesStyle::Solid, false) => chart.draw_series(LineSeries::new(run, style))?,
                (SeriesStyle::Dashed, false) => {
                    chart.draw_series(DashedLineSeries::new(run, 8, 6, style))?
                }
                (SeriesStyle::Solid, true) => {
                    chart.draw_secondary_series(LineSeries::new(run, style))?
                }
                (SeriesStyle::Dashed, true) => {
                    chart.draw_secondary_series(DashedLineSeries::new(run, 8, 6, style))?
                }
            };
            if !labelled && !series.label.is_empty() {
                labelled = true;
                annotation.label(&series.label).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            }
        }
        let ring = |point: (f64, f64)| Circle::new(point, 8, colour.stroke_width(2));
        if series.right_axis {
            chart.draw_secondary_series(ringed.into_iter().map(ring))?;
        } else {
            chart.draw_series(ringed.into_iter().map(ring))?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 18))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// The heat map's colours for levels in [0, 1]: dark blue → magenta → orange → pale yellow.
fn colour_map() -> DerivedColorMap<RGBColor> {
    DerivedColorMap::new(&[
        RGBColor(0, 0, 4),
        RGBColor(59, 15, 112),
        RGBColor(140, 41, 129),
        RGBColor(241, 96, 93),
        RGBColor(252, 253, 191),
    ])
}

/// A heat map (e.g. a spectrogram): `values[row * columns + column]`, row 0 at the bottom,
/// mapped linearly from `value_range` onto a dark-to-bright colour map and clamped, with a colour
/// bar. The x and y ranges label the axes (e.g. seconds and hertz).
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
    let spans_positive =
        |range: (f64, f64)| range.1 > range.0 && range.0.is_finite() && range.1.is_finite();
    if !spans_positive(x_range) || !spans_positive(y_range) {
        return Err(PlotError(format!(
            "heatmap: axis ranges {x_range:?}, {y_range:?} must be finite and increasing"
        )));
    }
    let (title, x_label, y_label) = labels;
    let map = colour_map();
    let level = |value: f64| {
        let level = (value - value_range.0) / (value_range.1 - value_range.0);
        if level.is_finite() {
            level.clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    write_png(path, |root| {
        let root = root.titled(title, (FONT, 24))?;
        let (main, bar) = root.split_horizontally(WIDTH - 130);
        let mut chart = ChartBuilder::on(&main)
            .margin(16)
            .x_label_area_size(60)
            .y_label_area_size(90)
            .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .label_style((FONT, 18))
            .axis_desc_style((FONT, 20))
            .x_label_formatter(&|value| tick_label(*value))
            .y_label_formatter(&|value| tick_label(*value))
            .draw()?;
        let cell_width = (x_range.1 - x_range.0) / columns as f64;
        let cell_height = (y_range.1 - y_range.0) / rows as f64;
        chart.draw_series((0..rows * columns).map(|index| {
            let (row, column) = (index / columns, index % columns);
            let x = x_range.0 + column as f64 * cell_width;
            let y = y_range.0 + row as f64 * cell_height;
            let colour = map.get_color(level(values[index]));
            Rectangle::new([(x, y), (x + cell_width, y + cell_height)], colour.filled())
        }))?;

        // The colour bar: the value range, bottom to top.
        let mut scale: ChartContext<'_, _, Cartesian2d<RangedCoordf64, RangedCoordf64>> =
            ChartBuilder::on(&bar)
                .margin_top(16)
                .margin_bottom(76)
                .margin_right(16)
                .y_label_area_size(60)
                .build_cartesian_2d(0.0..1.0, value_range.0..value_range.1)?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .label_style((FONT, 18))
            .y_label_formatter(&|value| tick_label(*value))
            .draw()?;
        const STEPS: usize = 256;
        let step = (value_range.1 - value_range.0) / STEPS as f64;
        scale.draw_series((0..STEPS).map(|index| {
            let low = value_range.0 + index as f64 * step;
            let colour = map.get_color((index as f64 + 0.5) / STEPS as f64);
            Rectangle::new([(0.0, low), (1.0, low + step)], colour.filled())
        }))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Width, height and the number of distinct colours of a PNG file.
    fn decode(path: &Path) -> (u32, u32, usize) {
        let bytes = std::fs::read(path).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut pixels).unwrap();
        assert_eq!(frame.color_type, png::ColorType::Rgb);
        let colours: std::collections::BTreeSet<&[u8]> =
            pixels[..frame.buffer_size()].chunks(3).collect();
        (frame.width, frame.height, colours.len())
    }

    #[test]
    fn log_range_spans_whole_decades() {
        let range = data_range([0.7, 35.0, -1.0].into_iter(), AxisScale::Log10).unwrap();
        assert_eq!(range, 0.1..100.0);
        let range = data_range([2.0, 2.0].into_iter(), AxisScale::Linear).unwrap();
        assert_eq!(range, 1.5..2.5);
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
            series: vec![Series::new("nothing", vec![(f64::NAN, 1.0)], [0, 0, 0])],
        };
        let path = std::env::temp_dir().join("javari-plot-empty.png");
        assert!(line_plot(&path, &plot).is_err());
    }

    #[test]
    fn line_plots_are_written_as_png() {
        let directory = std::env::temp_dir();
        let mut series = Series::new("sine", Vec::new(), PALETTE[0]);
        series.points = (0..50)
            .map(|i| (i as f64, 2.0 + (i as f64 / 8.0).sin()))
            .collect();
        series.points[20].1 = f64::NAN;
        series.ringed = vec![(10.0, 2.0 + (10.0f64 / 8.0).sin())];
        let mut right = Series::new("order (right)", vec![(0.0, 1.0), (49.0, 4.0)], PALETTE[1]);
        right.style = SeriesStyle::Dashed;
        right.right_axis = true;
        for y_scale in [AxisScale::Linear, AxisScale::Log10] {
            let plot = LinePlot {
                title: "test plot".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                y_scale,
                right_label: Some("order".into()),
                series: vec![series.clone(), right.clone()],
            };
            let path = directory.join(format!("javari-plot-line-{y_scale:?}.png"));
            line_plot(&path, &plot).unwrap();
            let (width, height, colours) = decode(&path);
            assert_eq!((width, height), (WIDTH, HEIGHT));
            // White, black text and axes, both series and the anti-aliased edges between.
            assert!(colours > 10, "{colours} colours: blank?");
            std::fs::remove_file(path).unwrap();
        }
    }

    #[test]
    fn heatmaps_are_written_as_png() {
        let directory = std::env::temp_dir();
        let path = directory.join("javari-plot-heat.png");
        let values: Vec<f64> = (0..12).map(f64::from).collect();
        let heatmap_of = |path: &Path, rows| {
            heatmap(
                path,
                &values,
                rows,
                4,
                (0.0, 1.0),
                (0.0, 100.0),
                (0.0, 11.0),
                ("t", "x", "y"),
            )
        };
        heatmap_of(&path, 3).unwrap();
        let (width, height, colours) = decode(&path);
        assert_eq!((width, height), (WIDTH, HEIGHT));
        assert!(
            colours > 12,
            "{colours} colours: the 12 cells should differ"
        );
        std::fs::remove_file(path).unwrap();
        assert!(heatmap_of(&directory.join("x.png"), 5).is_err());
    }
}
