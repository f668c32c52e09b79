//! `frames/surface_NNNN.ply`: the binary PLY of the frame's surface, with every field the body
//! gives (normals, velocities, texture coordinates, vertex ids, crack flags, fragment ids).

use std::path::Path;

use perifrac_io::{write_ply, PlyEncoding};

use super::{FrameFiles, FrameSink, FrameView, Written};

/// Writes the surface PLY.
pub struct SurfacePlySink;

impl FrameSink for SurfacePlySink {
    fn write(&self, dir: &Path, frame: &FrameView, files: &mut FrameFiles) -> Written {
        let name = format!("frames/surface_{:04}.ply", frame.index);
        write_ply(
            &dir.join(&name),
            &frame.surface,
            PlyEncoding::BinaryLittleEndian,
        )?;
        files.surface = name;
        Ok(())
    }
}
