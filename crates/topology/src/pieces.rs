//! Pieces (fragments): connected components of tets through uncracked faces.

use crate::mesh::{TetMesh, NO_TET};

/// The fragments of a mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pieces {
    /// Number of pieces.
    pub count: usize,
    /// Piece id of each tet, `0..count`, numbered in order of each piece's lowest tet.
    pub piece_of_tet: Vec<u32>,
}

impl TetMesh {
    /// Connected components of tets joined through uncracked faces.
    pub fn pieces(&self) -> Pieces {
        let n = self.tets.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        for (t, nb) in self.neighbours.iter().enumerate() {
            for (f, &o) in nb.iter().enumerate() {
                if o != NO_TET && (o as usize) > t && self.crack[t] & (1 << f) == 0 {
                    let (a, b) = (find(&mut parent, t as u32), find(&mut parent, o));
                    if a != b {
                        // Keep the lower root so roots are the lowest tet of their set.
                        parent[a.max(b) as usize] = a.min(b);
                    }
                }
            }
        }
        let mut piece_of_tet = vec![0u32; n];
        let mut count = 0u32;
        for t in 0..n {
            let root = find(&mut parent, t as u32) as usize;
            piece_of_tet[t] = if root == t {
                count += 1;
                count - 1
            } else {
                piece_of_tet[root]
            };
        }
        Pieces {
            count: count as usize,
            piece_of_tet,
        }
    }
}

/// Root of `x` with path halving.
fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[x as usize];
        parent[x as usize] = parent[p as usize];
        x = parent[x as usize];
    }
    x
}
