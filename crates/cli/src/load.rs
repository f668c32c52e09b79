//! Loading a tet mesh file into a validated topology mesh, keeping what the file said.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
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

/// Surface extensions: files that hold triangles, not tets.
pub const SURFACE_EXTENSIONS: [&str; 3] = ["obj", "off", "ply"];

/// Refuses a path that is a directory or a surface file with a message saying so (and, for a
/// surface, how to make a tet mesh of it), before a tet reader is tried.
pub fn check_tet_mesh_path(path: &Path) -> Result<()> {
    if path.is_dir() {
        bail!("{} is a directory, not a mesh file", path.display());
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if SURFACE_EXTENSIONS.contains(&ext.as_str()) {
        let stem = path.with_extension("mesh");
        bail!(
            "{} is a surface mesh (triangles), not a tet mesh; make a tet mesh of it with \
             `perifrac mesh {} -o {}`",
            path.display(),
            path.display(),
            stem.display()
        );
    }
    Ok(())
}

/// Reads `path` (format by extension) and validates it as a tet mesh. A problem the
/// validation finds names the file and the tet's line, tets and vertices counted from 1.
pub fn load_tet_mesh(path: &Path) -> Result<Loaded> {
    check_tet_mesh_path(path)?;
    let data = perifrac_io::read_tet_mesh(path)?;
    let TetMeshData {
        vertices,
        tets,
        tet_labels,
        boundary_faces,
        skipped,
        tet_lines,
    } = data;
    let (mesh, report) = TetMesh::new(vertices, tets)
        .map_err(|e| anyhow!(e.located(&perifrac_io::tet_lines_file(path), &tet_lines)))?;
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
        tet_lines: Vec::new(),
    }
}
