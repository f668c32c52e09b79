//! `frames/surface_NNNN.inc`: the frame's surface as a POV-Ray `mesh2` with normals, declared
//! as [`POVRAY_MESH_NAME`].

use std::path::Path;

use perifrac_io::write_povray_mesh2;

use super::{FrameFiles, FrameSink, FrameView, Written};

/// The identifier the `mesh2` of a frame's POV-Ray include is declared as.
pub const POVRAY_MESH_NAME: &str = "surface";

/// Writes the POV-Ray include.
pub struct PovraySink;

impl FrameSink for PovraySink {
    fn write(&self, dir: &Path, frame: &FrameView, files: &mut FrameFiles) -> Written {
        let name = format!("frames/surface_{:04}.inc", frame.index);
        write_povray_mesh2(&dir.join(&name), &frame.surface, POVRAY_MESH_NAME)?;
        files.povray = Some(name);
        Ok(())
    }
}
