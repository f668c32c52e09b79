//! Maps of a surface's triangles as PNG (the look report's crack faces, as cut and smoothed):
//! triangles already projected to 2-D, drawn back to front, each filled with a colour for its
//! value on a blue (0) to red (the top of the scale) ramp; one panel per surface, in rows.

use std::path::Path;

use plotters::prelude::*;

use crate::error::BenchError;
use crate::plot::font;

/// One panel: its caption and its triangles, back to front, with one value each.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Caption above the panel.
    pub caption: String,
    /// Triangles in the picture's plane (length), drawn in this order.
    pub triangles: Vec<[[f64; 2]; 3]>,
    /// One value per triangle, coloured on the shared scale.
    pub values: Vec<f64>,
}

/// Panels of triangles coloured by value on one scale.
#[derive(Debug, Clone, PartialEq)]
pub struct Facets {
    /// Title above the panels.
    pub title: String,
    /// What the colour says, with its unit, and the value at the top of the scale (red).
    pub scale: (String, f64),
    /// The panels, left to right and row by row.
    pub panels: Vec<Panel>,
    /// Rows the panels are laid out in (at least 1; the last may be short).
    pub rows: usize,
}

/// The ramp's colour for `share` of the scale (clamped to [0, 1]): blue through green and
/// yellow to red.
fn ramp(share: f64) -> HSLColor {
    let s = if share.is_finite() {
        share.clamp(0.0, 1.0)
    } else {
        1.0
    };
    HSLColor(0.66 * (1.0 - s), 0.85, 0.5)
}

impl Facets {
    /// Draws the panels into `path` (PNG, 450 pixels wide and 400 high per panel, with 120
    /// for the title and the scale), written atomically.
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
        // Each panel centred on its own triangles, all at one scale (the widest extent's),
        // equal on both axes.
        let bounds: Vec<[f64; 4]> = self
            .panels
            .iter()
            .map(|p| {
                let mut b = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
                for q in p.triangles.iter().flatten() {
                    b = [
                        b[0].min(q[0]),
                        b[1].max(q[0]),
                        b[2].min(q[1]),
                        b[3].max(q[1]),
                    ];
                }
                b
            })
            .collect();
        let half = 0.55
            * bounds
                .iter()
                .map(|b| (b[1] - b[0]).max(b[3] - b[2]))
                .fold(0.0, f64::max);
        if self.panels.is_empty() || bounds.iter().any(|b| b[0] > b[1]) || half <= 0.0 {
            return Err(err("nothing to draw".into()));
        }
        let rows = self.rows.clamp(1, self.panels.len());
        let columns = self.panels.len().div_ceil(rows);
        let width = 450 * columns as u32;
        let height = 400 * rows as u32;
        let root = BitMapBackend::new(path, (width, height + 120)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let root = root
            .titled(&self.title, ("sans-serif", 20))
            .map_err(|x| e(&x))?;
        let (body, legend) = root.split_vertically(height);
        for ((panel, b), area) in self
            .panels
            .iter()
            .zip(&bounds)
            .zip(body.split_evenly((rows, columns)))
        {
            let (cx, cy) = (0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]));
            let mut chart = ChartBuilder::on(&area)
                .caption(&panel.caption, ("sans-serif", 16))
                .margin(10)
                .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)
                .map_err(|x| e(&x))?;
            let top = self.scale.1;
            chart
                .draw_series(panel.triangles.iter().zip(&panel.values).map(|(t, &v)| {
                    let colour = ramp(v / top);
                    Polygon::new(t.map(|p| (p[0], p[1])).to_vec(), colour.filled())
                }))
                .map_err(|x| e(&x))?;
        }
        // The scale: a strip of the ramp with its two ends labelled.
        let steps = 60;
        let (left, right) = (40i32, width as i32 - 40);
        let span = f64::from(right - left);
        for k in 0..steps {
            let a = left + (span * k as f64 / steps as f64) as i32;
            let b = left + (span * (k + 1) as f64 / steps as f64) as i32;
            legend
                .draw(&Rectangle::new(
                    [(a, 10), (b, 34)],
                    ramp((k as f64 + 0.5) / steps as f64).filled(),
                ))
                .map_err(|x| e(&x))?;
        }
        let style = ("sans-serif", 15).into_font();
        for (text, x) in [
            ("0".to_string(), left),
            (format!("{}", self.scale.1), right - 30),
        ] {
            legend
                .draw(&Text::new(text, (x, 40), style.clone()))
                .map_err(|x| e(&x))?;
        }
        legend
            .draw(&Text::new(
                self.scale.0.clone(),
                ((width / 2) as i32 - 140, 58),
                style,
            ))
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }
}
