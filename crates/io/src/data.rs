//! The plain data exchanged with the rest of perifrac.

/// A tetrahedral mesh as read from / written to a file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TetMeshData {
    /// Vertex coordinates.
    pub vertices: Vec<[f64; 3]>,
    /// Tets as 0-based vertex indices.
    pub tets: Vec<[u32; 4]>,
    /// Per tet region label (Medit ref, Gmsh physical tag (2.2) or entity tag (4.1), TetGen
    /// attribute, VTK integer cell scalar); same length as `tets`; 0 when the file has none.
    pub tet_labels: Vec<i32>,
    /// Triangles the file itself lists (TetGen .face, Medit Triangles, Gmsh/VTK triangles);
    /// may be empty.
    pub boundary_faces: Vec<[u32; 3]>,
    /// Element kinds counted and skipped, e.g. `("gmsh type 1 (line)", 1200)`.
    pub skipped: Vec<(String, usize)>,
    /// The 1-based line each tet was read from (same length as `tets`), so that a problem found
    /// after reading (a flat tet, a face shared by three tets) can point at its line; empty for
    /// a mesh that did not come from a file. Writers ignore it.
    pub tet_lines: Vec<usize>,
}

/// A triangle surface; polygons from OBJ/PLY/OFF are fan-triangulated.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceData {
    /// Vertex coordinates.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as 0-based vertex indices.
    pub faces: Vec<[u32; 3]>,
}

/// Borrowed surface for output: optional per-face crack flag (0/1) and per-vertex RGB colour.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceRef<'a> {
    /// Vertex coordinates.
    pub vertices: &'a [[f64; 3]],
    /// Triangles as 0-based vertex indices.
    pub faces: &'a [[u32; 3]],
    /// Per face: 1 on a crack surface, 0 on the original boundary; same length as `faces`.
    pub crack: Option<&'a [u8]>,
    /// Per vertex colour; same length as `vertices`.
    pub colors: Option<&'a [[u8; 3]]>,
}

impl<'a> SurfaceRef<'a> {
    /// A surface with no crack flags and no colours.
    pub fn new(vertices: &'a [[f64; 3]], faces: &'a [[u32; 3]]) -> Self {
        SurfaceRef {
            vertices,
            faces,
            crack: None,
            colors: None,
        }
    }

    /// Checks array lengths and face indices before a writer starts.
    pub(crate) fn validate(&self, file: &std::path::Path) -> Result<(), crate::IoError> {
        let n = self.vertices.len();
        if let Some(c) = self.crack {
            if c.len() != self.faces.len() {
                return Err(crate::IoError::invalid(
                    file,
                    format!("{} crack flags for {} faces", c.len(), self.faces.len()),
                ));
            }
        }
        if let Some(c) = self.colors {
            if c.len() != n {
                return Err(crate::IoError::invalid(
                    file,
                    format!("{} colours for {n} vertices", c.len()),
                ));
            }
        }
        if let Some(f) = self
            .faces
            .iter()
            .position(|f| f.iter().any(|&i| i as usize >= n))
        {
            return Err(crate::IoError::invalid(
                file,
                format!("face {f} has a vertex index out of range ({n} vertices)"),
            ));
        }
        Ok(())
    }
}
