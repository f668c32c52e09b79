//! Legacy VTK `.vtk` (ASCII `DATASET UNSTRUCTURED_GRID`): reader and writer.
//!
//! The reader keeps tetra cells (type 10) as tets and triangles (type 5) as boundary faces and
//! counts other cell types in `skipped`. Both the classic `CELLS n size` layout and the VTK 5.1
//! `OFFSETS`/`CONNECTIVITY` layout are read. The first integer `SCALARS` array of `CELL_DATA`
//! becomes the tet labels (0 without one); everything after `CELL_DATA` is otherwise ignored.
//! The writer produces version 3.0 with a `label` cell scalar, so labels round-trip.

use crate::check::{self, Skipped};
use crate::error::read_all;
use crate::numfmt::write_xyz;
use crate::tokens::{show, Tokens};
use crate::{atomic_write, IoError, TetMeshData};
use std::io::Write;
use std::path::Path;

const TETRA: u64 = 10;
const TRIANGLE: u64 = 5;

/// Cells as read: flat connectivity, `offsets[i]..offsets[i+1]` per cell, and each cell's line.
#[derive(Default)]
struct Cells {
    offsets: Vec<usize>,
    conn: Vec<u64>,
    lines: Vec<usize>,
}

/// Reads a `.vtk` file.
pub(crate) fn read(path: &Path) -> Result<TetMeshData, IoError> {
    parse(path, &read_all(path)?)
}

/// Parses the bytes of a `.vtk` file.
pub(crate) fn parse(path: &Path, data: &[u8]) -> Result<TetMeshData, IoError> {
    let mut t = Tokens::new(path, data);
    t.set_comments(false);
    let magic = t.rest_of_line();
    if !magic
        .to_ascii_lowercase()
        .starts_with(b"# vtk datafile version")
    {
        return Err(t.error_at(
            1,
            format!(
                "expected \"# vtk DataFile Version x.x\", found \"{}\"",
                show(magic)
            ),
        ));
    }
    t.rest_of_line(); // title
    let encoding = t.expect("ASCII or BINARY")?;
    if encoding.eq_ignore_ascii_case(b"BINARY") {
        return Err(IoError::Unsupported {
            file: path.to_path_buf(),
            what: "binary legacy VTK; save it as ASCII".into(),
        });
    }
    if !encoding.eq_ignore_ascii_case(b"ASCII") {
        return Err(t.unexpected("ASCII or BINARY", encoding));
    }
    let dataset = t.expect("DATASET UNSTRUCTURED_GRID")?;
    let kind = t.expect("DATASET UNSTRUCTURED_GRID")?;
    if !dataset.eq_ignore_ascii_case(b"DATASET") || !kind.eq_ignore_ascii_case(b"UNSTRUCTURED_GRID")
    {
        return Err(t.error(format!(
            "expected \"DATASET UNSTRUCTURED_GRID\", found \"{} {}\"",
            show(dataset),
            show(kind)
        )));
    }
    let mut points: Option<Vec<[f64; 3]>> = None;
    let mut cells: Option<Cells> = None;
    let mut types: Option<Vec<u64>> = None;
    let mut labels: Option<Vec<i64>> = None;
    while let Some(keyword) = t.next() {
        let upper = keyword.to_ascii_uppercase();
        match upper.as_slice() {
            b"POINTS" => points = Some(read_points(&mut t)?),
            b"CELLS" => {
                let Some(p) = &points else {
                    return Err(t.error("\"CELLS\" before \"POINTS\""));
                };
                cells = Some(read_cells(&mut t, p.len())?);
            }
            b"CELL_TYPES" => {
                let n = t.usize("the number of cell types")?;
                let mut v = Vec::with_capacity(t.capacity_hint(n, 2));
                for i in 0..n {
                    v.push(
                        t.u64("a cell type")
                            .map_err(|e| e.context(|| format!("cell {} of {n}", i + 1)))?,
                    );
                }
                types = Some(v);
            }
            b"CELL_DATA" => {
                labels = read_cell_labels(&mut t)?;
                break;
            }
            _ if points.is_some() && cells.is_some() && types.is_some() => break,
            _ => return Err(t.unexpected("POINTS, CELLS or CELL_TYPES", keyword)),
        }
    }
    let points = points.ok_or_else(|| t.eof_error("a POINTS section"))?;
    let cells = cells.ok_or_else(|| t.eof_error("a CELLS section"))?;
    let types = types.ok_or_else(|| t.eof_error("a CELL_TYPES section"))?;
    assemble(&t, points, cells, types, labels)
}

fn read_points(t: &mut Tokens) -> Result<Vec<[f64; 3]>, IoError> {
    let n = t.usize("the number of points")?;
    let ty = t.expect("the point data type")?;
    if !matches!(ty.to_ascii_lowercase().as_slice(), b"float" | b"double") {
        return Err(t.unexpected("point data type float or double", ty));
    }
    let mut pts = Vec::with_capacity(t.capacity_hint(n, 6));
    for i in 0..n {
        let mut p = [0.0; 3];
        for c in &mut p {
            *c = t
                .f64("coordinate")
                .map_err(|e| e.context(|| format!("point {} of {n}", i + 1)))?;
        }
        pts.push(p);
    }
    Ok(pts)
}

fn read_cells(t: &mut Tokens, num_points: usize) -> Result<Cells, IoError> {
    let n = t.usize("the number of cells")?;
    let size = t.usize("the size of the cell list")?;
    let mut cells = Cells::default();
    let index = |t: &mut Tokens, cells: &mut Cells| -> Result<(), IoError> {
        let v = t.u64("a point index")?;
        if v >= num_points as u64 {
            return Err(t.error(format!(
                "point index {v} out of range (the file has {num_points} points)"
            )));
        }
        cells.conn.push(v);
        Ok(())
    };
    if t.peek().is_some_and(|k| k.eq_ignore_ascii_case(b"OFFSETS")) {
        // VTK 5.1: CELLS <n offsets> <n connectivity>, OFFSETS <type>, CONNECTIVITY <type>.
        t.next();
        t.expect("the offset data type")?;
        let mut prev = 0usize;
        for _ in 0..n {
            let o = t.usize("an offset")?;
            if o < prev || o > size {
                return Err(t.error(format!("offset {o} is not between {prev} and {size}")));
            }
            cells.offsets.push(o);
            prev = o;
        }
        let keyword = t.expect("CONNECTIVITY")?;
        if !keyword.eq_ignore_ascii_case(b"CONNECTIVITY") {
            return Err(t.unexpected("CONNECTIVITY", keyword));
        }
        t.expect("the connectivity data type")?;
        let num_cells = cells.offsets.len().saturating_sub(1);
        for k in 0..size {
            index(t, &mut cells)?;
            // A cell's line is the line of its first connectivity value.
            while cells.lines.len() < num_cells
                && cells
                    .offsets
                    .get(cells.lines.len())
                    .is_some_and(|&o| o <= k)
            {
                cells.lines.push(t.line());
            }
        }
        cells.lines.resize(num_cells, t.line());
        if cells.offsets.first().is_some_and(|&o| o != 0) {
            return Err(t.error("the first offset must be 0"));
        }
        if cells.offsets.last().is_some_and(|&o| o != size) {
            return Err(t.error(format!(
                "the last offset must equal the connectivity size {size}"
            )));
        }
        return Ok(cells);
    }
    cells.offsets.push(0);
    let mut used = 0usize;
    for i in 0..n {
        let k = t
            .usize("the number of points of a cell")
            .map_err(|e| e.context(|| format!("cell {} of {n}", i + 1)))?;
        used = used.saturating_add(k.saturating_add(1));
        if used > size {
            return Err(t.error(format!(
                "cells use more than the {size} values announced by CELLS"
            )));
        }
        cells.lines.push(t.line());
        for _ in 0..k {
            index(t, &mut cells).map_err(|e| e.context(|| format!("cell {} of {n}", i + 1)))?;
        }
        cells.offsets.push(cells.conn.len());
    }
    if used != size {
        return Err(t.error(format!("cells use {used} values, CELLS announced {size}")));
    }
    Ok(cells)
}

/// Reads `CELL_DATA n` arrays; returns the first integer `SCALARS` array, if any.
fn read_cell_labels(t: &mut Tokens) -> Result<Option<Vec<i64>>, IoError> {
    let n = t.usize("the number of cell data values")?;
    while t.peek().is_some_and(|k| k.eq_ignore_ascii_case(b"SCALARS")) {
        t.next();
        t.expect("a scalar array name")?;
        let ty = t.expect("a scalar data type")?.to_ascii_lowercase();
        let comps = if t.more_on_line() {
            t.usize("the number of components")?
        } else {
            1
        };
        if t.peek()
            .is_some_and(|k| k.eq_ignore_ascii_case(b"LOOKUP_TABLE"))
        {
            t.next();
            t.expect("a lookup table name")?;
        }
        let integer = !matches!(ty.as_slice(), b"float" | b"double");
        let count = n.saturating_mul(comps);
        if integer && comps == 1 {
            let mut v = Vec::with_capacity(t.capacity_hint(n, 2));
            for _ in 0..n {
                v.push(t.i64("an integer cell value")?);
            }
            return Ok(Some(v));
        }
        for _ in 0..count {
            t.expect("a cell data value")?;
        }
    }
    Ok(None)
}

fn type_name(ty: u64) -> String {
    let name = match ty {
        1 => "vertex",
        3 => "line",
        5 => "triangle",
        7 => "polygon",
        9 => "quad",
        10 => "tetra",
        12 => "hexahedron",
        13 => "wedge",
        14 => "pyramid",
        24 => "quadratic tetra",
        _ => "other",
    };
    format!("vtk type {ty} ({name})")
}

fn assemble(
    t: &Tokens,
    points: Vec<[f64; 3]>,
    cells: Cells,
    types: Vec<u64>,
    labels: Option<Vec<i64>>,
) -> Result<TetMeshData, IoError> {
    let ncells = cells.lines.len();
    if types.len() != ncells {
        return Err(t.error(format!(
            "CELL_TYPES has {} entries for {ncells} cells",
            types.len()
        )));
    }
    if let Some(l) = &labels {
        if l.len() != ncells {
            return Err(t.error(format!(
                "CELL_DATA has {} values for {ncells} cells",
                l.len()
            )));
        }
    }
    let mut mesh = TetMeshData {
        vertices: points,
        ..TetMeshData::default()
    };
    let mut skipped = Skipped::default();
    let n = mesh.vertices.len();
    for (i, &ty) in types.iter().enumerate() {
        let (start, end) = match (cells.offsets.get(i), cells.offsets.get(i + 1)) {
            (Some(&s), Some(&e)) => (s, e),
            _ => return Err(t.error("internal: cell offsets shorter than the cell count")),
        };
        let ids = cells.conn.get(start..end).unwrap_or(&[]);
        let line = cells.lines.get(i).copied().unwrap_or(0);
        let wrong = |k: usize| {
            t.error_at(
                line,
                format!(
                    "cell {i} has type {ty} but {} points, expected {k}",
                    ids.len()
                ),
            )
        };
        match ty {
            TETRA => {
                let raw: [u64; 4] = ids.try_into().map_err(|_| wrong(4))?;
                mesh.tets.push(check::element(
                    t, line, raw, 0, n, "cell", i as u64, "the file",
                )?);
                let label = labels.as_ref().and_then(|l| l.get(i)).copied().unwrap_or(0);
                let label = i32::try_from(label).map_err(|_| {
                    t.error(format!("cell label {label} does not fit a 32-bit label"))
                })?;
                mesh.tet_labels.push(label);
                mesh.tet_lines.push(line);
            }
            TRIANGLE => {
                let raw: [u64; 3] = ids.try_into().map_err(|_| wrong(3))?;
                mesh.boundary_faces.push(check::element(
                    t, line, raw, 0, n, "cell", i as u64, "the file",
                )?);
            }
            _ => skipped.add(&type_name(ty), 1),
        }
    }
    mesh.skipped = skipped.into_vec();
    Ok(mesh)
}

/// Writes `mesh` as legacy VTK 3.0 ASCII with a `label` cell scalar.
pub(crate) fn write(path: &Path, mesh: &TetMeshData) -> Result<(), IoError> {
    atomic_write(path, |w| {
        w.write_all(
            b"# vtk DataFile Version 3.0\nperifrac tet mesh\nASCII\nDATASET UNSTRUCTURED_GRID\n",
        )?;
        writeln!(w, "POINTS {} double", mesh.vertices.len())?;
        for p in &mesh.vertices {
            write_xyz(w, p)?;
            w.write_all(b"\n")?;
        }
        let (nf, nt) = (mesh.boundary_faces.len(), mesh.tets.len());
        writeln!(w, "CELLS {} {}", nf + nt, 4 * nf + 5 * nt)?;
        for f in &mesh.boundary_faces {
            writeln!(w, "3 {} {} {}", f[0], f[1], f[2])?;
        }
        for t in &mesh.tets {
            writeln!(w, "4 {} {} {} {}", t[0], t[1], t[2], t[3])?;
        }
        writeln!(w, "CELL_TYPES {}", nf + nt)?;
        for _ in 0..nf {
            w.write_all(b"5\n")?;
        }
        for _ in 0..nt {
            w.write_all(b"10\n")?;
        }
        writeln!(
            w,
            "CELL_DATA {}\nSCALARS label int 1\nLOOKUP_TABLE default",
            nf + nt
        )?;
        for _ in 0..nf {
            w.write_all(b"0\n")?;
        }
        for label in &mesh.tet_labels {
            writeln!(w, "{label}")?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vtk51_offsets_layout_and_wrapped_points() {
        let src = b"# vtk DataFile Version 5.1\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 0 1\n0 0 0 1\n\
CELLS 3 6\nOFFSETS vtktypeint64\n0 4 6\nCONNECTIVITY vtktypeint64\n0 1 2 3\n0 1\nCELL_TYPES 2\n10\n3\n";
        let m = parse(Path::new("a.vtk"), src).unwrap();
        assert_eq!(m.tets, vec![[0, 1, 2, 3]]);
        assert_eq!(m.tet_labels, vec![0]);
        assert_eq!(m.skipped, vec![("vtk type 3 (line)".to_string(), 1)]);
    }
}
