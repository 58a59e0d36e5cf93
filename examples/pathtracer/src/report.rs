//! Everything a run writes for people and tools: plots, CSV, JSON, image strips, markdown.

use std::error::Error;
use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

use crate::render::Image;

/// What the path tracer's fallible functions return: any error, sendable across threads.
pub type Result<T> = std::result::Result<T, Box<dyn Error + Send + Sync>>;

/// One line of a plot.
pub struct Series {
    /// The legend entry.
    pub name: String,
    /// The (x, y) points.
    pub points: Vec<(f64, f64)>,
    /// Draw markers instead of a line (for scattered measurements).
    pub markers: bool,
}

impl Series {
    /// A line through the points.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            markers: false,
        }
    }

    /// A marker at each point.
    pub fn markers(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            markers: true,
        }
    }
}

/// Axis scales of a plot.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Evenly spaced values.
    Linear,
    /// Evenly spaced decades.
    Log,
}

/// Axes and labels of a plot.
pub struct Axes<'a> {
    /// Above the plot.
    pub title: &'a str,
    /// Under the x axis.
    pub x_label: &'a str,
    /// Beside the y axis.
    pub y_label: &'a str,
    /// The x axis's scale.
    pub x_scale: Scale,
    /// The y axis's scale.
    pub y_scale: Scale,
}

impl<'a> Axes<'a> {
    /// Linear x, logarithmic y: the usual plot of an error against iterations or a setting.
    pub fn log_y(title: &'a str, x_label: &'a str, y_label: &'a str) -> Self {
        Axes {
            title,
            x_label,
            y_label,
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
        }
    }

    /// Both axes logarithmic.
    pub fn log_log(title: &'a str, x_label: &'a str, y_label: &'a str) -> Self {
        Axes {
            x_scale: Scale::Log,
            ..Axes::log_y(title, x_label, y_label)
        }
    }
}

/// The system font plots are labelled with (Debian's fonts-dejavu-core, on every machine of
/// this project's kind). Plotters' pure-Rust text path needs the font's bytes for the
/// program's lifetime, hence the leak, done once.
fn register_font() -> Result<()> {
    static OUTCOME: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    OUTCOME
        .get_or_init(|| {
            const CANDIDATES: [&str; 2] = [
                "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                "/usr/share/fonts/dejavu/DejaVuSans.ttf",
            ];
            match CANDIDATES.iter().find_map(|p| fs::read(p).ok()) {
                Some(bytes) => plotters::style::register_font(
                    "sans-serif",
                    FontStyle::Normal,
                    Box::leak(bytes.into_boxed_slice()),
                )
                .map_err(|_| "the DejaVu Sans font could not be parsed".to_string()),
                None => Err(
                    "plots need the DejaVu Sans font: apt-get install fonts-dejavu-core"
                        .to_string(),
                ),
            }
        })
        .clone()
        .map_err(Into::into)
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// A PNG plot of several series, framed, with a legend; on a log axis, non-positive values
/// are dropped (they cannot be drawn) rather than clamped.
///
/// # Errors
/// An axis without a label (every plot says what its axes count), a missing font, a file
/// that cannot be written.
pub fn plot(path: &Path, axes: &Axes<'_>, series: &[Series]) -> Result<()> {
    if axes.x_label.trim().is_empty() || axes.y_label.trim().is_empty() {
        return Err(format!("plot {}: both axes need a label", path.display()).into());
    }
    register_font()?;
    let keep = |v: f64, scale: Scale| v.is_finite() && (scale == Scale::Linear || v > 0.0);
    let points: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .copied()
                .filter(|&(x, y)| keep(x, axes.x_scale) && keep(y, axes.y_scale))
                .collect()
        })
        .collect();
    let all = points.iter().flatten();
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 1e-3, 1.0);
    }
    let pad = |lo: f64, hi: f64, scale: Scale| match scale {
        Scale::Log => (lo / 1.5, hi * 1.5),
        Scale::Linear if hi > lo => (lo - 0.03 * (hi - lo), hi + 0.03 * (hi - lo)),
        Scale::Linear => (lo - 0.5, hi + 0.5),
    };
    let (x0, x1) = pad(x0, x1, axes.x_scale);
    let (y0, y1) = pad(y0, y1, axes.y_scale);
    match (axes.x_scale, axes.y_scale) {
        (Scale::Linear, Scale::Linear) => draw(path, axes, series, &points, x0..x1, y0..y1),
        (Scale::Linear, Scale::Log) => {
            draw(path, axes, series, &points, x0..x1, (y0..y1).log_scale())
        }
        (Scale::Log, Scale::Linear) => {
            draw(path, axes, series, &points, (x0..x1).log_scale(), y0..y1)
        }
        (Scale::Log, Scale::Log) => draw(
            path,
            axes,
            series,
            &points,
            (x0..x1).log_scale(),
            (y0..y1).log_scale(),
        ),
    }
}

fn draw<X, Y>(
    path: &Path,
    axes: &Axes<'_>,
    series: &[Series],
    points: &[Vec<(f64, f64)>],
    x: X,
    y: Y,
) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(axes.title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(84)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(axes.x_label)
        .y_desc(axes.y_label)
        .label_style(("sans-serif", 15))
        .x_label_formatter(&|v| short_number(*v))
        .y_label_formatter(&|v| short_number(*v))
        .draw()?;
    // The frame: the mesh draws the left and bottom axes only.
    let (px, py) = chart.plotting_area().get_pixel_range();
    root.draw(&Rectangle::new(
        [(px.start, py.start), (px.end - 1, py.end - 1)],
        BLACK.stroke_width(1),
    ))?;
    for (i, (s, pts)) in series.iter().zip(points).enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let style = ShapeStyle::from(&color).stroke_width(2);
        let legend = move |(x, y): (i32, i32)| PathElement::new(vec![(x, y), (x + 22, y)], style);
        if s.markers {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, style.filled())))?
                .label(s.name.as_str())
                .legend(legend);
        } else {
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), style))?
                .label(s.name.as_str())
                .legend(legend);
        }
    }
    if series.iter().any(|s| !s.name.is_empty()) {
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 15))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// A tick label that stays short on any scale.
fn short_number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-2..1e4).contains(&a) {
        format!("{v:.0e}")
    } else if a >= 10.0 || v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}

/// Images side by side (all of the same height), as one image.
pub fn strip(images: &[Image]) -> Image {
    let height = images.iter().map(|im| im.height).max().unwrap_or(0);
    let gap = 4;
    let width =
        images.iter().map(|im| im.width).sum::<u32>() + gap * images.len().saturating_sub(1) as u32;
    let mut out = Image::new(width, height);
    let mut x0 = 0;
    for im in images {
        for y in 0..im.height {
            for x in 0..im.width {
                let src = 3 * (y as usize * im.width as usize + x as usize);
                let dst = 3 * (y as usize * width as usize + (x0 + x) as usize);
                out.data[dst..dst + 3].copy_from_slice(&im.data[src..src + 3]);
            }
        }
        x0 += im.width + gap;
    }
    out
}

/// A CSV file from a header and rows of already formatted cells.
pub fn write_csv(
    path: &Path,
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<String>>,
) -> Result<()> {
    let mut text = header.join(",");
    text.push('\n');
    for row in rows {
        text.push_str(&row.join(","));
        text.push('\n');
    }
    fs::write(path, text)?;
    Ok(())
}

/// A markdown table.
pub fn markdown_table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| {} |", header.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
    for row in rows {
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    s
}

/// A number in the compact scientific form the paper's tables use.
pub fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2e}")
    } else {
        "-".into()
    }
}

/// Median, minimum and maximum.
pub fn spread(values: &[f64]) -> (f64, f64, f64) {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    v.sort_by(f64::total_cmp);
    let mid = v.len() / 2;
    let median = if v.len() % 2 == 1 {
        v[mid]
    } else {
        0.5 * (v[mid - 1] + v[mid])
    };
    (median, v[0], v[v.len() - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lengths of the longest run of dark pixels in any row and in any column.
    fn longest_dark_lines(path: &Path) -> (u32, u32, u32, u32) {
        let image = image::open(path).expect("the plot reads back").to_rgb8();
        let dark = |x: u32, y: u32| image.get_pixel(x, y).0.iter().all(|&c| c < 60);
        let longest = |n: u32, at: &dyn Fn(u32) -> bool| {
            let (mut best, mut run) = (0, 0);
            for i in 0..n {
                run = if at(i) { run + 1 } else { 0 };
                best = best.max(run);
            }
            best
        };
        let (w, h) = image.dimensions();
        let rows: Vec<u32> = (0..h).map(|y| longest(w, &|x| dark(x, y))).collect();
        let columns: Vec<u32> = (0..w).map(|x| longest(h, &|y| dark(x, y))).collect();
        // Long lines in the top half (the frame's top) and the right half (its right side).
        let top = rows[..h as usize / 2].iter().copied().max().unwrap_or(0);
        let right = columns[w as usize / 2..].iter().copied().max().unwrap_or(0);
        (w, h, top, right)
    }

    /// A plot is framed on all four sides: its top and right edges are lines as long as most
    /// of the image, as the axes are; and a plot without axis labels is refused.
    #[test]
    fn plots_are_framed_and_need_labelled_axes() {
        let dir = std::env::temp_dir().join(format!("plateau-plot-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("framed.png");
        let series = [Series::line("a", vec![(0.0, 1.0), (1.0, 0.1), (2.0, 0.01)])];
        if let Err(e) = plot(&path, &Axes::log_y("t", "iteration", "MSE"), &series) {
            // Without the font no plot is drawn at all (said in the error).
            assert!(e.to_string().contains("font"), "{e}");
            return;
        }
        let (w, h, top, right) = longest_dark_lines(&path);
        assert!(
            top > w / 2,
            "no frame along the top: longest line {top} of {w}"
        );
        assert!(
            right > h / 2,
            "no frame along the right: longest line {right} of {h}"
        );
        for (x, y) in [("", "MSE"), ("iteration", " ")] {
            let refused = plot(&path, &Axes::log_y("t", x, y), &series).unwrap_err();
            assert!(refused.to_string().contains("label"), "{refused}");
        }
        fs::remove_dir_all(&dir).unwrap();
    }
}
