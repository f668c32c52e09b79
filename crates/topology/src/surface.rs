//! Extraction of the surface of every piece: rest boundary faces plus separated crack faces.

use crate::faces::{cross, dot, FACE_CORNERS};
use crate::mesh::{TetMesh, NO_TET};
use crate::pieces::Pieces;

/// A triangle surface in current positions, compacted to the vertices it uses.
///
/// Faces are outward oriented (counter-clockwise seen from outside). `crack[i]` is 1 for a crack
/// face and 0 for an original boundary face; `piece[i]` is the piece id of the face's tet (see
/// [`crate::Pieces`]); `vertex_ids[k]` is the mesh vertex id of compact vertex `k`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Surface {
    /// Positions of the compact vertices (length).
    pub vertices: Vec<[f64; 3]>,
    /// Mesh vertex id of each compact vertex.
    pub vertex_ids: Vec<u32>,
    /// Triangles as compact vertex indices, outward.
    pub faces: Vec<[u32; 3]>,
    /// 1 for a crack face, 0 for an original boundary face.
    pub crack: Vec<u8>,
    /// Piece id of each face's tet.
    pub piece: Vec<u32>,
}

impl Surface {
    /// Enclosed volume by the divergence theorem (length^3); positive for an outward surface.
    pub fn signed_volume(&self) -> f64 {
        self.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|k| self.vertices[k as usize]);
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    /// True when every directed edge `(a, b)` is matched by as many edges `(b, a)`.
    pub fn is_closed(&self) -> bool {
        let mut balance: hashbrown::HashMap<(u32, u32), i64> = hashbrown::HashMap::new();
        for f in &self.faces {
            for i in 0..3 {
                let (a, b) = (f[i], f[(i + 1) % 3]);
                let (key, d) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
                *balance.entry(key).or_insert(0) += d;
            }
        }
        balance.values().all(|&d| d == 0)
    }
}

impl TetMesh {
    /// The surface of all pieces together.
    pub fn surface(&self) -> Surface {
        self.surface_and_pieces().0
    }

    /// [`TetMesh::surface`] and [`TetMesh::pieces`] from one computation of the pieces.
    pub fn surface_and_pieces(&self) -> (Surface, Pieces) {
        let pieces = self.pieces();
        let mut map = vec![u32::MAX; self.pos.len()];
        let mut s = Surface::default();
        self.for_each_surface_face(|t, face, crack| {
            s.push(&mut map, &self.pos, face, crack, pieces.piece_of_tet[t]);
        });
        (s, pieces)
    }

    /// One surface per piece, indexed by piece id.
    pub fn piece_surfaces(&self) -> Vec<Surface> {
        let pieces = self.pieces();
        let mut faces = Vec::new();
        self.for_each_surface_face(|t, face, crack| {
            faces.push((pieces.piece_of_tet[t], face, crack));
        });
        // Group by piece (stable, so faces keep tet order within a piece), then compact each
        // piece on its own: before a split, one vertex id may still be used by two pieces.
        faces.sort_by_key(|f| f.0);
        let mut map = vec![u32::MAX; self.pos.len()];
        let mut out = vec![Surface::default(); pieces.count];
        let mut start = 0;
        while start < faces.len() {
            let p = faces[start].0;
            let end = start + faces[start..].iter().take_while(|f| f.0 == p).count();
            let s = &mut out[p as usize];
            for &(_, face, crack) in &faces[start..end] {
                s.push(&mut map, &self.pos, face, crack, p);
            }
            for &v in &s.vertex_ids {
                map[v as usize] = u32::MAX;
            }
            start = end;
        }
        out
    }

    /// Calls `emit(tet, outward vertex ids, crack flag)` for every surface face, in tet order.
    fn for_each_surface_face(&self, mut emit: impl FnMut(usize, [u32; 3], u8)) {
        for (t, tet) in self.tets.iter().enumerate() {
            for (f, corners) in FACE_CORNERS.iter().enumerate() {
                let face = corners.map(|k| tet[k]);
                let other = self.neighbours[t][f];
                if other == NO_TET {
                    emit(t, face, 0);
                } else if self.crack[t] & (1 << f) != 0 {
                    let o = &self.tets[other as usize];
                    if !face.iter().all(|v| o.contains(v)) {
                        emit(t, face, 1);
                    }
                }
            }
        }
    }
}

impl Surface {
    /// Appends a face, compacting its vertices through `map` (mesh id -> compact id).
    fn push(&mut self, map: &mut [u32], pos: &[[f64; 3]], face: [u32; 3], crack: u8, piece: u32) {
        let compact = face.map(|v| {
            let m = &mut map[v as usize];
            if *m == u32::MAX {
                *m = self.vertices.len() as u32;
                self.vertices.push(pos[v as usize]);
                self.vertex_ids.push(v);
            }
            *m
        });
        self.faces.push(compact);
        self.crack.push(crack);
        self.piece.push(piece);
    }
}
