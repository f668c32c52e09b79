//! Wavefront OBJ: reader (through tobj) and writer.

use crate::numfmt::{write_f64, write_xyz};
use crate::{atomic_write, IoError, SurfaceData, SurfaceRef};
use std::io::Write;
use std::path::Path;

/// Reads an OBJ with tobj (polygons triangulated); all objects/groups are merged into one
/// surface. Points and lines are ignored.
pub(crate) fn read(path: &Path) -> Result<SurfaceData, IoError> {
    // tobj reports a missing file without the OS error; check first so the message is useful.
    std::fs::metadata(path).map_err(|e| IoError::io(path, e))?;
    // Other tobj features (merging, reordering) add fields; keep the struct update for them.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| IoError::Format {
        file: path.to_path_buf(),
        message: format!("not a readable OBJ file: {e}"),
    })?;
    let mut surface = SurfaceData::default();
    for model in &models {
        let mesh = &model.mesh;
        let base = surface.vertices.len();
        let count = mesh.positions.len() / 3;
        surface
            .vertices
            .extend(mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        for tri in mesh.indices.chunks_exact(3) {
            let mut face = [0u32; 3];
            for (f, &i) in face.iter_mut().zip(tri) {
                if i as usize >= count {
                    return Err(IoError::Format {
                        file: path.to_path_buf(),
                        message: format!(
                            "object \"{}\": vertex index {i} out of range ({count} vertices)",
                            model.name
                        ),
                    });
                }
                *f = u32::try_from(base + i as usize).map_err(|_| IoError::Format {
                    file: path.to_path_buf(),
                    message: "more than 2^32 vertices".into(),
                })?;
            }
            surface.faces.push(face);
        }
    }
    Ok(surface)
}

/// Writes an OBJ: `v x y z` (plus `r g b` in 0..1 when the surface has colours, the common
/// extension Blender and MeshLab read) and 1-based `f a b c`. Crack flags are not represented.
pub fn write_obj(path: &Path, surface: &SurfaceRef) -> Result<(), IoError> {
    surface.validate(path)?;
    atomic_write(path, |w| {
        writeln!(
            w,
            "# written by perifrac-io: {} vertices, {} triangles",
            surface.vertices.len(),
            surface.faces.len()
        )?;
        for (i, p) in surface.vertices.iter().enumerate() {
            w.write_all(b"v ")?;
            write_xyz(w, p)?;
            if let Some(rgb) = surface.colors.and_then(|c| c.get(i)) {
                for &c in rgb {
                    w.write_all(b" ")?;
                    write_f64(w, f64::from(c) / 255.0)?;
                }
            }
            w.write_all(b"\n")?;
        }
        for f in surface.faces {
            writeln!(w, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
        }
        Ok(())
    })
}
