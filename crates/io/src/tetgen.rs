//! TetGen `.node` / `.ele` / `.face`: reader and writer.
//!
//! The first point id (0 or 1) sets the index base for all three files; `#` comments and blank
//! lines are allowed anywhere. The first `.ele` attribute becomes the tet label. The writer
//! uses base 0, writes one attribute (the label) per tet, and writes `.face` only when there
//! are boundary faces (removing a stale one otherwise, so a round trip reads what was written).

use crate::check::{self, Skipped};
use crate::error::read_all;
use crate::numfmt::write_xyz;
use crate::tokens::{show, Tokens};
use crate::{atomic_write, IoError, TetMeshData};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Reads a TetGen mesh given the path of its `.node` or `.ele`.
pub(crate) fn read(path: &Path) -> Result<TetMeshData, IoError> {
    let node_path = path.with_extension("node");
    let ele_path = path.with_extension("ele");
    let node_data = read_sibling(&node_path, path)?;
    let ele_data = read_sibling(&ele_path, path)?;
    let face_path = path.with_extension("face");
    let face_data = if face_path.is_file() {
        Some(read_all(&face_path)?)
    } else {
        None
    };
    parse_all(path, &node_data, &ele_data, face_data.as_deref())
}

/// Parses the three files' bytes; errors name `path` with each file's extension.
pub(crate) fn parse_all(
    path: &Path,
    node: &[u8],
    ele: &[u8],
    face: Option<&[u8]>,
) -> Result<TetMeshData, IoError> {
    let (vertices, base) = parse_node(&path.with_extension("node"), node)?;
    let mut mesh = parse_ele(&path.with_extension("ele"), ele, vertices.len(), base)?;
    mesh.vertices = vertices;
    if let Some(face) = face {
        let face_path = path.with_extension("face");
        mesh.boundary_faces = parse_face(&face_path, face, mesh.vertices.len(), base)?;
    }
    Ok(mesh)
}

fn read_sibling(sibling: &Path, asked: &Path) -> Result<Vec<u8>, IoError> {
    match std::fs::read(sibling) {
        Ok(d) => Ok(d),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(IoError::MissingSibling {
            missing: sibling.to_path_buf(),
            from: asked.to_path_buf(),
        }),
        Err(e) => Err(IoError::io(sibling, e)),
    }
}

/// Reads the optional header fields after the count (absent ones default to `default`).
fn header_field(t: &mut Tokens, what: &str, default: usize) -> Result<usize, IoError> {
    if t.more_on_line() {
        t.usize(what)
    } else {
        Ok(default)
    }
}

/// Parses a `.node` file; returns the points and the index base (first point id).
pub(crate) fn parse_node(path: &Path, data: &[u8]) -> Result<(Vec<[f64; 3]>, u64), IoError> {
    let mut t = Tokens::new(path, data);
    let n = t.usize("the number of points")?;
    let dim = header_field(&mut t, "the dimension", 3)?;
    if dim != 3 {
        return Err(t.error(format!("expected dimension 3, found {dim}")));
    }
    let attrs = header_field(&mut t, "the number of point attributes", 0)?;
    let markers = header_field(&mut t, "the boundary-marker flag (0 or 1)", 0)?;
    if markers > 1 {
        return Err(t.error(format!(
            "expected boundary-marker flag 0 or 1, found {markers}"
        )));
    }
    let extra = attrs.saturating_add(markers);
    let what = "a point: id, x, y, z";
    let mut points = Vec::with_capacity(t.capacity_hint(n, 8));
    let mut base = 0;
    for i in 0..n {
        let ctx = || format!("point {} of {n}", i + 1);
        let id = t.u64(what).map_err(|e| e.context(ctx))?;
        if i == 0 {
            if id > 1 {
                return Err(t.error(format!("expected first point id 0 or 1, found {id}")));
            }
            base = id;
        } else if id != base + i as u64 {
            return Err(t.error(format!("expected point id {}, found {id}", base + i as u64)));
        }
        let mut p = [0.0; 3];
        for c in &mut p {
            *c = t.f64("coordinate").map_err(|e| e.context(ctx))?;
        }
        for _ in 0..extra {
            t.expect("point attributes and marker")
                .map_err(|e| e.context(ctx))?;
        }
        points.push(p);
    }
    Ok((points, base))
}

/// Parses an `.ele` file against `num_vertices` points numbered from `base`.
pub(crate) fn parse_ele(
    path: &Path,
    data: &[u8],
    num_vertices: usize,
    base: u64,
) -> Result<TetMeshData, IoError> {
    let mut t = Tokens::new(path, data);
    let n = t.usize("the number of tetrahedra")?;
    let per_tet = header_field(&mut t, "the number of nodes per tetrahedron", 4)?;
    if per_tet != 4 && per_tet != 10 {
        return Err(t.error(format!(
            "expected 4 or 10 nodes per tetrahedron, found {per_tet}"
        )));
    }
    let attrs = header_field(&mut t, "the number of region attributes", 0)?;
    let what = "a tetrahedron: id and 4 vertex indices";
    let mut mesh = TetMeshData {
        tets: Vec::with_capacity(t.capacity_hint(n, 10)),
        tet_labels: Vec::with_capacity(t.capacity_hint(n, 10)),
        tet_lines: Vec::with_capacity(t.capacity_hint(n, 10)),
        ..TetMeshData::default()
    };
    for i in 0..n {
        let ctx = || format!("tetrahedron {} of {n}", i + 1);
        let id = t.u64(what).map_err(|e| e.context(ctx))?;
        let mut raw = [0u64; 4];
        for r in &mut raw {
            *r = t.u64(what).map_err(|e| e.context(ctx))?;
        }
        let line = t.line();
        for _ in 4..per_tet {
            t.u64("second-order node indices")
                .map_err(|e| e.context(ctx))?;
        }
        let mut label = 0;
        for a in 0..attrs {
            let v = t.f64("a region attribute").map_err(|e| e.context(ctx))?;
            if a == 0 {
                label = to_label(v).ok_or_else(|| {
                    t.error(format!(
                        "region attribute {v} of tetrahedron {id} is not an integer label"
                    ))
                })?;
            }
        }
        let tet = check::element(
            &t,
            line,
            raw,
            base,
            num_vertices,
            "tetrahedron",
            id,
            "the .node file",
        )?;
        mesh.tets.push(tet);
        mesh.tet_labels.push(label);
        mesh.tet_lines.push(line);
    }
    let mut skipped = Skipped::default();
    if per_tet == 10 {
        skipped.add("second-order nodes of 10-node tetrahedra (corners kept)", n);
    }
    mesh.skipped = skipped.into_vec();
    Ok(mesh)
}

fn to_label(v: f64) -> Option<i32> {
    if v.fract() == 0.0 && v >= f64::from(i32::MIN) && v <= f64::from(i32::MAX) {
        Some(v as i32)
    } else {
        None
    }
}

/// Parses a `.face` file.
pub(crate) fn parse_face(
    path: &Path,
    data: &[u8],
    num_vertices: usize,
    base: u64,
) -> Result<Vec<[u32; 3]>, IoError> {
    let mut t = Tokens::new(path, data);
    let n = t.usize("the number of faces")?;
    let markers = header_field(&mut t, "the boundary-marker flag (0 or 1)", 0)?;
    if markers > 1 {
        return Err(t.error(format!(
            "expected boundary-marker flag 0 or 1, found {markers}"
        )));
    }
    let what = "a face: id and 3 vertex indices";
    let mut faces = Vec::with_capacity(t.capacity_hint(n, 8));
    for i in 0..n {
        let ctx = || format!("face {} of {n}", i + 1);
        let id = t.u64(what).map_err(|e| e.context(ctx))?;
        let mut raw = [0u64; 3];
        for r in &mut raw {
            *r = t.u64(what).map_err(|e| e.context(ctx))?;
        }
        let line = t.line();
        if markers == 1 {
            let m = t.expect("a boundary marker").map_err(|e| e.context(ctx))?;
            if crate::tokens::parse_i64(m).is_none() {
                return Err(t.unexpected("a boundary marker", m));
            }
        }
        faces.push(check::element(
            &t,
            line,
            raw,
            base,
            num_vertices,
            "face",
            id,
            "the .node file",
        )?);
    }
    if let Some(extra) = t.next() {
        return Err(t.error(format!(
            "expected end of file after {n} faces, found \"{}\"",
            show(extra)
        )));
    }
    Ok(faces)
}

/// Writes `foo.node`, `foo.ele` and (when there are boundary faces) `foo.face`.
pub(crate) fn write(path: &Path, mesh: &TetMeshData) -> Result<(), IoError> {
    let node = path.with_extension("node");
    let ele = path.with_extension("ele");
    let face = path.with_extension("face");
    atomic_write(&node, |w| {
        writeln!(w, "# written by perifrac-io: id x y z (0-based)")?;
        writeln!(w, "{} 3 0 0", mesh.vertices.len())?;
        for (i, p) in mesh.vertices.iter().enumerate() {
            write!(w, "{i} ")?;
            write_xyz(w, p)?;
            w.write_all(b"\n")?;
        }
        Ok(())
    })?;
    atomic_write(&ele, |w| {
        writeln!(
            w,
            "# written by perifrac-io: id v0 v1 v2 v3 label (0-based)"
        )?;
        writeln!(w, "{} 4 1", mesh.tets.len())?;
        for (i, (t, label)) in mesh.tets.iter().zip(&mesh.tet_labels).enumerate() {
            writeln!(w, "{i} {} {} {} {} {label}", t[0], t[1], t[2], t[3])?;
        }
        Ok(())
    })?;
    if mesh.boundary_faces.is_empty() {
        remove_stale(&face)
    } else {
        atomic_write(&face, |w| {
            writeln!(w, "{} 0", mesh.boundary_faces.len())?;
            for (i, f) in mesh.boundary_faces.iter().enumerate() {
                writeln!(w, "{i} {} {} {}", f[0], f[1], f[2])?;
            }
            Ok(())
        })
    }
}

fn remove_stale(face: &PathBuf) -> Result<(), IoError> {
    match std::fs::remove_file(face) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(IoError::io(face, e)),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_based_with_attributes_and_markers() {
        let node = b"# pts\n4 3 1 1\n1 0 0 0 9.5 1\n2 1 0 0 9.5 1\n\n3 0 1 0 9.5 0\n4 0 0 1 9.5 0 # last\n";
        let (pts, base) = parse_node(Path::new("a.node"), node).unwrap();
        assert_eq!((pts.len(), base), (4, 1));
        let ele = b"1 4 1\n1 1 2 3 4 -3\n";
        let m = parse_ele(Path::new("a.ele"), ele, 4, base).unwrap();
        assert_eq!(m.tets, vec![[0, 1, 2, 3]]);
        assert_eq!(m.tet_labels, vec![-3]);
    }

    #[test]
    fn out_of_range_names_node_count() {
        let ele = b"2 4 0\n0 0 1 2 3\n1 0 1 2 9001\n";
        let e = parse_ele(Path::new("a.ele"), ele, 5, 0)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("a.ele:3: vertex index 9001 out of range (the .node file has 5 vertices"),
            "{e}"
        );
    }

    #[test]
    fn repeated_index() {
        let ele = b"1 4 0\n0 0 1 1 3\n";
        let e = parse_ele(Path::new("a.ele"), ele, 5, 0)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("a.ele:2: tetrahedron 0 repeats vertex index 1"),
            "{e}"
        );
    }
}
