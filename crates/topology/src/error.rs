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
    /// A primitive was asked for with an empty or non-finite extent, or one beyond
    /// [`crate::primitives::MAX_EXTENT`] from the origin.
    #[error("primitive extent {min:?}..{max:?} is empty, not finite or beyond 1e50 m")]
    BadExtent {
        /// Lower corner.
        min: [f64; 3],
        /// Upper corner.
        max: [f64; 3],
    },
    /// A box primitive has more cells than a mesh can index (or than `usize` counts).
    #[error(
        "{}x{}x{} cells are more than a mesh can index (at most 4294967294 tets and \
         4294967295 vertices: 32-bit ids; 6 tets per cell)",
        .cells[0], .cells[1], .cells[2]
    )]
    TooManyCells {
        /// The cell counts along x, y, z.
        cells: [usize; 3],
    },
    /// A box primitive's cells have a side outside [`crate::primitives::MIN_EXTENT`] ..
    /// [`crate::primitives::MAX_EXTENT`].
    #[error(
        "cells of {:e} x {:e} x {:e} m: every side must lie between 1e-50 and 1e50 m (tet \
         quality takes lengths to the sixth power, which must stay within f64's range)",
        .cell[0], .cell[1], .cell[2]
    )]
    CellOutOfRange {
        /// Cell sides along x, y, z (m).
        cell: [f64; 3],
    },
    /// A box primitive's cells are so flat that their tets would fail the degeneracy check.
    #[error(
        "cells of {:e} x {:e} x {:e} m are too flat: their tets' volume {volume:.3e} m^3 is not \
         above {tolerance:.3e} m^3 (a thousand times the degeneracy tolerance of 1e-12 * mean \
         edge^3); choose cell counts that make the cells closer to cubes",
        .cell[0], .cell[1], .cell[2]
    )]
    FlatCells {
        /// Cell sides along x, y, z (m).
        cell: [f64; 3],
        /// Volume of each tet (m^3).
        volume: f64,
        /// What it had to exceed (m^3).
        tolerance: f64,
    },
}

impl TopologyError {
    /// The tet (0-based, in the order given) a message about a file should point at: the one
    /// the error is about, or the latest of a pair or triple (the one that made the problem).
    pub fn tet(&self) -> Option<u32> {
        match *self {
            TopologyError::VertexOutOfRange { tet, .. }
            | TopologyError::RepeatedCorner { tet, .. }
            | TopologyError::Degenerate { tet, .. }
            | TopologyError::DuplicateTet { tet, .. }
            | TopologyError::FaceOutOfRange { tet, .. }
            | TopologyError::BoundaryFace { tet, .. } => Some(tet),
            TopologyError::NonManifoldFace { tets, .. } => tets.iter().max().copied(),
            _ => None,
        }
    }

    /// The message with tets and vertices numbered from 1 in the order given, which is the
    /// order a file lists them in (the readers count from 1 too).
    pub fn one_based(&self) -> String {
        let plus1 = |v: u32| u64::from(v) + 1;
        match self {
            TopologyError::NonFiniteVertex { vertex, coords } => format!(
                "vertex {} has a non-finite coordinate {coords:?}",
                plus1(*vertex)
            ),
            TopologyError::VertexOutOfRange {
                tet,
                vertex,
                num_vertices,
            } => format!(
                "tet {} refers to vertex {}, but there are only {num_vertices} vertices",
                plus1(*tet),
                plus1(*vertex)
            ),
            TopologyError::RepeatedCorner { tet, corners } => format!(
                "tet {} repeats a corner: {:?}; fix or remove it",
                plus1(*tet),
                corners.map(plus1)
            ),
            TopologyError::Degenerate {
                tet,
                volume,
                tolerance,
            } => format!(
                "tet {} has volume {volume:e} (below 1e-12 * mean edge^3 = {tolerance:e}); fix \
                 or remove it",
                plus1(*tet)
            ),
            TopologyError::NonManifoldFace { face, tets } => format!(
                "the face on vertices {:?} is shared by more than two tets: {:?}",
                face.map(plus1),
                tets.map(plus1)
            ),
            TopologyError::DuplicateTet { tet, other } => format!(
                "tets {} and {} have the same four corners; remove one",
                plus1(*other),
                plus1(*tet)
            ),
            other => other.to_string(),
        }
    }

    /// The [`TopologyError::one_based`] message for a mesh read from `file`, prefixed with
    /// `file:line:` when the error names a tet and `tet_lines` (1-based, one per tet, in the
    /// order given) has its line, `file:` otherwise.
    pub fn located(&self, file: &std::path::Path, tet_lines: &[usize]) -> String {
        let line = self.tet().and_then(|t| tet_lines.get(t as usize));
        match line {
            Some(line) => format!("{}:{line}: {}", file.display(), self.one_based()),
            None => format!("{}: {}", file.display(), self.one_based()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_based_messages_count_from_one() {
        let e = TopologyError::Degenerate {
            tet: 0,
            volume: 0.0,
            tolerance: 1e-12,
        };
        assert_eq!(e.tet(), Some(0));
        assert!(
            e.one_based().starts_with("tet 1 has volume 0e0"),
            "{}",
            e.one_based()
        );
        let e = TopologyError::NonManifoldFace {
            face: [0, 1, 2],
            tets: [4, 9, 7],
        };
        assert_eq!(e.tet(), Some(9));
        assert_eq!(
            e.one_based(),
            "the face on vertices [1, 2, 3] is shared by more than two tets: [5, 10, 8]"
        );
        let at = e.located(
            std::path::Path::new("m.mesh"),
            &[10, 11, 12, 13, 14, 15, 16, 17, 18, 19],
        );
        assert!(
            at.starts_with("m.mesh:19: the face on vertices [1, 2, 3]"),
            "{at}"
        );
        let at = e.located(std::path::Path::new("m.mesh"), &[]);
        assert!(at.starts_with("m.mesh: the face"), "{at}");
        assert_eq!(TopologyError::Empty.tet(), None);
        assert_eq!(TopologyError::Empty.one_based(), "the mesh has no tets");
    }
}
