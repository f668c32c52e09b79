//! The mesh's part of a checkpoint: what cracks and advection change (current positions,
//! vertex copies, tet corners, crack bits); the rest mesh and its adjacency come from the
//! setup.

use perifrac_checkpoint::{expect_count, CheckpointError, Reader, Writer};

use crate::mesh::TetMesh;
use crate::split::SplitScratch;

impl TetMesh {
    /// Writes the current positions, the vertex copies with their rest vertices, the tets'
    /// corners and the crack bits.
    pub fn save(&self, w: &mut Writer) {
        w.tag("mesh");
        w.array(&self.pos);
        w.array(&self.origin);
        w.array(&self.tets);
        w.array(&self.crack);
    }

    /// Reads what [`TetMesh::save`] wrote into a mesh built from the same rest mesh, checking
    /// that every copy belongs to a rest vertex and every tet still has its rest corners.
    pub fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("mesh")?;
        let mut pos = Vec::new();
        let mut origin = Vec::new();
        r.array_vec("vertex positions", &mut pos)?;
        r.array_vec("vertex origins", &mut origin)?;
        expect_count("vertex origins", pos.len(), origin.len())?;
        let invalid = |what: &str, message: String| CheckpointError::Invalid {
            what: what.into(),
            message,
        };
        let rest = self.rest.len();
        if pos.len() < rest {
            return Err(invalid(
                "vertex positions",
                format!(
                    "{} vertices, fewer than the {rest} rest vertices",
                    pos.len()
                ),
            ));
        }
        if let Some(&o) = origin.iter().find(|&&o| o as usize >= rest) {
            return Err(invalid(
                "vertex origins",
                format!("rest vertex {o} of {rest}"),
            ));
        }
        let mut tets = vec![[0u32; 4]; self.tets.len()];
        r.array_into("tets", &mut tets)?;
        for (t, (now, was)) in tets.iter().zip(&self.tets).enumerate() {
            for (&v, &w) in now.iter().zip(was) {
                let same = origin
                    .get(v as usize)
                    .is_some_and(|&o| o == self.origin[w as usize]);
                if !same {
                    return Err(invalid(
                        "tets",
                        format!("tet {t} has corner {v}, not a copy of its rest corner"),
                    ));
                }
            }
        }
        r.array_into("crack bits", &mut self.crack)?;
        if let Some(b) = self.crack.iter().find(|&&b| b > 0b1111) {
            return Err(invalid("crack bits", format!("{b:#b} names a fifth face")));
        }
        // the split buffers hold one flag per vertex copy (and nothing pending between steps)
        self.scratch = SplitScratch::new(pos.len());
        self.pos = pos;
        self.origin = origin;
        self.tets = tets;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::box_data;

    fn cut_box() -> TetMesh {
        let (v, t) = box_data([0.0; 3], [1.0; 3], [3, 2, 2]);
        let mut m = TetMesh::new(v, t).unwrap().0;
        // crack every face between the tets of the lower and the upper half
        let mut pairs = Vec::new();
        for (a, n) in m.neighbours().iter().enumerate() {
            for &b in n {
                if b != crate::NO_TET && (a as u32) < b && (a % 2 != b as usize % 2) {
                    pairs.push((a as u32, b));
                }
            }
        }
        m.crack_bonds(&pairs);
        m.split();
        for p in m.positions_mut() {
            p[2] += 0.25 * p[0];
        }
        m
    }

    #[test]
    fn a_restored_mesh_is_the_saved_one() {
        let cut = cut_box();
        assert!(
            cut.num_vertices() > cut.num_rest_vertices(),
            "the cut made copies"
        );
        let mut w = Writer::new();
        cut.save(&mut w);
        let (v, t) = box_data([0.0; 3], [1.0; 3], [3, 2, 2]);
        let mut fresh = TetMesh::new(v, t).unwrap().0;
        let mut r = Reader::new(w.bytes());
        fresh.restore(&mut r).unwrap();
        r.finish().unwrap();
        assert_eq!(fresh.positions(), cut.positions());
        assert_eq!(fresh.vertex_origin(), cut.vertex_origin());
        assert_eq!(fresh.tets(), cut.tets());
        assert_eq!(fresh.surface().faces, cut.surface().faces);
        assert_eq!(fresh.pieces().count, cut.pieces().count);
        // and it goes on cracking as the saved one would
        let mut a = cut.clone();
        let mut b = fresh;
        let pairs: Vec<(u32, u32)> = (0..a.num_tets() as u32)
            .flat_map(|t| a.neighbours()[t as usize].map(|n| (t, n)))
            .filter(|&(t, n)| n != crate::NO_TET && t < n)
            .collect();
        for m in [&mut a, &mut b] {
            m.crack_bonds(&pairs);
            m.split();
        }
        assert_eq!(a.tets(), b.tets());
        assert_eq!(a.num_vertices(), b.num_vertices());
    }

    #[test]
    fn a_mesh_of_another_shape_is_refused() {
        let mut w = Writer::new();
        cut_box().save(&mut w);
        let (v, t) = box_data([0.0; 3], [1.0; 3], [2, 3, 2]);
        let mut other = TetMesh::new(v, t).unwrap().0;
        let e = other.restore(&mut Reader::new(w.bytes())).unwrap_err();
        assert!(e.to_string().starts_with("tets"), "{e}");
    }
}
