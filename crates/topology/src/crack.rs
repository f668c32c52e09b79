//! The crack face set: marking faces between face-adjacent tets as cracked.

use crate::error::TopologyError;
use crate::faces::FACE_CORNERS;
use crate::mesh::{TetMesh, NO_TET};

impl TetMesh {
    /// Whether local face `f` of tet `t` is cracked. False for out-of-range arguments.
    pub fn is_cracked(&self, t: u32, f: u8) -> bool {
        f < 4
            && self
                .crack
                .get(t as usize)
                .is_some_and(|bits| bits & (1 << f) != 0)
    }

    /// Marks local face `f` of tet `t` as cracked, on both sides, and queues its three vertices
    /// for the next [`TetMesh::split`]. Returns `Ok(false)` if the face was already cracked.
    ///
    /// Errors: `t` or `f` out of range, or the face is on the rest boundary.
    pub fn crack_face(&mut self, t: u32, f: u8) -> Result<bool, TopologyError> {
        let num_tets = self.tets.len();
        if t as usize >= num_tets {
            return Err(TopologyError::TetOutOfRange { tet: t, num_tets });
        }
        if f >= 4 {
            return Err(TopologyError::FaceOutOfRange { tet: t, face: f });
        }
        let other = self.neighbours[t as usize][f as usize];
        if other == NO_TET {
            return Err(TopologyError::BoundaryFace { tet: t, face: f });
        }
        if self.is_cracked(t, f) {
            return Ok(false);
        }
        self.crack[t as usize] |= 1 << f;
        if let Some(g) = self.face_towards(other, t) {
            self.crack[other as usize] |= 1 << g;
        }
        for k in FACE_CORNERS[f as usize] {
            let v = self.tets[t as usize][k];
            self.scratch.queue_vertex(v);
        }
        Ok(true)
    }

    /// Cracks the shared face of every face-adjacent pair among `bonds` (broken particle bonds
    /// `(i, j)`); pairs that share no face, or are out of range, are ignored. Returns the number
    /// of crack faces added.
    pub fn crack_bonds(&mut self, bonds: &[(u32, u32)]) -> usize {
        let mut added = 0;
        for &(i, j) in bonds {
            let Some(f) = self.face_towards(i, j) else {
                continue;
            };
            if let Ok(true) = self.crack_face(i, f) {
                added += 1;
            }
        }
        added
    }

    /// Local face of tet `t` across which lies tet `other`, if they are face-adjacent.
    #[inline]
    pub(crate) fn face_towards(&self, t: u32, other: u32) -> Option<u8> {
        if other == NO_TET {
            return None;
        }
        let nb = self.neighbours.get(t as usize)?;
        nb.iter().position(|&n| n == other).map(|f| f as u8)
    }
}
