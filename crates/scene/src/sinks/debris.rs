//! `frames/debris_NNNN.ply`: small pieces as points at their centres of mass, with `radius`
//! (m), velocity `vx vy vz` (m/s), `mass` (kg) and `fragment` (see [`crate::debris`]).

use std::path::Path;

use perifrac_io::write_ply_points;

use super::{FrameFiles, FrameSink, FrameView, Written};
use crate::manifest::DebrisJson;

/// Writes the debris PLY when the body made debris.
pub struct DebrisSink;

impl FrameSink for DebrisSink {
    fn write(&self, dir: &Path, frame: &FrameView, files: &mut FrameFiles) -> Written {
        let Some(debris) = frame.debris else {
            return Ok(());
        };
        let name = format!("frames/debris_{:04}.ply", frame.index);
        let velocity = |d: usize| -> Vec<f64> { debris.velocity.iter().map(|v| v[d]).collect() };
        let fragment: Vec<f64> = debris.fragment.iter().map(|&f| f64::from(f)).collect();
        write_ply_points(
            &dir.join(&name),
            &debris.points,
            &[
                ("radius", &debris.radius),
                ("vx", &velocity(0)),
                ("vy", &velocity(1)),
                ("vz", &velocity(2)),
                ("mass", &debris.mass),
                ("fragment", &fragment),
            ],
        )?;
        files.debris = Some(DebrisJson {
            path: name,
            pieces: debris.points.len(),
        });
        Ok(())
    }
}
