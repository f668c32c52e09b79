//! Multi-way vertex splitting along crack faces (docs/model.md section 3).

use crate::mesh::{vec_bytes, TetMesh, NO_TET};

/// Label of a star entry not yet reached by the grouping walk.
const UNSET: u32 = u32::MAX;

/// What one [`TetMesh::split`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SplitReport {
    /// Vertices that fell into two or more groups.
    pub vertices_split: usize,
    /// New vertex copies created (groups beyond the first, summed over split vertices).
    pub copies_added: usize,
}

/// Buffers owned by the mesh so that splitting allocates nothing in steady state.
#[derive(Debug, Clone, Default)]
pub(crate) struct SplitScratch {
    /// Vertices touched by crack faces since the last split, each once.
    pending: Vec<u32>,
    /// `queued[v]` is true while `v` is in `pending`; one entry per vertex copy.
    queued: Vec<bool>,
    /// Tets currently using the vertex being split (ascending) ...
    star: Vec<u32>,
    /// ... and the local corner at which each uses it.
    corner: Vec<u8>,
    /// Group of each star entry.
    label: Vec<u32>,
    /// Walk stack of star entries.
    stack: Vec<u32>,
}

impl SplitScratch {
    pub(crate) fn new(num_vertices: usize) -> Self {
        SplitScratch {
            queued: vec![false; num_vertices],
            ..Default::default()
        }
    }

    /// Queues vertex `v` for the next split, once.
    #[inline]
    pub(crate) fn queue_vertex(&mut self, v: u32) {
        let q = &mut self.queued[v as usize];
        if !*q {
            *q = true;
            self.pending.push(v);
        }
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        let Self {
            pending,
            queued,
            star,
            corner,
            label,
            stack,
        } = self;
        vec_bytes(pending)
            + vec_bytes(queued)
            + vec_bytes(star)
            + vec_bytes(corner)
            + vec_bytes(label)
            + vec_bytes(stack)
    }
}

impl TetMesh {
    /// Splits every vertex touched by crack faces added since the last split.
    ///
    /// For each such vertex, the tets using it are grouped (two join when they share an uncracked
    /// face containing the vertex); `k` groups give `k - 1` new copies at the same rest and current
    /// position, and the tets of every group but the one holding the lowest tet index are rewired
    /// to their copy. Cost is proportional to the stars of the touched vertices; the only
    /// allocation in steady state is growth of the vertex arrays.
    pub fn split(&mut self) -> SplitReport {
        let mut report = SplitReport::default();
        let mut pending = std::mem::take(&mut self.scratch.pending);
        for &v in &pending {
            self.scratch.queued[v as usize] = false;
            let groups = self.split_vertex(v);
            if groups > 1 {
                report.vertices_split += 1;
                report.copies_added += groups - 1;
            }
        }
        pending.clear();
        self.scratch.pending = pending;
        report
    }

    /// Groups the tets using `v` and rewires all groups but the first; returns the group count.
    fn split_vertex(&mut self, v: u32) -> usize {
        let r = self.origin[v as usize] as usize;
        let s = &mut self.scratch;
        s.star.clear();
        s.corner.clear();
        for &t in &self.star_tets[self.star_offsets[r]..self.star_offsets[r + 1]] {
            if let Some(k) = self.tets[t as usize].iter().position(|&w| w == v) {
                s.star.push(t);
                s.corner.push(k as u8);
            }
        }
        s.label.clear();
        s.label.resize(s.star.len(), UNSET);
        let mut groups = 0u32;
        for start in 0..s.star.len() {
            if s.label[start] != UNSET {
                continue;
            }
            s.label[start] = groups;
            s.stack.clear();
            s.stack.push(start as u32);
            while let Some(i) = s.stack.pop() {
                let (t, k) = (s.star[i as usize] as usize, s.corner[i as usize] as usize);
                for f in 0..4 {
                    // Faces containing corner k are the three faces other than face k.
                    let n = self.neighbours[t][f];
                    if f == k || n == NO_TET || self.crack[t] & (1 << f) != 0 {
                        continue;
                    }
                    if let Ok(j) = s.star.binary_search(&n) {
                        if s.label[j] == UNSET {
                            s.label[j] = groups;
                            s.stack.push(j as u32);
                        }
                    }
                }
            }
            groups += 1;
        }
        if groups > 1 {
            let first_copy = self.pos.len() as u32;
            let p = self.pos[v as usize];
            for _ in 1..groups {
                self.pos.push(p);
                self.origin.push(r as u32);
                s.queued.push(false);
            }
            for (i, &g) in s.label.iter().enumerate() {
                if g > 0 {
                    let t = s.star[i] as usize;
                    self.tets[t][s.corner[i] as usize] = first_copy + g - 1;
                }
            }
        }
        groups as usize
    }
}
