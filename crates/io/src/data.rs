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

/// Borrowed surface for output: optional per-face crack flag (0/1) and fragment id, and
/// optional per-vertex RGB colour, normal, velocity, texture coordinates and id.
#[derive(Debug, Clone, Copy, Default)]
pub struct SurfaceRef<'a> {
    /// Vertex coordinates.
    pub vertices: &'a [[f64; 3]],
    /// Triangles as 0-based vertex indices.
    pub faces: &'a [[u32; 3]],
    /// Per face: 1 on a crack surface, 0 on the original boundary; same length as `faces`.
    pub crack: Option<&'a [u8]>,
    /// Per vertex colour; same length as `vertices`.
    pub colors: Option<&'a [[u8; 3]]>,
    /// Per vertex unit normal; same length as `vertices`.
    pub normals: Option<&'a [[f64; 3]]>,
    /// Per vertex velocity (length/time); same length as `vertices`.
    pub velocities: Option<&'a [[f64; 3]]>,
    /// Per vertex texture coordinates; same length as `vertices`.
    pub uv: Option<&'a [[f64; 2]]>,
    /// Per vertex id (the welded vertex a split shading vertex copies, so a reader can weld
    /// the copies back); same length as `vertices`.
    pub vertex_ids: Option<&'a [u32]>,
    /// Per face fragment id; same length as `faces`.
    pub fragment: Option<&'a [u32]>,
}

impl<'a> SurfaceRef<'a> {
    /// A surface with no crack flags and no colours.
    pub fn new(vertices: &'a [[f64; 3]], faces: &'a [[u32; 3]]) -> Self {
        SurfaceRef {
            vertices,
            faces,
            ..SurfaceRef::default()
        }
    }

    /// Checks array lengths and face indices before a writer starts.
    pub(crate) fn validate(&self, file: &std::path::Path) -> Result<(), crate::IoError> {
        let n = self.vertices.len();
        let m = self.faces.len();
        let lengths = [
            ("crack flags", self.crack.map(<[u8]>::len), m, "faces"),
            ("fragment ids", self.fragment.map(<[u32]>::len), m, "faces"),
            ("colours", self.colors.map(<[[u8; 3]]>::len), n, "vertices"),
            (
                "normals",
                self.normals.map(<[[f64; 3]]>::len),
                n,
                "vertices",
            ),
            (
                "velocities",
                self.velocities.map(<[[f64; 3]]>::len),
                n,
                "vertices",
            ),
            (
                "texture coordinates",
                self.uv.map(<[[f64; 2]]>::len),
                n,
                "vertices",
            ),
            (
                "vertex ids",
                self.vertex_ids.map(<[u32]>::len),
                n,
                "vertices",
            ),
        ];
        for (what, len, expected, of) in lengths {
            if let Some(len) = len.filter(|&l| l != expected) {
                return Err(crate::IoError::invalid(
                    file,
                    format!("{len} {what} for {expected} {of}"),
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
