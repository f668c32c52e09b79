//! POV-Ray `mesh2` include writer.
//!
//! The file declares `#declare NAME = mesh2 { ... }`. When the surface has crack flags, each
//! face carries a texture index from a two-entry `texture_list`: 0 for the original surface,
//! 1 for crack faces. The two textures are identifiers the scene may declare *before*
//! including the file:
//!
//! ```text
//! #declare NAME_surface_texture = texture { pigment { rgb <0.9, 0.9, 0.85> } }
//! #declare NAME_crack_texture   = texture { pigment { rgb <0.7, 0.2, 0.1> } }
//! #include "frame_0001.inc"
//! object { NAME }
//! ```
//!
//! Undeclared ones get neutral defaults (`#ifndef`). Without crack flags no `texture_list` is
//! written, so `object { NAME texture { ... } }` in the scene decides. Vertex normals, when
//! given, are written as `normal_vectors` (smooth shading between them); vertex colours are not
//! written.

use crate::numfmt::write_xyz_sep;
use crate::{atomic_write, IoError, SurfaceRef};
use std::io::Write;
use std::path::Path;

/// Writes `surface` as a POV-Ray include declaring the `mesh2` object `name` (a POV-Ray
/// identifier: letters, digits, `_`, not starting with a digit).
pub fn write_povray_mesh2(path: &Path, surface: &SurfaceRef, name: &str) -> Result<(), IoError> {
    surface.validate(path)?;
    let valid = name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !valid {
        return Err(IoError::invalid(
            path,
            format!("\"{name}\" is not a POV-Ray identifier"),
        ));
    }
    atomic_write(path, |w| {
        writeln!(
            w,
            "// POV-Ray mesh2 written by perifrac-io: {} vertices, {} triangles.",
            surface.vertices.len(),
            surface.faces.len()
        )?;
        if surface.crack.is_some() {
            writeln!(
                w,
                "// Face texture 0 = {name}_surface_texture, 1 = {name}_crack_texture;"
            )?;
            writeln!(
                w,
                "// declare them before including this file to override the defaults."
            )?;
            writeln!(w, "#ifndef ({name}_surface_texture)\n  #declare {name}_surface_texture = texture {{ pigment {{ rgb <0.85, 0.85, 0.85> }} }}\n#end")?;
            writeln!(w, "#ifndef ({name}_crack_texture)\n  #declare {name}_crack_texture = texture {{ pigment {{ rgb <0.75, 0.25, 0.1> }} }}\n#end")?;
        }
        writeln!(w, "#declare {name} = mesh2 {{")?;
        writeln!(w, "  vertex_vectors {{\n    {}", surface.vertices.len())?;
        for p in surface.vertices {
            w.write_all(b"    ,<")?;
            write_xyz_sep(w, p, b",")?;
            w.write_all(b">\n")?;
        }
        w.write_all(b"  }\n")?;
        if let Some(normals) = surface.normals {
            // As many normals as vertices and no normal_indices: POV-Ray takes the face
            // indices for the normals too, and interpolates them across each face.
            writeln!(w, "  normal_vectors {{\n    {}", normals.len())?;
            for n in normals {
                w.write_all(b"    ,<")?;
                write_xyz_sep(w, n, b",")?;
                w.write_all(b">\n")?;
            }
            w.write_all(b"  }\n")?;
        }
        if surface.crack.is_some() {
            writeln!(w, "  texture_list {{ 2, texture {{ {name}_surface_texture }}, texture {{ {name}_crack_texture }} }}")?;
        }
        writeln!(w, "  face_indices {{\n    {}", surface.faces.len())?;
        for (i, f) in surface.faces.iter().enumerate() {
            write!(w, "    ,<{},{},{}>", f[0], f[1], f[2])?;
            if let Some(flag) = surface.crack.and_then(|c| c.get(i)) {
                write!(w, ",{}", u8::from(*flag != 0))?;
            }
            w.write_all(b"\n")?;
        }
        w.write_all(b"  }\n}\n")
    })
}
