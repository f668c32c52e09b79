//! The tet mesh: rest state, current state, adjacency, crack bits, and read accessors.

use crate::faces::{signed_volume, EDGES};
use crate::split::SplitScratch;

/// Marks "no tet across this face" in [`TetMesh::neighbours`].
pub const NO_TET: u32 = u32::MAX;

/// A tetrahedral mesh that peridynamic particles are embedded in (tet index == particle index).
///
/// Vertices come in two layers: *rest vertices* (the input) and *vertex copies* made when cracks
/// split a vertex. Every copy remembers its rest vertex ([`TetMesh::vertex_origin`]); a fresh mesh
/// has exactly one copy per rest vertex, with equal ids. Faces are identified by
/// `(tet, local face)` (see [`crate::faces`]), never by vertex ids, so the adjacency built once
/// from the rest mesh stays valid after any number of splits.
#[derive(Debug, Clone)]
pub struct TetMesh {
    /// Rest position of each rest vertex (length).
    pub(crate) rest: Vec<[f64; 3]>,
    /// Current position of each vertex copy (length).
    pub(crate) pos: Vec<[f64; 3]>,
    /// Rest vertex of each vertex copy.
    pub(crate) origin: Vec<u32>,
    /// Corners of each tet as current vertex ids, positively oriented.
    pub(crate) tets: Vec<[u32; 4]>,
    /// Tet across each local face, or [`NO_TET`].
    pub(crate) neighbours: Vec<[u32; 4]>,
    /// Bit `f` set when local face `f` of the tet is cracked.
    pub(crate) crack: Vec<u8>,
    /// CSR offsets of the rest-vertex star (`star_offsets[r]..star_offsets[r + 1]`).
    pub(crate) star_offsets: Vec<usize>,
    /// Tets around each rest vertex, ascending within a vertex.
    pub(crate) star_tets: Vec<u32>,
    /// Mean length of the distinct rest edges (length).
    pub(crate) mean_edge: f64,
    /// Number of rest boundary faces.
    pub(crate) boundary_faces: usize,
    /// Buffers reused by `crack_face` / `split`.
    pub(crate) scratch: SplitScratch,
    /// Per-vertex accumulators reused by `advect` / `place_from_particles`: sum of weighted
    /// vector (3) and sum of weights (1).
    pub(crate) accum: Vec<[f64; 4]>,
}

/// What [`TetMesh::new`] repaired in its input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BuildReport {
    /// Tets given with negative orientation and reoriented by swapping two corners.
    pub inverted_fixed: usize,
}

impl TetMesh {
    /// Number of vertices now, vertex copies included.
    pub fn num_vertices(&self) -> usize {
        self.pos.len()
    }

    /// Number of rest (input) vertices.
    pub fn num_rest_vertices(&self) -> usize {
        self.rest.len()
    }

    /// Number of tets (== number of particles).
    pub fn num_tets(&self) -> usize {
        self.tets.len()
    }

    /// Corners of every tet as current vertex ids, positively oriented.
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }

    /// Tet across each local face (face `f` is opposite corner `f`), or [`NO_TET`].
    pub fn neighbours(&self) -> &[[u32; 4]] {
        &self.neighbours
    }

    /// Rest positions, one per rest vertex (length).
    pub fn rest_positions(&self) -> &[[f64; 3]] {
        &self.rest
    }

    /// Current positions, one per vertex copy (length).
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.pos
    }

    /// Current positions for the caller to move (length).
    pub fn positions_mut(&mut self) -> &mut [[f64; 3]] {
        &mut self.pos
    }

    /// The rest vertex each vertex copy was made from.
    pub fn vertex_origin(&self) -> &[u32] {
        &self.origin
    }

    /// Rest corner positions of tet `t`.
    #[inline]
    pub(crate) fn rest_corners(&self, t: usize) -> [[f64; 3]; 4] {
        self.tets[t].map(|v| self.rest[self.origin[v as usize] as usize])
    }

    /// Current corner positions of tet `t`.
    #[inline]
    pub(crate) fn current_corners(&self, t: usize) -> [[f64; 3]; 4] {
        self.tets[t].map(|v| self.pos[v as usize])
    }

    /// Rest volume of tet `t` (length^3, positive). Panics if `t` is out of range.
    pub fn tet_rest_volume(&self, t: usize) -> f64 {
        let [a, b, c, d] = self.rest_corners(t);
        signed_volume(a, b, c, d)
    }

    /// Rest volume of every tet (length^3), i.e. the particle volumes.
    pub fn rest_volumes(&self) -> Vec<f64> {
        (0..self.tets.len())
            .map(|t| self.tet_rest_volume(t))
            .collect()
    }

    /// Sum of the rest volumes (length^3).
    pub fn total_rest_volume(&self) -> f64 {
        (0..self.tets.len()).map(|t| self.tet_rest_volume(t)).sum()
    }

    /// Rest barycentre of every tet (length), i.e. the particle rest positions.
    pub fn rest_barycentres(&self) -> Vec<[f64; 3]> {
        (0..self.tets.len())
            .map(|t| {
                let c = self.rest_corners(t);
                let mut b = [0.0; 3];
                for p in c {
                    for i in 0..3 {
                        b[i] += 0.25 * p[i];
                    }
                }
                b
            })
            .collect()
    }

    /// Mean length of the distinct rest edges (length): the `lambda` of docs/model.md section 1.
    pub fn mean_edge_length(&self) -> f64 {
        self.mean_edge
    }

    /// Number of faces on the rest mesh boundary.
    pub fn boundary_face_count(&self) -> usize {
        self.boundary_faces
    }

    /// Heap bytes held by the mesh, scratch buffers included (capacities, not lengths).
    pub fn memory_bytes(&self) -> usize {
        let Self {
            rest,
            pos,
            origin,
            tets,
            neighbours,
            crack,
            star_offsets,
            star_tets,
            mean_edge: _,
            boundary_faces: _,
            scratch,
            accum,
        } = self;
        vec_bytes(rest)
            + vec_bytes(pos)
            + vec_bytes(origin)
            + vec_bytes(tets)
            + vec_bytes(neighbours)
            + vec_bytes(crack)
            + vec_bytes(star_offsets)
            + vec_bytes(star_tets)
            + scratch.memory_bytes()
            + vec_bytes(accum)
    }
}

/// Heap bytes of a vector's allocation.
pub(crate) fn vec_bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * std::mem::size_of::<T>()
}

/// Mean length of the distinct edges of `tets` over `positions` (length); 0 for no tets.
pub(crate) fn mean_distinct_edge(positions: &[[f64; 3]], tets: &[[u32; 4]]) -> f64 {
    let mut seen = hashbrown::HashSet::with_capacity(tets.len() * 2);
    let mut sum = 0.0;
    for tet in tets {
        for [i, j] in EDGES {
            let (a, b) = (tet[i].min(tet[j]), tet[i].max(tet[j]));
            if seen.insert((a, b)) {
                sum += crate::faces::norm(crate::faces::sub(
                    positions[b as usize],
                    positions[a as usize],
                ));
            }
        }
    }
    if seen.is_empty() {
        0.0
    } else {
        sum / seen.len() as f64
    }
}
