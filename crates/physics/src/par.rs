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
    // Zero-sized: the second slice costs nothing.
    let mut none = vec![(); per_particle.len()];
    split_rows2(
        offsets,
        0,
        per_particle,
        &mut none,
        per_bond,
        &|first, p, _, b| f(first, p, b),
    );
}

/// As [`for_rows_mut`] with two per-particle slices, split alike.
pub(crate) fn for_rows_mut2<P: Send, Q: Send, B: Send, F>(
    offsets: &[u32],
    per_particle: &mut [P],
    also: &mut [Q],
    per_bond: &mut [B],
    f: &F,
) where
    F: Fn(usize, &mut [P], &mut [Q], &mut [B]) + Sync,
{
    split_rows2(offsets, 0, per_particle, also, per_bond, f);
}

fn split_rows2<P: Send, Q: Send, B: Send, F>(
    offsets: &[u32],
    first: usize,
    per_particle: &mut [P],
    also: &mut [Q],
    per_bond: &mut [B],
    f: &F,
) where
    F: Fn(usize, &mut [P], &mut [Q], &mut [B]) + Sync,
{
    let n = per_particle.len();
    if n <= GRAIN {
        f(first, per_particle, also, per_bond);
        return;
    }
    let mid = n / 2;
    let (pl, pr) = per_particle.split_at_mut(mid);
    let (ql, qr) = also.split_at_mut(mid);
    let split = (offsets[first + mid] - offsets[first]) as usize;
    let (bl, br) = per_bond.split_at_mut(split);
    rayon::join(
        || split_rows2(offsets, first, pl, ql, bl, f),
        || split_rows2(offsets, first + mid, pr, qr, br, f),
    );
}
