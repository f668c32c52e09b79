//! Helpers shared by the integration tests.
#![allow(dead_code)]

use perifrac_io::TetMeshData;
use std::path::PathBuf;

/// `/work/shared/data/meshes`, reached from `crates/io` as the brief describes; `None` (with a
/// printed note) when the data set is not present.
pub fn mesh_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("SKIPPED: {} not found", dir.display());
        None
    }
}

/// Two tets sharing a face, with awkward coordinates, labels and boundary faces.
pub fn small_mesh() -> TetMeshData {
    TetMeshData {
        vertices: vec![
            [0.1, 1e-300, -123456.789],
            [1.0 / 3.0, 0.0, -0.0],
            [2.0 / 3.0, 1e300, 5e-324],
            [-1.5, 0.2 + 0.1, 7.0],
            [123456789.12345679, -1e-7, 1e16],
        ],
        tets: vec![[0, 1, 2, 3], [4, 2, 1, 3]],
        tet_labels: vec![3, 7],
        boundary_faces: vec![[0, 1, 2], [4, 2, 3]],
        skipped: vec![],
        tet_lines: vec![],
    }
}

/// Asserts two meshes are identical, coordinates bit for bit.
pub fn assert_same(a: &TetMeshData, b: &TetMeshData, what: &str) {
    assert_eq!(a.vertices.len(), b.vertices.len(), "{what}: vertex count");
    for (i, (p, q)) in a.vertices.iter().zip(&b.vertices).enumerate() {
        for k in 0..3 {
            assert_eq!(
                p[k].to_bits(),
                q[k].to_bits(),
                "{what}: vertex {i} coord {k}: {p:?} vs {q:?}"
            );
        }
    }
    assert_eq!(a.tets, b.tets, "{what}: tets");
    assert_eq!(a.tet_labels, b.tet_labels, "{what}: labels");
    assert_eq!(a.boundary_faces, b.boundary_faces, "{what}: boundary faces");
}
