//! Fragment ids that stay: a fragment keeps its id from the frame it separates to the end of
//! the run. Pieces only ever split (a crack face is never removed), so each piece of a frame
//! lies inside one fragment of the frame before: a fragment that is still whole keeps its id,
//! and the pieces a fragment split into all get new ids, recorded with it as their parent.

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_topology::Pieces;
use serde::{Deserialize, Serialize};

/// Where a fragment came from, in `run.json`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FragmentBirth {
    /// The fragment's id.
    pub id: u32,
    /// The fragment it split from (`None` for the fragments of the first frame).
    pub parent: Option<u32>,
    /// The first frame it appears in.
    pub frame: usize,
}

/// The stable fragment ids of a run, updated frame by frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FragmentIds {
    /// The fragment id of each tet (or shell triangle) at the last frame.
    id_of_tet: Vec<u32>,
    /// Every fragment so far, in id order.
    births: Vec<FragmentBirth>,
}

impl FragmentIds {
    /// The ids of the pieces of frame `frame` (`ids[piece]`), updating the record. The first
    /// call numbers the pieces as they are.
    pub fn update(&mut self, pieces: &Pieces, frame: usize) -> Vec<u32> {
        if self.id_of_tet.len() != pieces.piece_of_tet.len() {
            // First frame (or a mesh of another size): pieces as they are.
            self.births.clear();
        }
        self.update_split(&pieces.piece_of_tet, pieces.count, frame, &|t| t)
    }

    /// [`FragmentIds::update`] for a body whose elements split and append the new ones (a
    /// shell's triangles): `piece_of[e]` is element `e`'s piece (of `count`), `earlier(e)` the
    /// element of the last update that `e` was part of (`e` itself for one that existed then).
    /// The first call numbers the pieces as they are.
    pub fn update_split(
        &mut self,
        piece_of: &[u32],
        count: usize,
        frame: usize,
        earlier: &dyn Fn(usize) -> usize,
    ) -> Vec<u32> {
        if self.births.is_empty() {
            self.births = (0..count as u32)
                .map(|id| FragmentBirth {
                    id,
                    parent: None,
                    frame,
                })
                .collect();
            self.id_of_tet = piece_of.to_vec();
            return (0..count as u32).collect();
        }
        // The earlier fragment of each piece (that of its lowest element) and how many pieces
        // each earlier fragment now holds.
        let mut previous = vec![u32::MAX; count];
        let mut parts = vec![0u32; self.births.len()];
        for (t, &p) in piece_of.iter().enumerate() {
            let slot = &mut previous[p as usize];
            if *slot == u32::MAX {
                *slot = self.id_of_tet[earlier(t)];
                parts[*slot as usize] += 1;
            }
        }
        let ids: Vec<u32> = previous
            .iter()
            .map(|&old| {
                if parts[old as usize] == 1 {
                    old
                } else {
                    let id = self.births.len() as u32;
                    self.births.push(FragmentBirth {
                        id,
                        parent: Some(old),
                        frame,
                    });
                    id
                }
            })
            .collect();
        self.id_of_tet = piece_of.iter().map(|&p| ids[p as usize]).collect();
        ids
    }

    /// Every fragment so far, in id order.
    pub fn births(&self) -> &[FragmentBirth] {
        &self.births
    }

    /// Writes the ids for a checkpoint.
    pub fn save(&self, w: &mut Writer) {
        w.tag("fragment ids");
        w.array(&self.id_of_tet);
        let parents: Vec<u32> = self
            .births
            .iter()
            .map(|b| b.parent.unwrap_or(u32::MAX))
            .collect();
        let frames: Vec<u64> = self.births.iter().map(|b| b.frame as u64).collect();
        w.array(&parents);
        w.array(&frames);
    }

    /// Reads what [`FragmentIds::save`] wrote, for a mesh of `tets` tets.
    pub fn restore(&mut self, r: &mut Reader, tets: usize) -> Result<(), CheckpointError> {
        r.tag("fragment ids")?;
        let (mut id_of_tet, mut parents, mut frames) = (Vec::new(), Vec::new(), Vec::<u64>::new());
        r.array_vec("fragment id of each tet", &mut id_of_tet)?;
        r.array_vec("fragment parents", &mut parents)?;
        r.array_vec("fragment frames", &mut frames)?;
        let invalid = |message: String| CheckpointError::Invalid {
            what: "fragment ids".into(),
            message,
        };
        let count = parents.len();
        if !id_of_tet.is_empty() && id_of_tet.len() != tets {
            return Err(invalid(format!(
                "{} tets recorded, the mesh has {tets}",
                id_of_tet.len()
            )));
        }
        if frames.len() != count {
            return Err(invalid(format!("{count} parents, {} frames", frames.len())));
        }
        if let Some(&bad) = id_of_tet.iter().find(|&&i| i as usize >= count) {
            return Err(invalid(format!("tet fragment {bad} of {count}")));
        }
        let mut births = Vec::with_capacity(count);
        for (id, (&parent, &frame)) in parents.iter().zip(&frames).enumerate() {
            if parent != u32::MAX && parent as usize >= id {
                return Err(invalid(format!(
                    "fragment {id} has a later parent {parent}"
                )));
            }
            births.push(FragmentBirth {
                id: id as u32,
                parent: (parent != u32::MAX).then_some(parent),
                frame: usize::try_from(frame).map_err(|_| invalid(format!("frame {frame}")))?,
            });
        }
        self.id_of_tet = id_of_tet;
        self.births = births;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pieces(piece_of_tet: &[u32]) -> Pieces {
        Pieces {
            count: piece_of_tet.iter().max().map_or(0, |&m| m as usize + 1),
            piece_of_tet: piece_of_tet.to_vec(),
        }
    }

    #[test]
    fn whole_fragments_keep_their_ids_and_split_ones_get_new() {
        let mut ids = FragmentIds::default();
        // Frame 0: two pieces {0, 1, 2, 3} and {4, 5}.
        assert_eq!(ids.update(&pieces(&[0, 0, 0, 0, 1, 1]), 0), vec![0, 1]);
        // Frame 1: the first splits into {0, 1} and {2, 3}; numbering of pieces is by lowest
        // tet, so piece 2 is {4, 5}, which keeps id 1.
        assert_eq!(ids.update(&pieces(&[0, 0, 1, 1, 2, 2]), 1), vec![2, 3, 1]);
        // Frame 2: nothing changes: the same ids.
        assert_eq!(ids.update(&pieces(&[0, 0, 1, 1, 2, 2]), 2), vec![2, 3, 1]);
        // Frame 3: {4, 5} splits; {0, 1} and {2, 3} keep theirs.
        assert_eq!(
            ids.update(&pieces(&[0, 0, 1, 1, 2, 3]), 3),
            vec![2, 3, 4, 5]
        );
        let b = ids.births();
        assert_eq!(b.len(), 6);
        assert_eq!((b[2].parent, b[2].frame), (Some(0), 1));
        assert_eq!((b[3].parent, b[3].frame), (Some(0), 1));
        assert_eq!((b[4].parent, b[4].frame), (Some(1), 3));
        assert_eq!((b[5].parent, b[5].frame), (Some(1), 3));
        assert!(b[..2].iter().all(|f| f.parent.is_none() && f.frame == 0));
    }

    #[test]
    fn split_off_elements_take_the_fragment_they_were_part_of() {
        let mut ids = FragmentIds::default();
        // Frame 0: triangles {0, 1} and {2}.
        assert_eq!(ids.update_split(&[0, 0, 1], 2, 0, &|t| t), vec![0, 1]);
        // Frame 1: triangle 1 split off triangle 3 and triangle 3 triangle 4 (4 -> 3 -> 1);
        // fragment 0 came apart into {0, 1, 3} and {4}, both new; {2} keeps its id.
        let from = [0usize, 1, 2, 1, 3];
        let earlier = |t: usize| {
            let mut t = t;
            while t >= 3 {
                t = from[t];
            }
            t
        };
        assert_eq!(
            ids.update_split(&[0, 0, 1, 0, 2], 3, 1, &earlier),
            vec![2, 1, 3]
        );
        let b = ids.births();
        assert_eq!((b[2].parent, b[3].parent), (Some(0), Some(0)));
        // Frame 2: nothing new: the same ids, element by element.
        assert_eq!(
            ids.update_split(&[0, 0, 1, 0, 2], 3, 2, &|t| t),
            vec![2, 1, 3]
        );
    }

    #[test]
    fn a_checkpoint_round_trip_keeps_the_ids() {
        let mut ids = FragmentIds::default();
        ids.update(&pieces(&[0, 0, 0, 1]), 0);
        ids.update(&pieces(&[0, 1, 1, 2]), 1);
        let mut w = Writer::new();
        ids.save(&mut w);
        let mut back = FragmentIds::default();
        back.restore(&mut Reader::new(w.bytes()), 4).unwrap();
        assert_eq!(back, ids);
        // The next frame numbers the same way in both.
        let next = pieces(&[0, 1, 2, 3]);
        assert_eq!(back.update(&next, 2), ids.update(&next, 2));
        // A mesh of another size is refused.
        let mut other = FragmentIds::default();
        assert!(other.restore(&mut Reader::new(w.bytes()), 5).is_err());
    }
}
