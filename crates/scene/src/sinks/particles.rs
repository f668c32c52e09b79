//! `frames/particles_NNNN.ply`: the particles as PLY points with `damage`, `mass` (kg) and
//! `fragment`.

use std::path::Path;

use perifrac_io::write_ply_points;

use super::{FrameFiles, FrameSink, FrameView, Written};

/// Writes the particle PLY (a body without particles writes none).
pub struct ParticlesSink;

impl FrameSink for ParticlesSink {
    fn write(&self, dir: &Path, frame: &FrameView, files: &mut FrameFiles) -> Written {
        let Some(p) = &frame.particles else {
            return Ok(());
        };
        let name = format!("frames/particles_{:04}.ply", frame.index);
        write_ply_points(
            &dir.join(&name),
            p.positions,
            &[
                ("damage", p.damage),
                ("mass", p.mass),
                ("fragment", p.fragment),
            ],
        )?;
        files.particles = Some(name);
        Ok(())
    }

    fn wants_particles(&self) -> bool {
        true
    }
}
