//! Loading a tet mesh file into a validated topology mesh, keeping what the file said.

use std::path::Path;

use anyhow::{Context, Result};
use perifrac_io::TetMeshData;
use perifrac_topology::{BuildReport, TetMesh};

/// A tet mesh file read and validated: the topology mesh plus the file's own extras.
pub struct Loaded {
    /// The validated mesh (inverted tets already reoriented).
    pub mesh: TetMesh,
    /// What validation changed.
    pub report: BuildReport,
    /// Per-tet region labels from the file.
    pub tet_labels: Vec<i32>,
    /// Boundary triangles the file listed itself (may be empty).
    pub boundary_faces: Vec<[u32; 3]>,
    /// Element kinds the reader skipped, with counts.
    pub skipped: Vec<(String, usize)>,
}

/// Reads `path` (format by extension) and validates it as a tet mesh.
pub fn load_tet_mesh(path: &Path) -> Result<Loaded> {
    let data = perifrac_io::read_tet_mesh(path)?;
    let TetMeshData {
        vertices,
        tets,
        tet_labels,
        boundary_faces,
        skipped,
    } = data;
    let (mesh, report) = TetMesh::new(vertices, tets)
        .with_context(|| format!("{} is not a valid tet mesh", path.display()))?;
    Ok(Loaded {
        mesh,
        report,
        tet_labels,
        boundary_faces,
        skipped,
    })
}

/// The mesh as plain file data again (current vertices, reoriented tets, labels, faces).
pub fn to_data(mesh: &TetMesh, tet_labels: Vec<i32>, boundary_faces: Vec<[u32; 3]>) -> TetMeshData {
    TetMeshData {
        vertices: mesh.positions().to_vec(),
        tets: mesh.tets().to_vec(),
        tet_labels,
        boundary_faces,
        skipped: Vec::new(),
    }
}
