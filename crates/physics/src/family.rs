//! Families (MODEL.md section 1): a breadth-first walk over the tet face graph bounded by the
//! horizon ball, symmetrised, stored as CSR bonds.

use crate::error::PhysicsError;
use crate::math::{norm, norm_squared, sub, Vec3};
use rayon::prelude::*;

/// Marker for "no neighbour across this face" in face adjacency tables.
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// Bonds in compressed-row form, one entry per direction: the bonds of particle `i` are
/// `offsets[i]..offsets[i + 1]`, sorted by neighbour index.
#[derive(Debug, Clone, PartialEq)]
pub struct Family {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
    rest_lengths: Vec<f64>,
}

/// What the family build found, for the caller to report.
#[derive(Debug, Clone, PartialEq)]
pub struct FamilyReport {
    /// Directed bonds stored (twice the number of pairs).
    pub bonds: usize,
    /// Directed bonds added because only the walk from the other end found the pair.
    pub added_by_symmetry: usize,
    /// Particles with no bond at all (they move ballistically): a warning, not an error.
    pub isolated: Vec<u32>,
    /// Fewest and most bonds of any particle.
    pub min_bonds: usize,
    /// Most bonds of any particle.
    pub max_bonds: usize,
}

impl Family {
    /// Builds the families of `positions` (rest barycentres, m) with horizon `horizon` (m), walking
    /// the face adjacency `adjacency` (entry `f` of tet `t` is the tet across the face opposite
    /// local vertex `f`, or [`NO_NEIGHBOUR`]). Inputs are assumed validated by the caller.
    pub(crate) fn build(
        positions: &[Vec3],
        adjacency: &[[u32; 4]],
        horizon: f64,
    ) -> Result<(Family, FamilyReport), PhysicsError> {
        let n = positions.len();
        let rows = walk_all(positions, adjacency, horizon);
        // Symmetrise: a pair found by one walk only is added to the other row.
        let rows_ref = &rows;
        let mut extra: Vec<(u32, u32)> = rows
            .par_iter()
            .enumerate()
            .flat_map_iter(|(i, row)| {
                row.iter().filter_map(move |&j| {
                    let back = &rows_ref[j as usize];
                    match back.binary_search(&(i as u32)) {
                        Ok(_) => None,
                        Err(_) => Some((j, i as u32)),
                    }
                })
            })
            .collect();
        extra.par_sort_unstable();
        let total: usize = rows.iter().map(Vec::len).sum::<usize>() + extra.len();
        if total > u32::MAX as usize {
            return Err(PhysicsError::TooManyBonds(total));
        }
        if total == 0 && n > 0 {
            return Err(PhysicsError::HorizonTooSmall { horizon });
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut neighbours = Vec::with_capacity(total);
        offsets.push(0u32);
        let mut e = 0;
        for (i, row) in rows.iter().enumerate() {
            let start = neighbours.len();
            neighbours.extend_from_slice(row);
            while e < extra.len() && extra[e].0 as usize == i {
                neighbours.push(extra[e].1);
                e += 1;
            }
            neighbours[start..].sort_unstable();
            offsets.push(neighbours.len() as u32);
        }
        drop(rows);
        let mut rest_lengths = vec![0.0; total];
        rest_lengths
            .par_chunks_mut(4096)
            .enumerate()
            .for_each(|(c, chunk)| {
                let first = c * 4096;
                // find the owning particle of bond `first` by binary search on offsets
                let mut i = offsets.partition_point(|&o| o as usize <= first) - 1;
                for (k, r) in chunk.iter_mut().enumerate() {
                    let b = first + k;
                    while offsets[i + 1] as usize <= b {
                        i += 1;
                    }
                    let j = neighbours[b] as usize;
                    *r = norm(sub(positions[j], positions[i]));
                }
            });
        let counts = offsets.windows(2).map(|w| (w[1] - w[0]) as usize);
        let isolated: Vec<u32> = counts
            .clone()
            .enumerate()
            .filter(|&(_, c)| c == 0)
            .map(|(i, _)| i as u32)
            .collect();
        let report = FamilyReport {
            bonds: total,
            added_by_symmetry: extra.len(),
            isolated,
            min_bonds: counts.clone().min().unwrap_or(0),
            max_bonds: counts.max().unwrap_or(0),
        };
        Ok((
            Family {
                offsets,
                neighbours,
                rest_lengths,
            },
            report,
        ))
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of directed bonds.
    pub fn num_bonds(&self) -> usize {
        self.neighbours.len()
    }

    /// Row offsets, `len() + 1` entries.
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }

    /// Neighbour particle of each directed bond.
    pub fn neighbours(&self) -> &[u32] {
        &self.neighbours
    }

    /// Rest length `r = |X_j - X_i|` of each directed bond, m.
    pub fn rest_lengths(&self) -> &[f64] {
        &self.rest_lengths
    }

    /// Bond range of particle `i`.
    #[inline(always)]
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// Neighbours of particle `i`.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.neighbours[self.range(i)]
    }

    /// For each directed bond `i -> j`, the index of the bond `j -> i`.
    pub fn reverse_index(&self) -> Vec<u32> {
        let mut rev = vec![0u32; self.num_bonds()];
        self.for_each_reverse(|k, r| rev[k] = r as u32);
        rev
    }

    /// Calls `f(k, r)` for every directed bond `k` (`i -> j`), in bond order, with the index
    /// `r` of its reverse (`j -> i`), storing no index. Rows are sorted by neighbour, so
    /// walking the particles in order meets the entries equal to `i` of each row `j` in that
    /// row's own order: a cursor per row finds every reverse bond in one pass.
    pub fn for_each_reverse(&self, mut f: impl FnMut(usize, usize)) {
        let mut cursor: Vec<u32> = self.offsets[..self.len()].to_vec();
        for i in 0..self.len() {
            for k in self.range(i) {
                let j = self.neighbours[k] as usize;
                debug_assert_eq!(self.neighbours[cursor[j] as usize] as usize, i);
                f(k, cursor[j] as usize);
                cursor[j] += 1;
            }
        }
    }

    /// Heap bytes used by the bond arrays.
    pub fn memory_bytes(&self) -> usize {
        let Family {
            offsets,
            neighbours,
            rest_lengths,
        } = self;
        offsets.len() * 4 + neighbours.len() * 4 + rest_lengths.len() * 8
    }
}

/// One breadth-first walk per particle; each row sorted.
fn walk_all(positions: &[Vec3], adjacency: &[[u32; 4]], horizon: f64) -> Vec<Vec<u32>> {
    let n = positions.len();
    let h2 = horizon * horizon;
    (0..n)
        .into_par_iter()
        .with_min_len(256)
        .map_init(
            || (vec![u32::MAX; n], Vec::<u32>::new()),
            |(stamp, queue), i| {
                let xi = positions[i];
                let mut row = Vec::new();
                queue.clear();
                queue.push(i as u32);
                stamp[i] = i as u32;
                let mut head = 0;
                while head < queue.len() {
                    let t = queue[head] as usize;
                    head += 1;
                    for &u in &adjacency[t] {
                        if u == NO_NEIGHBOUR || stamp[u as usize] == i as u32 {
                            continue;
                        }
                        stamp[u as usize] = i as u32;
                        if norm_squared(sub(positions[u as usize], xi)) < h2 {
                            queue.push(u);
                            row.push(u);
                        }
                    }
                }
                row.sort_unstable();
                row
            },
        )
        .collect()
}
