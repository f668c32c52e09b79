//! Medit / INRIA `.mesh` (ASCII): reader and writer.
//!
//! Keywords are case-insensitive, the count may be on the keyword's line or the next, `#`
//! starts a comment. Indices are 1-based in the file. Sections other than Vertices,
//! Tetrahedra and Triangles are skipped by their count and listed in `skipped`.

use crate::check::{self, Skipped};
use crate::error::read_all;
use crate::numfmt::write_xyz;
use crate::tokens::{show, Tokens};
use crate::{atomic_write, IoError, TetMeshData};
use std::io::Write;
use std::path::Path;

/// Tokens per item of the sections that are skipped.
const SKIPPED_SECTIONS: &[(&str, usize)] = &[
    ("edges", 3),
    ("quadrilaterals", 5),
    ("hexahedra", 9),
    ("prisms", 7),
    ("pyramids", 6),
    ("corners", 1),
    ("ridges", 1),
    ("requiredvertices", 1),
    ("requirededges", 1),
    ("requiredtriangles", 1),
    ("requiredquadrilaterals", 1),
    ("requiredtetrahedra", 1),
    ("normals", 3),
    ("tangents", 3),
    ("normalatvertices", 2),
    ("normalattrianglevertices", 3),
    ("normalatquadrilateralvertices", 3),
    ("tangentatvertices", 2),
    ("tangentatedgevertices", 3),
    ("edgesp2", 4),
    ("trianglesp2", 7),
    ("tetrahedrap2", 11),
];

const TET: &str = "4 vertex indices and a reference after \"Tetrahedra\"";
const TRI: &str = "3 vertex indices and a reference after \"Triangles\"";
const VERT: &str = "a vertex reference after the 3 coordinates";

/// Reads a `.mesh` file.
pub(crate) fn read(path: &Path) -> Result<TetMeshData, IoError> {
    parse(path, &read_all(path)?)
}

/// Parses the bytes of a `.mesh` file.
pub(crate) fn parse(path: &Path, data: &[u8]) -> Result<TetMeshData, IoError> {
    let mut t = Tokens::new(path, data);
    let mut mesh = TetMeshData::default();
    let mut skipped = Skipped::default();
    let mut vertices_seen = false;
    // Line of an element section read before Vertices: its range check happens at the end.
    let mut late_check: Option<usize> = None;
    while let Some(keyword) = t.next() {
        let keyword_line = t.line();
        let lower = keyword.to_ascii_lowercase();
        match lower.as_slice() {
            b"end" => break,
            b"meshversionformatted" => {
                t.u64("a version number after \"MeshVersionFormatted\"")?;
            }
            b"dimension" => {
                let d = t.u64("a dimension after \"Dimension\"")?;
                if d != 3 {
                    return Err(t.error(format!("expected Dimension 3, found Dimension {d}")));
                }
            }
            b"vertices" => {
                if vertices_seen {
                    return Err(t.error("a second \"Vertices\" section"));
                }
                let n = t.usize("a vertex count after \"Vertices\"")?;
                mesh.vertices.reserve(t.capacity_hint(n, 8));
                for i in 0..n {
                    let ctx = || format!("vertex {} of {n}", i + 1);
                    let mut p = [0.0; 3];
                    for c in &mut p {
                        *c = t.f64("coordinate").map_err(|e| e.context(ctx))?;
                    }
                    t.i64(VERT).map_err(|e| e.context(ctx))?;
                    mesh.vertices.push(p);
                }
                vertices_seen = true;
            }
            b"tetrahedra" => {
                let n = t.usize("a tet count after \"Tetrahedra\"")?;
                let limit = index_limit(vertices_seen, &mesh, &mut late_check, keyword_line);
                mesh.tets.reserve(t.capacity_hint(n, 10));
                mesh.tet_labels.reserve(t.capacity_hint(n, 10));
                for i in 0..n {
                    let ctx = || format!("tet {} of {n}", i + 1);
                    let mut raw = [0u64; 4];
                    for r in &mut raw {
                        *r = t.u64(TET).map_err(|e| e.context(ctx))?;
                    }
                    let line = t.line();
                    let label = t.i32(TET).map_err(|e| e.context(ctx))?;
                    let id = mesh.tets.len() as u64 + 1;
                    let tet = check::element(&t, line, raw, 1, limit, "tet", id, "the file")?;
                    mesh.tets.push(tet);
                    mesh.tet_labels.push(label);
                    mesh.tet_lines.push(line);
                }
            }
            b"triangles" => {
                let n = t.usize("a triangle count after \"Triangles\"")?;
                let limit = index_limit(vertices_seen, &mesh, &mut late_check, keyword_line);
                mesh.boundary_faces.reserve(t.capacity_hint(n, 8));
                for i in 0..n {
                    let ctx = || format!("triangle {} of {n}", i + 1);
                    let mut raw = [0u64; 3];
                    for r in &mut raw {
                        *r = t.u64(TRI).map_err(|e| e.context(ctx))?;
                    }
                    let line = t.line();
                    t.i64(TRI).map_err(|e| e.context(ctx))?;
                    let id = mesh.boundary_faces.len() as u64 + 1;
                    let face = check::element(&t, line, raw, 1, limit, "triangle", id, "the file")?;
                    mesh.boundary_faces.push(face);
                }
            }
            other => {
                let Some(&(_, per_item)) = SKIPPED_SECTIONS
                    .iter()
                    .find(|(name, _)| name.as_bytes() == other)
                else {
                    return Err(t.error(format!(
                        "expected a Medit keyword (Vertices, Tetrahedra, Triangles, End, ...), found \"{}\"",
                        show(keyword)
                    )));
                };
                let name = String::from_utf8_lossy(keyword).into_owned();
                let what = format!("a count after \"{name}\"");
                let n = t.usize(&what)?;
                let what = format!("{per_item} values per item of \"{name}\"");
                for i in 0..n.saturating_mul(per_item) {
                    t.expect(&what)
                        .map_err(|e| e.context(|| format!("item {} of {n}", i / per_item + 1)))?;
                }
                skipped.add(&name, n);
            }
        }
    }
    if let Some(line) = late_check {
        let n = mesh.vertices.len();
        let too_big = |i: &u32| *i as usize >= n;
        if mesh.tets.iter().flatten().any(too_big)
            || mesh.boundary_faces.iter().flatten().any(too_big)
        {
            return Err(t.error_at(
                line,
                format!(
                    "a vertex index in this section is out of range (the file has {n} vertices)"
                ),
            ));
        }
    }
    mesh.skipped = skipped.into_vec();
    Ok(mesh)
}

/// Writes `mesh` as a `.mesh` file (version 2, 1-based indices, labels as tet references).
pub(crate) fn write(path: &Path, mesh: &TetMeshData) -> Result<(), IoError> {
    atomic_write(path, |w| {
        writeln!(w, "MeshVersionFormatted 2\nDimension 3\n")?;
        writeln!(w, "Vertices\n{}", mesh.vertices.len())?;
        for p in &mesh.vertices {
            write_xyz(w, p)?;
            w.write_all(b" 0\n")?;
        }
        writeln!(w, "\nTetrahedra\n{}", mesh.tets.len())?;
        for (t, label) in mesh.tets.iter().zip(&mesh.tet_labels) {
            writeln!(
                w,
                "{} {} {} {} {label}",
                t[0] + 1,
                t[1] + 1,
                t[2] + 1,
                t[3] + 1
            )?;
        }
        if !mesh.boundary_faces.is_empty() {
            writeln!(w, "\nTriangles\n{}", mesh.boundary_faces.len())?;
            for f in &mesh.boundary_faces {
                writeln!(w, "{} {} {} 0", f[0] + 1, f[1] + 1, f[2] + 1)?;
            }
        }
        writeln!(w, "\nEnd")
    })
}

/// Largest vertex index an element section may use: the vertex count once `Vertices` was read;
/// otherwise anything, with the section's line kept so the indices are checked at the end.
fn index_limit(
    vertices_seen: bool,
    mesh: &TetMeshData,
    late_check: &mut Option<usize>,
    keyword_line: usize,
) -> usize {
    if vertices_seen {
        mesh.vertices.len()
    } else {
        late_check.get_or_insert(keyword_line);
        u32::MAX as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("m.mesh")
    }

    #[test]
    fn count_on_next_line_and_skipped_sections() {
        let src = b"MeshVersionFormatted 1\nDimension\n3\n# c\nvertices 4\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\nEdges 1\n1 2 0\nTETRAHEDRA\n1\n1 2 3 4 7\nTriangles 1 1 2 3 5\nEnd\n";
        let m = parse(p(), src).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.tets, vec![[0, 1, 2, 3]]);
        assert_eq!(m.tet_labels, vec![7]);
        assert_eq!(m.boundary_faces, vec![[0, 1, 2]]);
        assert_eq!(m.skipped, vec![("Edges".to_string(), 1)]);
    }

    #[test]
    fn truncated_names_line() {
        let src = b"Dimension 3\nVertices 4\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\nTetrahedra 2\n1 2 3 4 0\n";
        let e = parse(p(), src).unwrap_err().to_string();
        assert!(e.starts_with("m.mesh:8: expected 4 vertex indices and a reference after \"Tetrahedra\", found end of file"), "{e}");
        assert!(e.contains("tet 2 of 2"), "{e}");
    }

    #[test]
    fn tets_before_vertices_are_range_checked() {
        let src = b"Dimension 3\nTetrahedra 1\n1 2 3 9 0\nVertices 4\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\nEnd";
        let e = parse(p(), src).unwrap_err().to_string();
        assert!(e.starts_with("m.mesh:2: "), "{e}");
    }
}
