//! What every reader target does with a mesh that loads: builds its topology and everything
//! downstream, which must give an answer or an error, never a panic.

use perifrac_io::TetMeshData;
use perifrac_topology::TetMesh;

/// Builds the topology of a loaded tet mesh and queries it.
pub fn exercise_tet_mesh(data: TetMeshData) {
    if let Ok((mesh, _report)) = TetMesh::new(data.vertices, data.tets) {
        let _ = mesh.quality();
        let _ = mesh.surface();
        let _ = mesh.pieces();
    }
}
