//! Deterministic parallel loops over particles, with per-particle and per-bond outputs split into
//! disjoint slices (no locks, no atomics). Each particle's result is computed sequentially over
//! its own bonds, so results do not depend on the thread count.

use rayon::prelude::*;

/// Particles handled by one task.
pub(crate) const GRAIN: usize = 512;

/// Calls `f(i)` for every particle and stores the result in `out[i]`, in parallel.
pub(crate) fn map_particles<T: Send, F>(out: &mut [T], f: F)
where
    F: Fn(usize) -> T + Sync,
{
    out.par_chunks_mut(GRAIN)
        .enumerate()
        .for_each(|(c, chunk)| {
            for (o, slot) in chunk.iter_mut().enumerate() {
                *slot = f(c * GRAIN + o);
            }
        });
}

/// Calls `f(i, &mut out[i])` for every particle, in parallel.
pub(crate) fn update_particles<T: Send, F>(out: &mut [T], f: F)
where
    F: Fn(usize, &mut T) + Sync,
{
    out.par_chunks_mut(GRAIN)
        .enumerate()
        .for_each(|(c, chunk)| {
            for (o, slot) in chunk.iter_mut().enumerate() {
                f(c * GRAIN + o, slot);
            }
        });
}

/// Calls `f(i)` for every particle and stores the pair it returns in `a[i]`, `b[i]`, in
/// parallel.
pub(crate) fn map_particles2<A: Send, B: Send, F>(a: &mut [A], b: &mut [B], f: F)
where
    F: Fn(usize) -> (A, B) + Sync,
{
    a.par_chunks_mut(GRAIN)
        .zip(b.par_chunks_mut(GRAIN))
        .enumerate()
        .for_each(|(c, (ca, cb))| {
            for (o, (sa, sb)) in ca.iter_mut().zip(cb.iter_mut()).enumerate() {
                (*sa, *sb) = f(c * GRAIN + o);
            }
        });
}

/// Calls `f(first, per_particle, per_bond)` on disjoint blocks of consecutive particles starting at
/// `first`, where `per_bond` holds exactly the bonds of those particles (CSR `offsets`).
pub(crate) fn for_rows_mut<P: Send, B: Send, F>(
    offsets: &[u32],
    per_particle: &mut [P],
    per_bond: &mut [B],
    f: &F,
) where
    F: Fn(usize, &mut [P], &mut [B]) + Sync,
{
    let n = per_particle.len();
    split_rows(offsets, 0, n, per_particle, per_bond, f);
}

/// Calls `f(i, row)` for every particle `i` (`offsets.len() - 1` of them), `row` its own bonds'
/// slots of `per_bond` (CSR `offsets`), in parallel blocks.
pub(crate) fn for_each_row<B: Send, F>(offsets: &[u32], per_bond: &mut [B], f: &F)
where
    F: Fn(usize, &mut [B]) + Sync,
{
    // zero-sized: no storage
    let mut particles = vec![(); offsets.len() - 1];
    for_rows_mut(
        offsets,
        &mut particles,
        per_bond,
        &|first, block: &mut [()], bonds| {
            let base = offsets[first] as usize;
            for i in first..first + block.len() {
                f(
                    i,
                    &mut bonds[offsets[i] as usize - base..offsets[i + 1] as usize - base],
                );
            }
        },
    );
}

/// As [`for_rows_mut`] with any [`Rows`] per particle and per bond (a slice, or a pair of
/// them, split alike), over the `n` particles.
pub(crate) fn for_rows<P: Rows, B: Rows, F>(offsets: &[u32], n: usize, p: P, b: B, f: &F)
where
    F: Fn(usize, P, B) + Sync,
{
    split_rows(offsets, 0, n, p, b, f);
}

/// Per-particle or per-bond outputs that split into disjoint halves.
pub(crate) trait Rows: Send + Sized {
    /// The first `at` entries and the rest.
    fn split(self, at: usize) -> (Self, Self);
}

impl<T: Send> Rows for &mut [T] {
    fn split(self, at: usize) -> (Self, Self) {
        self.split_at_mut(at)
    }
}

impl<A: Rows, B: Rows> Rows for (A, B) {
    fn split(self, at: usize) -> (Self, Self) {
        let (al, ar) = self.0.split(at);
        let (bl, br) = self.1.split(at);
        ((al, bl), (ar, br))
    }
}

/// Halves the `n` particles from `first` (and their bonds with them) until a block is at most
/// [`GRAIN`].
fn split_rows<P: Rows, B: Rows, F>(offsets: &[u32], first: usize, n: usize, p: P, b: B, f: &F)
where
    F: Fn(usize, P, B) + Sync,
{
    if n <= GRAIN {
        f(first, p, b);
        return;
    }
    let mid = n / 2;
    let (pl, pr) = p.split(mid);
    let (bl, br) = b.split((offsets[first + mid] - offsets[first]) as usize);
    rayon::join(
        || split_rows(offsets, first, mid, pl, bl, f),
        || split_rows(offsets, first + mid, n - mid, pr, br, f),
    );
}
