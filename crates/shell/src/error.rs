//! Typed errors of the shell crate.

use thiserror::Error;

/// What can be wrong with a shell's mesh, material or settings.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ShellError {
    /// The mesh has no triangle.
    #[error("the surface has no triangles")]
    Empty,
    /// A vertex position is NaN or infinite.
    #[error("vertex {vertex}: position {position:?} is not finite")]
    NonFiniteVertex {
        /// Vertex index.
        vertex: usize,
        /// Its position (m).
        position: [f64; 3],
    },
    /// A triangle names a vertex that does not exist, or one vertex twice.
    #[error("triangle {face}: vertices {vertices:?} must be three distinct indices below {count}")]
    BadTriangle {
        /// Triangle index.
        face: usize,
        /// Its vertex indices.
        vertices: [u32; 3],
        /// Number of vertices.
        count: usize,
    },
    /// A triangle has (nearly) no area.
    #[error("triangle {face}: degenerate (area {area:.3e} m^2 against {reference:.3e} m^2 for its longest edge)")]
    Degenerate {
        /// Triangle index.
        face: usize,
        /// Its area (m^2).
        area: f64,
        /// The area of an equilateral triangle on its longest edge (m^2).
        reference: f64,
    },
    /// More than two triangles share an edge.
    #[error("edge {a}-{b} is shared by {count} triangles (at most 2: the surface is not a 2-manifold), triangles {faces:?}")]
    NonManifoldEdge {
        /// Lower vertex index.
        a: u32,
        /// Higher vertex index.
        b: u32,
        /// Triangles using it.
        count: usize,
        /// Up to three of them.
        faces: Vec<usize>,
    },
    /// Two triangles traverse their shared edge in the same direction.
    #[error("triangles {first} and {second} are oriented inconsistently across edge {a}-{b} (flip one so their normals agree)")]
    Orientation {
        /// One triangle.
        first: usize,
        /// The other.
        second: usize,
        /// Edge's first vertex.
        a: u32,
        /// Edge's second vertex.
        b: u32,
    },
    /// The triangles around a vertex form more than one fan (two sheets touching at a point).
    #[error(
        "vertex {vertex}: its triangles form {fans} separate fans (the surface is pinched there)"
    )]
    NonManifoldVertex {
        /// Vertex index.
        vertex: usize,
        /// Number of fans.
        fans: usize,
    },
    /// A vertex belongs to no triangle (it would have no mass).
    #[error("vertex {vertex} belongs to no triangle")]
    Unused {
        /// Vertex index.
        vertex: usize,
    },
    /// Two adjacent triangles are folded onto each other at rest (dihedral angle of 180 degrees).
    #[error("edge {a}-{b}: its two triangles are folded flat onto each other at rest (dihedral angle {angle_deg:.1} deg); bending is not defined there")]
    Folded {
        /// Edge's first vertex.
        a: u32,
        /// Edge's second vertex.
        b: u32,
        /// Rest dihedral angle (deg).
        angle_deg: f64,
    },
    /// A material constant or setting is out of range.
    #[error("{what} must be {expected}, got {value}")]
    BadSetting {
        /// Which constant.
        what: &'static str,
        /// What it must be.
        expected: &'static str,
        /// What was given.
        value: f64,
    },
    /// The stable-step estimate found no finite positive frequency (a shell with no stiffness).
    #[error("the shell's highest frequency came out as {omega} rad/s: no stable step can be set")]
    NoFrequency {
        /// What the estimate gave (rad/s).
        omega: f64,
    },
    /// Contact with the colliders was refused (a vertex starts inside one, say).
    #[error("shell contact: {0}")]
    Contact(String),
    /// The energy became infinite or NaN: the step is too long for the mesh (after fracture
    /// made it finer, say).
    #[error("the shell ran away at t = {time:.6e} s (the time step is too long for its mesh)")]
    RanAway {
        /// Simulated time (s).
        time: f64,
    },
    /// The implicit step's matrix could not be factored (it is singular: a free vertex with
    /// no mass, say).
    #[error("the implicit shell step's matrix: {0}")]
    Factorization(String),
    /// Arrays that must match the vertex count do not.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
}

/// [`ShellError::BadSetting`] as an `Err`, for the settings' checks.
pub(crate) fn bad_setting<T>(
    what: &'static str,
    expected: &'static str,
    value: f64,
) -> Result<T, ShellError> {
    Err(ShellError::BadSetting {
        what,
        expected,
        value,
    })
}
