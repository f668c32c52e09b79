//! Families (docs/model.md section 1): a breadth-first walk over the tet face graph bounded by the
//! horizon ball, symmetrised, stored as CSR bonds.

use crate::error::PhysicsError;
use crate::math::{norm_squared, sub, Vec3};
use crate::par::for_each_row;
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
        let (walk_off, walk_nb, (below, above, hash)) = walk_all(positions, adjacency, horizon)?;
        let row = |i: usize| &walk_nb[walk_off[i] as usize..walk_off[i + 1] as usize];
        // Each pair found by both walks is named twice, once from each end; one found by a
        // single walk, once. So the rows name as many pairs below their own index as above
        // when the walks agree, and a hash of each pair (ends in order) cancels out of the
        // rows' exclusive-or: both hold unless the walks differ, for a set of pairs whose
        // hashes happen to cancel (one chance in 2^64 for a hash spread as `pair_hash`'s, and
        // never for a single pair, which the counts catch). Each walk reads both off its row
        // while the row is at hand ([`row_check`]); only when they fail is every pair searched
        // for from its other end.
        // Symmetrise: a pair found by one walk only is added to the other row.
        let mut extra: Vec<(u32, u32)> = if below == above && hash == 0 {
            Vec::new()
        } else {
            // j is the p-th nearest index of i's row: i sits about as far from the end of j's
            // (neighbourhoods alike, indices spatially ordered), searched from there
            let found_back = |i: usize, p: usize, j: u32| {
                let back = row(j as usize);
                contains_near(back, i as u32, back.len().saturating_sub(p + 1))
            };
            (0..n)
                .into_par_iter()
                .flat_map_iter(|i| {
                    let r = row(i);
                    (0..r.len())
                        .filter_map(move |p| (!found_back(i, p, r[p])).then_some((r[p], i as u32)))
                })
                .collect()
        };
        extra.par_sort_unstable();
        let total = walk_nb.len() + extra.len();
        if total > u32::MAX as usize {
            return Err(PhysicsError::TooManyBonds(total));
        }
        if total == 0 && n > 0 {
            return Err(PhysicsError::HorizonTooSmall { horizon });
        }
        let (offsets, neighbours) = if extra.is_empty() {
            (walk_off, walk_nb)
        } else {
            // every row's walk, then the pairs only the other end found, sorted in
            let mut extra_from = vec![0usize; n + 1];
            for &(i, _) in &extra {
                extra_from[i as usize + 1] += 1;
            }
            let mut offsets = Vec::with_capacity(n + 1);
            offsets.push(0u32);
            for i in 0..n {
                extra_from[i + 1] += extra_from[i];
                let len = row(i).len() + extra_from[i + 1] - extra_from[i];
                offsets.push(offsets[i] + len as u32);
            }
            let mut neighbours = vec![0u32; total];
            let (extra, extra_from) = (&extra, &extra_from);
            for_each_row(&offsets, &mut neighbours, &|i, out: &mut [u32]| {
                let walked = row(i);
                out[..walked.len()].copy_from_slice(walked);
                let added = &extra[extra_from[i]..extra_from[i + 1]];
                for (slot, &(_, j)) in out[walked.len()..].iter_mut().zip(added) {
                    *slot = j;
                }
                if !added.is_empty() {
                    out.sort_unstable();
                }
            });
            (offsets, neighbours)
        };
        let mut rest_lengths = vec![0.0; total];
        let (offs, nbs) = (offsets.as_slice(), neighbours.as_slice());
        for_each_row(offs, &mut rest_lengths, &|i, rl: &mut [f64]| {
            let row = &nbs[offs[i] as usize..offs[i + 1] as usize];
            crate::material::lanes::lengths(positions, i, row, rl);
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

    /// Bonds given row by row: particle `i`'s neighbours are
    /// `neighbours[offsets[i]..offsets[i + 1]]`, each row sorted, the pairs symmetric (the
    /// caller's duty); rest lengths from `positions` (m).
    pub(crate) fn from_rows(positions: &[Vec3], offsets: Vec<u32>, neighbours: Vec<u32>) -> Family {
        let mut rest_lengths = vec![0.0; neighbours.len()];
        let (offs, nbs) = (offsets.as_slice(), neighbours.as_slice());
        for_each_row(offs, &mut rest_lengths, &|i, rl: &mut [f64]| {
            let row = &nbs[offs[i] as usize..offs[i + 1] as usize];
            crate::material::lanes::lengths(positions, i, row, rl);
        });
        Family {
            offsets,
            neighbours,
            rest_lengths,
        }
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

/// A hash of the pair `(lo, hi)` spread over 64 bits (SplitMix64's finaliser: a bijection
/// of the packed pair, so distinct pairs hash apart).
#[inline]
fn pair_hash(lo: u32, hi: u32) -> u64 {
    let mut x = ((lo as u64) << 32 | hi as u64) ^ 0x9e37_79b9_7f4a_7c15;
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Whether the sorted `row` holds `v`, searched outward from index `guess` in doubling steps,
/// then by bisection within the bracket found: a few reads when the guess is close, never
/// more than twice a plain bisection's.
fn contains_near(row: &[u32], v: u32, guess: usize) -> bool {
    let Some(&at) = row.get(guess.min(row.len().saturating_sub(1))) else {
        return false;
    };
    let g = guess.min(row.len() - 1);
    let (lo, hi) = match at.cmp(&v) {
        std::cmp::Ordering::Equal => return true,
        // v lies right of g: double the step until row[g + step] >= v
        std::cmp::Ordering::Less => {
            let mut step = 1;
            while g + step < row.len() && row[g + step] < v {
                step *= 2;
            }
            (g + step / 2 + 1, (g + step + 1).min(row.len()))
        }
        std::cmp::Ordering::Greater => {
            let mut step = 1;
            while step <= g && row[g - step] > v {
                step *= 2;
            }
            (g.saturating_sub(step), g - step / 2)
        }
    };
    row[lo..hi].binary_search(&v).is_ok()
}

/// What the symmetry check reads off the rows: pairs named below their row's own index, pairs
/// named above it, and the exclusive-or of every named pair's [`pair_hash`] (ends in order).
type Check = (usize, usize, u64);

/// [`Check`] of row `i`.
fn row_check(i: usize, row: &[u32]) -> Check {
    row.iter().fold((0, 0, 0), |(b, a, h), &j| {
        let low = (j as usize) < i;
        let (lo, hi) = if low { (j, i as u32) } else { (i as u32, j) };
        (
            b + usize::from(low),
            a + usize::from(!low),
            h ^ pair_hash(lo, hi),
        )
    })
}

/// Two [`Check`]s together.
fn merge(a: Check, b: Check) -> Check {
    (a.0 + b.0, a.1 + b.1, a.2 ^ b.2)
}

/// Particles a walk task takes in turn: one growing buffer for all their rows.
const WALK_CHUNK: usize = 256;

/// A walk task's reusable state: for each tet the walk that last stamped it, the walk's
/// queue, and a bit per particle marking the current walk's finds.
struct Walker {
    stamp: Vec<u32>,
    queue: Vec<u32>,
    bits: Vec<u64>,
    /// Particles the task's last chunk found.
    last: usize,
}

impl Walker {
    fn new(n: usize) -> Walker {
        Walker {
            stamp: vec![u32::MAX; n],
            queue: Vec::new(),
            bits: vec![0; n.div_ceil(64)],
            last: 0,
        }
    }

    /// Walks from particle `i`, appending the particles found inside the ball of radius
    /// `sqrt(h2)` to `found`, sorted. The finds are marked in `bits` as well: where they span
    /// fewer words than twice their number (indices spatially ordered, as a lattice's or a
    /// mesher's are), reading the words back in order sorts them in one sweep; elsewhere a
    /// comparison sort does.
    fn walk(
        &mut self,
        i: usize,
        positions: &[Vec3],
        adjacency: &[[u32; 4]],
        h2: f64,
        found: &mut Vec<u32>,
    ) {
        let Walker {
            stamp, queue, bits, ..
        } = self;
        let xi = positions[i];
        let start = found.len();
        let (mut lo, mut hi) = (usize::MAX, 0);
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
                    found.push(u);
                    let w = u as usize / 64;
                    bits[w] |= 1 << (u % 64);
                    lo = lo.min(w);
                    hi = hi.max(w);
                }
            }
        }
        let row = &mut found[start..];
        if row.is_empty() {
            return;
        }
        if hi - lo < 2 * row.len() {
            // each find set one bit: the words hold exactly `row.len()` of them
            let mut at = 0;
            for (w, word) in (lo..).zip(&mut bits[lo..=hi]) {
                let mut b = std::mem::take(word);
                while b != 0 {
                    row[at] = (w * 64) as u32 + b.trailing_zeros();
                    at += 1;
                    b &= b - 1;
                }
            }
        } else {
            for &u in row.iter() {
                bits[u as usize / 64] = 0;
            }
            row.sort_unstable();
        }
    }
}

/// One breadth-first walk per particle, each row sorted, as CSR (row offsets, neighbours),
/// with the rows' [`Check`]:
/// each task walks [`WALK_CHUNK`] particles into one buffer, so the rows are neither allocated
/// one by one nor left scattered over the heap when they are freed; the buffers are then
/// copied into place in parallel.
fn walk_all(
    positions: &[Vec3],
    adjacency: &[[u32; 4]],
    horizon: f64,
) -> Result<(Vec<u32>, Vec<u32>, Check), PhysicsError> {
    let n = positions.len();
    let h2 = horizon * horizon;
    let chunks: Vec<(Vec<u32>, Vec<u32>, Check)> = (0..n.div_ceil(WALK_CHUNK))
        .into_par_iter()
        .map_init(
            || Walker::new(n),
            |walker, c| {
                // room for a chunk as full as this task's last (grown by doubling past it)
                let room = walker.last + walker.last / 8;
                let (mut lens, mut found) =
                    (Vec::with_capacity(WALK_CHUNK), Vec::with_capacity(room));
                let mut check = (0, 0, 0);
                for i in c * WALK_CHUNK..n.min((c + 1) * WALK_CHUNK) {
                    let start = found.len();
                    walker.walk(i, positions, adjacency, h2, &mut found);
                    lens.push((found.len() - start) as u32);
                    check = merge(check, row_check(i, &found[start..]));
                }
                walker.last = found.len();
                (lens, found, check)
            },
        )
        .collect();
    let check = chunks.iter().fold((0, 0, 0), |a, (_, _, b)| merge(a, *b));
    let total: usize = chunks.iter().map(|(_, f, _)| f.len()).sum();
    if total > u32::MAX as usize {
        return Err(PhysicsError::TooManyBonds(total));
    }
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0u32);
    for (lens, _, _) in &chunks {
        for len in lens {
            offsets.push(offsets[offsets.len() - 1] + len);
        }
    }
    let mut neighbours = vec![0u32; total];
    let mut rest = neighbours.as_mut_slice();
    let mut slices = Vec::with_capacity(chunks.len());
    for (_, found, _) in &chunks {
        let (head, tail) = rest.split_at_mut(found.len());
        slices.push(head);
        rest = tail;
    }
    slices
        .into_par_iter()
        .zip(&chunks)
        .for_each(|(out, (_, found, _))| out.copy_from_slice(found));
    Ok((offsets, neighbours, check))
}
