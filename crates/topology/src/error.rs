//! Typed errors of the topology crate; every message names the offending tet or vertex.

use thiserror::Error;

/// What can go wrong when building or cutting a tet mesh.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TopologyError {
    /// The mesh has no tets at all.
    #[error("the mesh has no tets")]
    Empty,
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate {coords:?}")]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: u32,
        /// Its coordinates as given.
        coords: [f64; 3],
    },
    /// A tet refers to a vertex index past the end of the vertex list.
    #[error("tet {tet} refers to vertex {vertex}, but there are only {num_vertices} vertices")]
    VertexOutOfRange {
        /// Index of the tet.
        tet: u32,
        /// The offending vertex index.
        vertex: u32,
        /// Number of vertices given.
        num_vertices: usize,
    },
    /// A tet uses the same vertex at two corners.
    #[error("tet {tet} repeats a corner: {corners:?}; fix or remove it")]
    RepeatedCorner {
        /// Index of the tet.
        tet: u32,
        /// Its four corners as given.
        corners: [u32; 4],
    },
    /// A tet is flat (or nearly so).
    #[error(
        "tet {tet} has volume {volume:e} (below 1e-12 * mean edge^3 = {tolerance:e}); fix or remove it"
    )]
    Degenerate {
        /// Index of the tet.
        tet: u32,
        /// Its signed volume (length^3).
        volume: f64,
        /// The tolerance it failed (length^3).
        tolerance: f64,
    },
    /// Three or more tets share one triangular face.
    #[error("face {face:?} is shared by more than two tets: {tets:?}")]
    NonManifoldFace {
        /// The face's vertex ids, sorted.
        face: [u32; 3],
        /// The tets found on it so far (at least three).
        tets: [u32; 3],
    },
    /// Two tets share all four corners.
    #[error("tets {tet} and {other} have the same four corners; remove one")]
    DuplicateTet {
        /// The later of the two tets.
        tet: u32,
        /// The earlier one.
        other: u32,
    },
    /// A tet index past the end of the tet list.
    #[error("tet {tet} is out of range (the mesh has {num_tets} tets)")]
    TetOutOfRange {
        /// The offending tet index.
        tet: u32,
        /// Number of tets.
        num_tets: usize,
    },
    /// A local face index other than 0..4.
    #[error("local face {face} of tet {tet} is out of range (0..4)")]
    FaceOutOfRange {
        /// Index of the tet.
        tet: u32,
        /// The offending local face.
        face: u8,
    },
    /// Cracking was asked for a face on the mesh boundary.
    #[error("local face {face} of tet {tet} is on the boundary and cannot be cracked")]
    BoundaryFace {
        /// Index of the tet.
        tet: u32,
        /// The local face.
        face: u8,
    },
    /// A primitive was asked for with an empty or non-finite extent.
    #[error("primitive extent {min:?}..{max:?} is empty or not finite")]
    BadExtent {
        /// Lower corner.
        min: [f64; 3],
        /// Upper corner.
        max: [f64; 3],
    },
}
