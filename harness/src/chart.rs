//! Log-log line charts drawn with plotters, written (atomically) as PNG and SVG.
//!
//! Text is drawn with a copy of DejaVu Sans kept in `assets/` (plotters' `ab_glyph` font
//! path), so a machine without system fonts draws the same chart.

use plotters::coord::Shift;
use plotters::prelude::*;
use scenes::file::image::write_png_rgb;
use scenes::file::output::write_bytes;
use std::path::{Path, PathBuf};
use std::sync::Once;
use thiserror::Error;

/// One curve: name, linear RGB colour, and (x, y) points; points with x or y not positive
/// cannot sit on log axes and are left out.
pub struct Series<'a> {
    /// Legend label.
    pub name: &'a str,
    /// Line colour.
    pub colour: [f32; 3],
    /// Points, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// Dashed, without point markers: for bounds and floors rather than measurements.
    pub dashed: bool,
}

/// Why a chart could not be written.
#[derive(Debug, Error)]
pub enum ChartError {
    /// plotters could not draw it.
    #[error("{path}: cannot draw the chart: {reason}")]
    Draw {
        /// File being drawn.
        path: String,
        /// What plotters said.
        reason: String,
    },
    /// The file could not be written.
    #[error("{path}: cannot write: {reason}")]
    Write {
        /// File.
        path: String,
        /// What the encoder or the operating system said.
        reason: String,
    },
}

/// Chart size in pixels (PNG) and user units (SVG).
pub const CHART_SIZE: (u32, u32) = (800, 520);

const FONT: &str = "sans-serif";
static DEJAVU_SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, DEJAVU_SANS)
            .unwrap_or_else(|_| panic!("the vendored DejaVu Sans is a valid font"));
    });
}

/// Draws the series on log-log axes (labelled ticks, a legend in the curves' colours, title
/// and axis labels) and writes `stem.png` and `stem.svg`.
pub fn write_loglog_chart(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), ChartError> {
    register_font();
    let png = with_extension(stem, "png");
    let svg = with_extension(stem, "svg");
    let draw_err = |path: &Path| {
        let path = path.display().to_string();
        move |reason: String| ChartError::Draw { path, reason }
    };
    let (w, h) = CHART_SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw(&root, title, x_label, y_label, series).map_err(draw_err(&png))?;
    }
    write_png_rgb(&png, &rgb, w, h).map_err(write_err(&png))?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
        draw(&root, title, x_label, y_label, series).map_err(draw_err(&svg))?;
    }
    write_bytes(&svg, text).map_err(write_err(&svg))
}

fn write_err(path: &Path) -> impl FnOnce(std::io::Error) -> ChartError {
    let path = path.display().to_string();
    move |e| ChartError::Write {
        path,
        reason: e.to_string(),
    }
}

fn with_extension(stem: &Path, ext: &str) -> PathBuf {
    let mut name = stem.as_os_str().to_owned();
    name.push(".");
    name.push(ext);
    PathBuf::from(name)
}

fn decades(values: impl Iterator<Item = f64>) -> (i32, i32) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !lo.is_finite() {
        return (0, 1);
    }
    let lo = lo.log10().floor() as i32;
    let hi = (hi.log10().ceil() as i32).max(lo + 1);
    (lo, hi)
}

/// `m x 10^d` as the nearest `f64` to the decimal, so that labels print as written.
fn decimal(m: u32, d: i32) -> f64 {
    format!("{m}e{d}").parse().expect("a decimal literal")
}

/// Labelled ticks: every decade, and 2 and 5 times each when the axis spans at most three
/// decades (so a short axis still has several labels); grid lines at 2..9 times each decade.
fn ticks((lo, hi): (i32, i32)) -> (Vec<f64>, Vec<f64>) {
    let between: &[u32] = if hi - lo <= 3 { &[1, 2, 5] } else { &[1] };
    let mut bold = Vec::new();
    let mut light = Vec::new();
    for d in lo..=hi {
        for m in 1..10 {
            let v = decimal(m, d);
            if d == hi && m > 1 {
                break;
            }
            if between.contains(&m) {
                bold.push(v);
            } else {
                light.push(v);
            }
        }
    }
    (bold, light)
}

/// A tick label: plain decimals from 0.001 to 10,000, else `2e-5`.
fn tick_label(v: f64) -> String {
    if (1e-3..=1e4).contains(&v) {
        format!("{v}")
    } else {
        let d = v.log10().floor() as i32;
        let m = (v / 10f64.powi(d)).round();
        format!("{m}e{d}")
    }
}

fn rgb(c: [f32; 3]) -> RGBColor {
    let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    RGBColor(byte(c[0]), byte(c[1]), byte(c[2]))
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let positive = |s: &Series| -> Vec<(f64, f64)> {
        s.points
            .iter()
            .copied()
            .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
            .collect()
    };
    let all: Vec<(f64, f64)> = series.iter().flat_map(positive).collect();
    let xd = decades(all.iter().map(|p| p.0));
    let yd = decades(all.iter().map(|p| p.1));
    let (x_bold, x_light) = ticks(xd);
    let (y_bold, y_light) = ticks(yd);
    let x_range = (decimal(1, xd.0)..decimal(1, xd.1))
        .log_scale()
        .with_key_points(x_bold)
        .with_light_points(x_light);
    let y_range = (decimal(1, yd.0)..decimal(1, yd.1))
        .log_scale()
        .with_key_points(y_bold)
        .with_light_points(y_light);
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 22))
        .margin(16)
        .x_label_area_size(52)
        .y_label_area_size(72)
        .build_cartesian_2d(x_range, y_range)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .axis_desc_style((FONT, 16))
        .label_style((FONT, 14))
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .bold_line_style(BLACK.mix(0.18))
        .light_line_style(BLACK.mix(0.06))
        .draw()
        .map_err(e)?;
    for s in series {
        let colour = rgb(s.colour);
        let points = positive(s);
        let line = colour.stroke_width(2);
        let legend = move |(x, y): (i32, i32)| {
            PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3))
        };
        if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(points, 8, 5, line))
                .map_err(e)?
                .label(s.name)
                .legend(legend);
        } else {
            chart
                .draw_series(LineSeries::new(points.clone(), line))
                .map_err(e)?
                .label(s.name)
                .legend(legend);
            chart
                .draw_series(points.iter().map(|p| Circle::new(*p, 3, colour.filled())))
                .map_err(e)?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK.mix(0.4))
        .label_font((FONT, 14))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_axes_get_ticks_between_decades_and_long_ones_do_not() {
        let (bold, _) = ticks((-2, 0));
        assert_eq!(bold, vec![0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0]);
        let (bold, light) = ticks((-6, 0));
        assert_eq!(bold.len(), 7);
        assert!(light.contains(&2e-3));
        assert_eq!(tick_label(0.05), "0.05");
        assert_eq!(tick_label(2e-5), "2e-5");
    }

    #[test]
    fn decades_cover_the_data_and_are_never_empty() {
        assert_eq!(decades([0.3, 0.5].into_iter()), (-1, 0));
        assert_eq!(decades([1.0].into_iter()), (0, 1));
        assert_eq!(decades(std::iter::empty()), (0, 1));
        assert_eq!(decades([0.02, 150.0].into_iter()), (-2, 3));
    }
}
