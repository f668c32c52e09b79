//! Error against wall time (and other curves) as PNG, through plotters' bitmap backend.
//!
//! Text needs a TrueType font; plotters is built with `ab_glyph`, which reads one from bytes,
//! so no system library is linked: the first of [`FONT_PATHS`] that exists is loaded once.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::error::BenchError;

/// Where a sans-serif TrueType font is looked for (Debian's fonts-dejavu-core first).
pub const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// Curve colours: distinct on white, none pale.
pub(crate) const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 0),
];

/// `v` with at most two significant digits and no exponent: 0.0012, 0.5, 3, 120.
fn short(v: f64) -> String {
    let rounded: f64 = format!("{v:.1e}").parse().unwrap_or(v);
    format!("{rounded}")
}

/// Whether a point can be drawn on logarithmic axes: finite and positive.
fn drawable(&(x, y): &(f64, f64)) -> bool {
    x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0
}

/// One curve: a name for the legend and its points `(x, y)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Points in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// A plot of several curves with logarithmic axes.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
}

pub(crate) fn font() -> Result<(), String> {
    static LOADED: OnceLock<Result<(), String>> = OnceLock::new();
    LOADED
        .get_or_init(|| {
            for path in FONT_PATHS {
                if let Ok(bytes) = std::fs::read(path) {
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    return register_font("sans-serif", FontStyle::Normal, bytes)
                        .map_err(|_| format!("{path} is not a usable font"));
                }
            }
            Err(format!(
                "no TrueType font found (looked for {}); install fonts-dejavu-core",
                FONT_PATHS.join(", ")
            ))
        })
        .clone()
}

/// Draws a PNG with `draw` into a temporary name beside `path` and renames it into place, so
/// a reader never sees half a picture.
pub(crate) fn write_png_atomically(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), BenchError>,
) -> Result<(), BenchError> {
    let tmp = path.with_extension("tmp.png");
    draw(&tmp)?;
    std::fs::rename(&tmp, path).map_err(|e| BenchError::Plot {
        file: path.display().to_string(),
        message: e.to_string(),
    })
}

impl Plot {
    /// Draws the plot into `path` (PNG, 900 x 600 pixels), both axes logarithmic over the
    /// points' range; written to a temporary name beside it and renamed into place. Points that
    /// are not finite and positive are left out.
    pub fn write_png(&self, path: &Path) -> Result<(), BenchError> {
        write_png_atomically(path, |tmp| self.draw(tmp))
    }

    fn draw(&self, path: &Path) -> Result<(), BenchError> {
        let err = |message: String| BenchError::Plot {
            file: path.display().to_string(),
            message,
        };
        font().map_err(err)?;
        let points = || {
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .filter(|p| drawable(p))
        };
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(x, y) in points() {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        if x0 > x1 {
            return Err(err("no finite, positive point to draw".into()));
        }
        let (x0, x1) = (x0 / 1.5, x1 * 1.5);
        let (y0, y1) = (y0 / 1.5, y1 * 1.5);
        let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
        let e = |e: &dyn std::fmt::Display| err(e.to_string());
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_label_formatter(&|x| short(*x))
            .y_label_formatter(&|y| format!("{}%", short(100.0 * y)))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(|x| e(&x))?;
        for (k, s) in self.series.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(drawable).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(|x| e(&x))?
                .label(&s.name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(|x| e(&x))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperMiddle)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }
}
