//! Gmsh `.msh` writers, ASCII 2.2 and 4.1.
//!
//! 2.2: tets are type 4 with tags `label label` (physical, elementary); boundary faces are
//! type 2 with tags `0 0`. 4.1: every distinct label is a volume entity whose tag is the label
//! (Gmsh itself expects positive tags), tets are written in blocks of consecutive equal labels
//! so their order is kept, and boundary faces go in surface entity 1. Node tags are 1-based.

use crate::numfmt::write_xyz;
use crate::{atomic_write, IoError, TetMeshData};
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Writes Gmsh 2.2 ASCII.
pub(crate) fn write_v22(path: &Path, mesh: &TetMeshData) -> Result<(), IoError> {
    atomic_write(path, |w| {
        w.write_all(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n")?;
        writeln!(w, "$Nodes\n{}", mesh.vertices.len())?;
        for (i, p) in mesh.vertices.iter().enumerate() {
            write!(w, "{} ", i + 1)?;
            write_xyz(w, p)?;
            w.write_all(b"\n")?;
        }
        w.write_all(b"$EndNodes\n")?;
        let total = mesh.boundary_faces.len() + mesh.tets.len();
        writeln!(w, "$Elements\n{total}")?;
        let mut id = 0usize;
        for f in &mesh.boundary_faces {
            id += 1;
            writeln!(w, "{id} 2 2 0 0 {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
        }
        for (t, label) in mesh.tets.iter().zip(&mesh.tet_labels) {
            id += 1;
            writeln!(
                w,
                "{id} 4 2 {label} {label} {} {} {} {}",
                t[0] + 1,
                t[1] + 1,
                t[2] + 1,
                t[3] + 1
            )?;
        }
        w.write_all(b"$EndElements\n")
    })
}

/// Writes Gmsh 4.1 ASCII.
pub(crate) fn write_v41(path: &Path, mesh: &TetMeshData) -> Result<(), IoError> {
    let mut labels: Vec<i32> = mesh.tet_labels.clone();
    labels.sort_unstable();
    labels.dedup();
    let runs = label_runs(&mesh.tet_labels);
    atomic_write(path, |w| {
        w.write_all(b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")?;
        entities(w, mesh, &labels)?;
        let n = mesh.vertices.len();
        let node_entity = labels.first().copied().unwrap_or(1);
        w.write_all(b"$Nodes\n")?;
        if n == 0 {
            w.write_all(b"0 0 0 0\n")?;
        } else {
            writeln!(w, "1 {n} 1 {n}\n3 {node_entity} 0 {n}")?;
            for i in 1..=n {
                writeln!(w, "{i}")?;
            }
            for p in &mesh.vertices {
                write_xyz(w, p)?;
                w.write_all(b"\n")?;
            }
        }
        w.write_all(b"$EndNodes\n")?;
        let faces = mesh.boundary_faces.len();
        let total = faces + mesh.tets.len();
        let blocks = runs.len() + usize::from(faces > 0);
        writeln!(w, "$Elements\n{blocks} {total} {} {total}", total.min(1))?;
        let mut id = 0usize;
        if faces > 0 {
            writeln!(w, "2 1 2 {faces}")?;
            for f in &mesh.boundary_faces {
                id += 1;
                writeln!(w, "{id} {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
            }
        }
        for &(start, end) in &runs {
            let label = mesh.tet_labels.get(start).copied().unwrap_or(0);
            writeln!(w, "3 {label} 4 {}", end - start)?;
            for t in mesh.tets.get(start..end).unwrap_or(&[]) {
                id += 1;
                writeln!(
                    w,
                    "{id} {} {} {} {}",
                    t[0] + 1,
                    t[1] + 1,
                    t[2] + 1,
                    t[3] + 1
                )?;
            }
        }
        w.write_all(b"$EndElements\n")
    })
}

/// `[start, end)` ranges of consecutive equal labels.
fn label_runs(labels: &[i32]) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut start = 0;
    for i in 1..=labels.len() {
        if i == labels.len() || labels.get(i) != labels.get(start) {
            runs.push((start, i));
            start = i;
        }
    }
    runs
}

/// `$Entities`: surface 1 when there are boundary faces, one volume per label; each entity
/// gets the whole mesh's bounding box.
fn entities<W: Write>(w: &mut BufWriter<W>, mesh: &TetMeshData, labels: &[i32]) -> io::Result<()> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &mesh.vertices {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if mesh.vertices.is_empty() {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    let surfaces = usize::from(!mesh.boundary_faces.is_empty());
    writeln!(w, "$Entities\n0 0 {surfaces} {}", labels.len())?;
    let bbox = |w: &mut BufWriter<W>| -> io::Result<()> {
        write_xyz(w, &lo)?;
        w.write_all(b" ")?;
        write_xyz(w, &hi)
    };
    if surfaces == 1 {
        w.write_all(b"1 ")?;
        bbox(w)?;
        w.write_all(b" 0 0\n")?;
    }
    for label in labels {
        write!(w, "{label} ")?;
        bbox(w)?;
        w.write_all(b" 0 0\n")?;
    }
    w.write_all(b"$EndEntities\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs() {
        assert_eq!(label_runs(&[]), vec![]);
        assert_eq!(label_runs(&[1, 1, 2, 1]), vec![(0, 2), (2, 3), (3, 4)]);
    }
}
