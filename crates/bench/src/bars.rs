//! Bar charts as PNG (histograms: crack directions, fragment sizes), through plotters' bitmap
//! backend, with linear axes; several series are drawn side by side in each bin.

use std::path::Path;

use plotters::prelude::*;

use crate::error::BenchError;
use crate::plot::{font, COLORS};

/// Bars over labelled bins, one bar per series in each bin.
#[derive(Debug, Clone, PartialEq)]
pub struct Bars {
    /// Title above the chart.
    pub title: String,
    /// Label of the x axis (the bins).
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// The bins' labels, left to right.
    pub bins: Vec<String>,
    /// `(legend entry, one value per bin)`.
    pub series: Vec<(String, Vec<f64>)>,
    /// A horizontal line to draw across the chart (a target), with its legend entry.
    pub line: Option<(String, f64)>,
}

impl Bars {
    /// Draws the chart into `path` (PNG, 900 x 600 pixels), written to a temporary name beside
    /// it and renamed into place.
    pub fn write_png(&self, path: &Path) -> Result<(), BenchError> {
        crate::plot::write_png_atomically(path, |tmp| self.draw(tmp))
    }

    fn draw(&self, path: &Path) -> Result<(), BenchError> {
        let err = |message: String| BenchError::Plot {
            file: path.display().to_string(),
            message,
        };
        font().map_err(err)?;
        let e = |e: &dyn std::fmt::Display| err(e.to_string());
        let n = self.bins.len();
        let top = self
            .series
            .iter()
            .flat_map(|(_, v)| v.iter().copied())
            .chain(self.line.iter().map(|l| l.1))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        if n == 0 || top <= 0.0 {
            return Err(err("nothing to draw".into()));
        }
        let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(60)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..n as f64, 0.0..1.1 * top)
            .map_err(|x| e(&x))?;
        let bins = &self.bins;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_label_formatter(&|x| {
                let k = x.floor() as usize;
                // Labels at the bins' middles only.
                if (x - k as f64 - 0.5).abs() < 1e-9 && k < bins.len() {
                    bins[k].clone()
                } else {
                    String::new()
                }
            })
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|x| e(&x))?;
        let groups = self.series.len().max(1) as f64;
        let width = 0.8 / groups;
        for (s, (name, values)) in self.series.iter().enumerate() {
            let color = COLORS[s % COLORS.len()];
            chart
                .draw_series(
                    values
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| v.is_finite())
                        .map(|(k, &v)| {
                            let x0 = k as f64 + 0.1 + s as f64 * width;
                            Rectangle::new([(x0, 0.0), (x0 + width, v)], color.filled())
                        }),
                )
                .map_err(|x| e(&x))?
                .label(name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled())
                });
        }
        if let Some((name, y)) = &self.line {
            let y = *y;
            chart
                .draw_series(LineSeries::new(
                    vec![(0.0, y), (n as f64, y)],
                    BLACK.stroke_width(2),
                ))
                .map_err(|x| e(&x))?
                .label(name)
                .legend(move |(x, ly)| PathElement::new(vec![(x, ly), (x + 14, ly)], BLACK));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }
}
