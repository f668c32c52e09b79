//! `perifrac convert`: tet mesh and surface format conversion.

use std::path::Path;

use anyhow::{bail, Result};
use perifrac_io::{SurfaceRef, TetFormat};

use crate::load::{load_tet_mesh, to_data};

/// Surface extensions (read side) that `convert` treats as surfaces rather than tet meshes.
const SURFACE_IN: [&str; 3] = ["obj", "off", "ply"];

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Converts `input` to `output`, both formats chosen by extension.
pub fn run(input: &Path, output: &Path, gmsh22: bool) -> Result<()> {
    if SURFACE_IN.contains(&extension(input).as_str()) {
        return convert_surface(input, output);
    }
    let mut format = TetFormat::from_path(output)?;
    if gmsh22 {
        if !matches!(format, TetFormat::Gmsh41) {
            bail!("--gmsh22 only applies to .msh output");
        }
        format = TetFormat::Gmsh22;
    }
    let loaded = load_tet_mesh(input)?;
    let data = to_data(&loaded.mesh, loaded.tet_labels, loaded.boundary_faces);
    perifrac_io::write_tet_mesh(output, &data, format)?;
    eprintln!(
        "wrote {} ({} vertices, {} tets{})",
        output.display(),
        data.vertices.len(),
        data.tets.len(),
        match loaded.report.inverted_fixed {
            0 => String::new(),
            n => format!(", {n} inverted tets reoriented"),
        }
    );
    for (kind, count) in &loaded.skipped {
        eprintln!("skipped {count} {kind}");
    }
    Ok(())
}

fn convert_surface(input: &Path, output: &Path) -> Result<()> {
    if TetFormat::from_path(output).is_ok() {
        bail!(
            "{} is a surface and {} a tet mesh format: convert changes formats, not what the \
             mesh is; make a tet mesh of the surface with `perifrac mesh {} -o {}`",
            input.display(),
            output.display(),
            input.display(),
            output.display()
        );
    }
    let surface = perifrac_io::read_surface(input)?;
    let view = SurfaceRef {
        vertices: &surface.vertices,
        faces: &surface.faces,
        crack: None,
        colors: None,
        ..Default::default()
    };
    perifrac_io::write_surface(output, &view)?;
    eprintln!(
        "wrote {} ({} vertices, {} triangles)",
        output.display(),
        surface.vertices.len(),
        surface.faces.len()
    );
    Ok(())
}
