//! Wavefront OBJ: reader (through tobj) and writer.

use crate::numfmt::{write_f64, write_xyz};
use crate::{atomic_write, IoError, SurfaceData, SurfaceRef};
use std::io::Write;
use std::path::Path;

/// Parses the bytes of an OBJ with tobj (polygons triangulated); all objects/groups are merged
/// into one surface. Points, lines and materials are ignored (no `mtllib` file is opened). The
/// vertex and face lines are checked first, with their line numbers ([`check_lines`]): tobj's
/// own errors carry none.
pub(crate) fn parse(path: &Path, text: &[u8]) -> Result<SurfaceData, IoError> {
    check_lines(path, text)?;
    // Other tobj features (merging, reordering) add fields; keep the struct update for them.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = text;
    // Materials are not used: every `mtllib` resolves to "no materials".
    let no_materials = |_: &Path| Ok((Vec::new(), Default::default()));
    let (models, _materials) =
        tobj::load_obj_buf(&mut reader, &options, no_materials).map_err(|e| IoError::Format {
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
    // check_lines refused these already; kept so that no path returns a non-finite vertex.
    if let Some(i) = surface
        .vertices
        .iter()
        .position(|p| !p.iter().all(|x| x.is_finite()))
    {
        return Err(IoError::Format {
            file: path.to_path_buf(),
            message: format!("vertex {} has a non-finite coordinate", i + 1),
        });
    }
    Ok(surface)
}

/// The kinds of OBJ element a face corner refers to, in corner order `v/vt/vn`.
const CORNER_PARTS: [(&str, &str); 3] = [
    ("v", "vertex"),
    ("vt", "texture coordinate"),
    ("vn", "normal"),
];

/// Checks every `v` line (three finite coordinates) and `f` line (at least three corners, each
/// `v`, `v/vt`, `v//vn` or `v/vt/vn` with numbers of existing elements: 1-based, or negative,
/// counted back from the last element so far) of an OBJ, reporting the 1-based line of the
/// first problem. tobj trusts texture and normal numbers (an absurd one overflows its index
/// arithmetic), so they are checked here although only positions are read.
fn check_lines(path: &Path, text: &[u8]) -> Result<(), IoError> {
    let keyword = |raw: &[u8]| -> Option<usize> {
        let first = raw
            .split(|b| b.is_ascii_whitespace())
            .find(|w| !w.is_empty())?;
        CORNER_PARTS.iter().position(|(k, _)| k.as_bytes() == first)
    };
    let mut total = [0usize; 3];
    for raw in text.split(|&b| b == b'\n') {
        if let Some(k) = keyword(raw) {
            total[k] += 1;
        }
    }
    let mut seen = [0usize; 3];
    for (k, raw) in text.split(|&b| b == b'\n').enumerate() {
        let line = k + 1;
        let err = |message: String| IoError::parse(path, line, message);
        let Ok(s) = std::str::from_utf8(raw) else {
            return Err(err("not UTF-8 text (an OBJ file is text)".into()));
        };
        let mut words = s.split_whitespace();
        match words.next() {
            Some("v") => {
                seen[0] += 1;
                let n = seen[0];
                for axis in ["x", "y", "z"] {
                    let Some(w) = words.next() else {
                        return Err(err(format!(
                            "vertex {n} has no {axis} coordinate (expected v x y z)"
                        )));
                    };
                    let x: f64 = w.parse().map_err(|_| {
                        err(format!(
                            "vertex {n}: the {axis} coordinate \"{w}\" is not a number"
                        ))
                    })?;
                    if !x.is_finite() {
                        return Err(err(format!(
                            "vertex {n}: the {axis} coordinate is NaN/infinite (found \"{w}\")"
                        )));
                    }
                }
            }
            Some("vt") => seen[1] += 1,
            Some("vn") => seen[2] += 1,
            Some("f") => {
                let mut corners = 0;
                for w in words {
                    check_corner(w, &total, &seen).map_err(&err)?;
                    corners += 1;
                }
                if corners < 3 {
                    return Err(err(format!(
                        "a face needs at least 3 corners, found {corners}"
                    )));
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Checks one face corner `w` against the file's element counts (`total`) and those before
/// its line (`seen`), in `v, vt, vn` order; the message says what is wrong.
fn check_corner(w: &str, total: &[usize; 3], seen: &[usize; 3]) -> Result<(), String> {
    let parts: Vec<&str> = w.split('/').collect();
    if parts.len() > 3 {
        return Err(format!(
            "face corner \"{w}\" has {} parts (expected v, v/vt, v//vn or v/vt/vn)",
            parts.len()
        ));
    }
    for (k, part) in parts.iter().enumerate() {
        let (_, name) = CORNER_PARTS[k];
        if part.is_empty() && k > 0 {
            continue;
        }
        let i: i64 = part.parse().map_err(|_| {
            if k == 0 {
                format!("face corner \"{w}\" does not start with a vertex number")
            } else {
                format!("face corner \"{w}\": its {name} number \"{part}\" is not a number")
            }
        })?;
        let exists = match i {
            0 => false,
            i if i > 0 => i.unsigned_abs() <= total[k] as u64,
            i => i.unsigned_abs() <= seen[k] as u64,
        };
        if !exists {
            return Err(format!(
                "face corner \"{w}\": there is no {name} {i} (the file has {} {name}s, {} \
                 before this line; indices start at 1, negative ones count back)",
                total[k], seen[k]
            ));
        }
    }
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    fn check(text: &str) -> Result<(), String> {
        check_lines(Path::new("m.obj"), text.as_bytes()).map_err(|e| e.to_string())
    }

    const CUBE_CORNER: &str = "# a tet\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n\
                               f 1 3 2\nf 1 2 4\nf 2 3 4\nf -4/1 -1/1/1 -2//1\nvt 0 0\nvn 0 0 1\n";

    #[test]
    fn good_lines_pass() {
        check(CUBE_CORNER).unwrap();
    }

    #[test]
    fn problems_name_the_line() {
        let e = check(&CUBE_CORNER.replace("v 1 0 0", "v nan 0 0")).unwrap_err();
        assert!(
            e.starts_with("m.obj:3: vertex 2: the x coordinate is NaN/infinite"),
            "{e}"
        );
        let e = check(&CUBE_CORNER.replace("v 0 0 1", "v 0 0 inf")).unwrap_err();
        assert!(e.starts_with("m.obj:5: vertex 4: the z coordinate"), "{e}");
        let e = check(&CUBE_CORNER.replace("v 0 1 0", "v 0 1")).unwrap_err();
        assert!(
            e.starts_with("m.obj:4: vertex 3 has no z coordinate"),
            "{e}"
        );
        let e = check(&CUBE_CORNER.replace("f 1 2 4", "f 1 2 9")).unwrap_err();
        assert!(
            e.starts_with("m.obj:7: face corner \"9\": there is no vertex 9"),
            "{e}"
        );
        let e = check(&CUBE_CORNER.replace("f 2 3 4", "f 2 x 4")).unwrap_err();
        assert!(e.starts_with("m.obj:8: face corner \"x\""), "{e}");
        let e = check(&CUBE_CORNER.replace("f 2 3 4", "f 2 3")).unwrap_err();
        assert!(
            e.starts_with("m.obj:8: a face needs at least 3 corners"),
            "{e}"
        );
        let e = check(&CUBE_CORNER.replace("f 1 3 2", "f 0 3 2")).unwrap_err();
        assert!(e.starts_with("m.obj:6: "), "{e}");
    }

    #[test]
    fn texture_and_normal_numbers_are_checked() {
        // Found by the read_obj fuzz target: a normal number counted back past the start
        // overflowed tobj's index arithmetic (a panic with overflow checks on).
        let e = check(&CUBE_CORNER.replace("-2//1", "-2//-3")).unwrap_err();
        assert!(
            e.starts_with("m.obj:9: face corner \"-2//-3\": there is no normal -3"),
            "{e}"
        );
        let e = check(&CUBE_CORNER.replace("-4/1 ", "-4/2 ")).unwrap_err();
        assert!(e.contains("there is no texture coordinate 2"), "{e}");
        let e = check(&CUBE_CORNER.replace("-4/1 ", "-4/1/1/1 ")).unwrap_err();
        assert!(e.contains("has 4 parts"), "{e}");
        let e = check(&CUBE_CORNER.replace("-4/1 ", "-4/a ")).unwrap_err();
        assert!(
            e.contains("texture coordinate number \"a\" is not a number"),
            "{e}"
        );
        // The same file through the whole reader gives the same line.
        let text = CUBE_CORNER.replace("-2//1", "-2//-3");
        let e = parse(Path::new("m.obj"), text.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("m.obj:9: "), "{e}");
    }
}
