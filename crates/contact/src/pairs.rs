//! Short-range contact between particles that share no intact bond (docs/model.md section 7): two
//! fragments, or the two sides of a crack, push each other apart when they come closer than a
//! contact distance, with damping and Coulomb friction as against colliders.
//!
//! The contact distance of a pair is `min(rest_factor |X_j - X_i|, distance_factor (r_i + r_j))`
//! with `X` the rest positions and `r` the contact radii: two particles whose rest distance is
//! shorter than their radii (the two tets on either side of a crack face) are pushed apart only
//! when they come closer than they were at rest, not the moment the bond between them breaks
//! (the short-range force of Silling and Askari).
//!
//! Pairs come from a Verlet list: every pair within its contact bound plus a skin, found through
//! a spatial hash and rebuilt only when some particle has moved more than half the skin since
//! the last build. Each row lists a particle's candidates in increasing index, with a flag for
//! those joined by an intact bond; [`SelfContact::unbond`] clears the flags of bonds as they
//! break, so the list need not be rebuilt for that. The force pass runs over particles in
//! parallel, each summing over its own row: no locks or atomics, the same sums for any thread
//! count, and the pair force computed from either side is exactly the negative of the other.

use rayon::prelude::*;

use crate::error::ContactError;
use crate::kernel::{penalty_force, Coeffs};
use crate::math::{add, add_assign, dot, scale, sub};
use crate::Vec3;

/// Coefficients of the contact between particles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfContactParams {
    /// Factor on the sum of two contact radii (dimensionless, > 0; default 1.3). Particles
    /// are spheres with gaps between them: at 1 two cut blocks pressed together nest into
    /// each other by 0.3 of a cell, at 1.3 by 0.1, where the rest cap takes over (the stack
    /// test in crates/scene/tests/self_contact.rs measured it).
    pub distance_factor: f64,
    /// Factor on the rest distance of a pair, which caps its contact distance (dimensionless,
    /// in (0, 1]; default 0.9, Silling and Askari's).
    pub rest_factor: f64,
    /// Normal damping as a fraction of critical damping of the pair on its penalty spring
    /// (dimensionless, >= 0).
    pub damping_ratio: f64,
    /// Coulomb friction coefficient (dimensionless, >= 0).
    pub friction: f64,
    /// Verlet skin as a multiple of the largest contact radius (dimensionless, > 0; default
    /// 1): a longer skin means fewer rebuilds and longer rows. On the default wall 1 builds the
    /// list half as often as 0.5 (85 against 170 times in 2,448 steps), the run 9% faster.
    pub skin_factor: f64,
}

impl Default for SelfContactParams {
    fn default() -> Self {
        SelfContactParams {
            distance_factor: 1.3,
            rest_factor: 0.9,
            damping_ratio: 0.1,
            friction: 0.5,
            skin_factor: 1.0,
        }
    }
}

/// Which candidate pairs an intact bond joins (they feel no contact), asked once per particle
/// and build. Any `Fn(u32, u32) -> bool + Sync` is one, asked pair by pair.
pub trait Bonds: Sync {
    /// Writes into `out[k]` 1 when an intact bond joins particle `i` and `candidates[k]`, 0
    /// otherwise; `candidates` is increasing and as long as `out`.
    fn flags(&self, i: u32, candidates: &[u32], out: &mut [u8]);
}

impl<F: Fn(u32, u32) -> bool + Sync> Bonds for F {
    fn flags(&self, i: u32, candidates: &[u32], out: &mut [u8]) {
        for (o, &j) in out.iter_mut().zip(candidates) {
            *o = u8::from(self(i, j));
        }
    }
}

/// Most pairs one particle is taken to touch at once for the stable step: the kissing number
/// of equal spheres.
pub const MAX_TOUCHING: f64 = 12.0;

/// What one force pass found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SelfContactStats {
    /// Pairs in contact, each counted once.
    pub pairs: usize,
    /// Largest overlap (m): contact distance minus distance, over the pairs in contact.
    pub max_overlap: f64,
    /// Largest overlap as a share of its pair's contact distance (dimensionless).
    pub max_overlap_share: f64,
}

impl SelfContactStats {
    fn merge(a: SelfContactStats, b: SelfContactStats) -> SelfContactStats {
        SelfContactStats {
            pairs: a.pairs + b.pairs,
            max_overlap: a.max_overlap.max(b.max_overlap),
            max_overlap_share: a.max_overlap_share.max(b.max_overlap_share),
        }
    }
}

/// Contact between the particles of one body (or several) that are not bonded.
#[derive(Debug, Clone)]
pub struct SelfContact {
    params: SelfContactParams,
    rest: Vec<Vec3>,
    radii: Vec<f64>,
    stiffness: Vec<f64>,
    /// Verlet skin (m).
    skin: f64,
    /// Row starts of the candidate lists (CSR, `len + 1`).
    offsets: Vec<u32>,
    /// Candidates, each row increasing.
    others: Vec<u32>,
    /// 1 where the candidate is joined by an intact bond (no contact force).
    bonded: Vec<u8>,
    /// The contact distance of each candidate pair (m), computed at the build.
    contact_distance: Vec<f64>,
    /// Positions at the last build (m).
    anchor: Vec<Vec3>,
    built: bool,
    rebuilds: u64,
    /// Per-particle energies of [`SelfContact::potential`] (J), summed in index order.
    energy: Vec<f64>,
    /// The spatial hash of the last build, kept for its buffers.
    hash: Hash,
    /// Per chunk of particles, the rows of the last build, kept for their buffers.
    scratch: Vec<ChunkRows>,
}

/// The uniform grid the pair search hashes: cells of `cell` metres into `buckets` buckets (a
/// power of two).
#[derive(Debug, Clone, Copy)]
struct Grid {
    cell: f64,
    buckets: usize,
}

impl Grid {
    #[inline]
    fn key(&self, p: Vec3) -> [i64; 3] {
        p.map(|x| (x / self.cell).floor() as i64)
    }

    /// A multiplicative hash of a cell; collisions only add candidates that the distance test
    /// then drops.
    #[inline]
    fn bucket(&self, k: [i64; 3]) -> usize {
        let h = (k[0] as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (k[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (k[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
        (h >> 17) as usize & (self.buckets - 1)
    }
}

/// The particles sorted by bucket (CSR over the buckets) and the sort's work buffers.
#[derive(Debug, Clone, Default)]
struct Hash {
    bucket_of: Vec<u32>,
    start: Vec<u32>,
    fill: Vec<u32>,
    sorted: Vec<u32>,
    /// Position (m) and contact radius (m) of each particle of `sorted`, in its order: a
    /// bucket's particles lie together in memory.
    points: Vec<[f64; 4]>,
}

/// Particles per chunk of a pair-list build.
const BUILD_CHUNK: usize = 1024;

/// The rows one chunk of particles found in a build: candidates, bond flags, row lengths.
#[derive(Debug, Clone, Default)]
struct ChunkRows {
    others: Vec<u32>,
    bonded: Vec<u8>,
    reach: Vec<f64>,
    lengths: Vec<u32>,
}

/// Particles per spatial hash bucket on average, at most (the table has at least twice as many
/// buckets as particles).
const BUCKETS_PER_PARTICLE: usize = 2;

impl SelfContact {
    /// Contact for particles at `rest` positions (m) with contact `radii` (m) and per-particle
    /// penalty `stiffness` (N/m; a pair's spring is the two in series).
    pub fn new(
        rest: Vec<Vec3>,
        radii: Vec<f64>,
        stiffness: Vec<f64>,
        params: SelfContactParams,
    ) -> Result<SelfContact, ContactError> {
        for (what, value, expected) in [
            (
                "self contact distance_factor",
                params.distance_factor,
                "finite and > 0",
            ),
            ("self contact rest_factor", params.rest_factor, "in (0, 1]"),
            (
                "self contact skin_factor",
                params.skin_factor,
                "finite and > 0",
            ),
            (
                "self contact damping_ratio",
                params.damping_ratio,
                "finite and >= 0",
            ),
            ("self contact friction", params.friction, "finite and >= 0"),
        ] {
            let positive = expected != "finite and >= 0";
            let most = if what.ends_with("rest_factor") {
                1.0
            } else {
                f64::INFINITY
            };
            if !value.is_finite() || value < 0.0 || (positive && value == 0.0) || value > most {
                return Err(ContactError::BadSetting {
                    what,
                    expected,
                    value,
                });
            }
        }
        let n = rest.len();
        if radii.len() != n || stiffness.len() != n {
            return Err(ContactError::BadSelfContact(format!(
                "{n} particles but {} radii and {} stiffnesses",
                radii.len(),
                stiffness.len()
            )));
        }
        for (what, values) in [
            ("contact radius", &radii),
            ("contact stiffness", &stiffness),
        ] {
            if let Some((particle, &value)) = values
                .iter()
                .enumerate()
                .find(|(_, v)| !v.is_finite() || **v < 0.0)
            {
                return Err(ContactError::BadParticle {
                    particle,
                    what,
                    expected: "finite and >= 0",
                    value,
                });
            }
        }
        let r_max = radii.iter().cloned().fold(0.0, f64::max);
        Ok(SelfContact {
            skin: params.skin_factor * r_max,
            params,
            rest,
            radii,
            stiffness,
            offsets: vec![0; n + 1],
            others: Vec::new(),
            bonded: Vec::new(),
            contact_distance: Vec::new(),
            anchor: Vec::new(),
            built: false,
            rebuilds: 0,
            energy: vec![0.0; n],
            hash: Hash::default(),
            scratch: Vec::new(),
        })
    }

    /// How many times the pair list was built.
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Candidate pairs in the list (each direction counted).
    pub fn candidates(&self) -> usize {
        self.others.len()
    }

    /// Forgets the pair list, so that the next [`SelfContact::prepare`] builds it (after the
    /// particles were moved from outside, a restore say).
    pub fn invalidate(&mut self) {
        self.built = false;
    }

    /// The contact distance (m) of particles `i` and `j`.
    #[inline]
    fn distance(&self, i: usize, j: usize) -> f64 {
        let rest = sub(self.rest[j], self.rest[i]);
        let by_rest = self.params.rest_factor * dot(rest, rest).sqrt();
        by_rest.min(self.params.distance_factor * (self.radii[i] + self.radii[j]))
    }

    /// Builds the pair list when there is none or when the particles may have moved apart by
    /// more than the skin since the last build before this step ends. A particle's predicted
    /// displacement is its displacement so far plus its velocity over `dt` (s); two particles
    /// move apart by at most the sum of their displacements' distances from any common one, so
    /// the list holds while every displacement stays within half the skin of the middle of
    /// their bounding box: a body that falls or flies as one keeps its list. `bonded` says
    /// which pairs an intact bond joins. Returns whether it built.
    pub fn prepare(
        &mut self,
        positions: &[Vec3],
        velocities: &[Vec3],
        dt: f64,
        bonded: &dyn Bonds,
    ) -> bool {
        if self.built && self.anchor.len() == positions.len() && velocities.len() == positions.len()
        {
            let anchor = &self.anchor;
            let moved = |i: usize| add(sub(positions[i], anchor[i]), scale(velocities[i], dt));
            let inf = f64::INFINITY;
            // min and max are exact whatever the order: the same box for any thread count.
            let (lo, hi) = (0..positions.len())
                .into_par_iter()
                .map(|i| {
                    let d = moved(i);
                    (d, d)
                })
                .reduce(
                    || ([inf; 3], [-inf; 3]),
                    |(l1, h1), (l2, h2)| {
                        (
                            [0, 1, 2].map(|k| l1[k].min(l2[k])),
                            [0, 1, 2].map(|k| h1[k].max(h2[k])),
                        )
                    },
                );
            let middle = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
            let reach = (0..positions.len())
                .into_par_iter()
                .map(|i| {
                    let e = sub(moved(i), middle);
                    let r = dot(e, e).sqrt();
                    // NaN (a run-away particle) rebuilds; the guard stops the run elsewhere.
                    if r.is_nan() {
                        inf
                    } else {
                        r
                    }
                })
                .reduce(|| 0.0, f64::max);
            if reach < 0.5 * self.skin {
                return false;
            }
        }
        self.build(positions, bonded);
        true
    }

    /// Builds the pair list at `positions` (m): a counting sort of the particles into the
    /// hash buckets, then one search per particle whose rows each fixed chunk of particles
    /// writes into its own buffer, joined in order. Every buffer is kept, so a rebuild
    /// allocates nothing once the buffers fit the particles and pairs.
    fn build(&mut self, positions: &[Vec3], bonded: &dyn Bonds) {
        let n = positions.len();
        let r_max = self.radii.iter().cloned().fold(0.0, f64::max);
        // The longest contact bound of any pair, plus the skin: one grid cell.
        let cell = (self.params.distance_factor * 2.0 * r_max + self.skin).max(f64::MIN_POSITIVE);
        let buckets = (BUCKETS_PER_PARTICLE * n).next_power_of_two().max(1);
        let grid = Grid { cell, buckets };
        // Counting sort of the particles by bucket: deterministic.
        let mut hash = std::mem::take(&mut self.hash);
        hash.bucket_of.clear();
        hash.bucket_of
            .extend(positions.iter().map(|&p| grid.bucket(grid.key(p)) as u32));
        hash.start.clear();
        hash.start.resize(buckets + 1, 0);
        for &b in &hash.bucket_of {
            hash.start[b as usize + 1] += 1;
        }
        for b in 0..buckets {
            hash.start[b + 1] += hash.start[b];
        }
        hash.fill.clear();
        hash.fill.extend_from_slice(&hash.start[..buckets]);
        hash.sorted.clear();
        hash.sorted.resize(n, 0);
        for (i, &b) in hash.bucket_of.iter().enumerate() {
            let slot = &mut hash.fill[b as usize];
            hash.sorted[*slot as usize] = i as u32;
            *slot += 1;
        }
        hash.points.clear();
        hash.points.extend(hash.sorted.iter().map(|&i| {
            let p = positions[i as usize];
            [p[0], p[1], p[2], self.radii[i as usize]]
        }));
        // Each fixed chunk of particles writes its rows into its own buffer (kept from build
        // to build), then the chunks are joined in order: one search per particle, the same
        // rows for any thread count.
        let chunks = n.div_ceil(BUILD_CHUNK);
        let mut scratch = std::mem::take(&mut self.scratch);
        if scratch.len() < chunks {
            scratch.resize_with(chunks, ChunkRows::default);
        }
        let this = &*self;
        scratch[..chunks]
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, rows)| {
                rows.others.clear();
                rows.bonded.clear();
                rows.reach.clear();
                rows.lengths.clear();
                for i in c * BUILD_CHUNK..((c + 1) * BUILD_CHUNK).min(n) {
                    let start = rows.others.len();
                    this.candidates_of(&grid, &hash, positions, i, |j| rows.others.push(j));
                    rows.others[start..].sort_unstable();
                    rows.bonded.resize(rows.others.len(), 0);
                    bonded.flags(i as u32, &rows.others[start..], &mut rows.bonded[start..]);
                    for k in start..rows.others.len() {
                        rows.reach.push(this.distance(i, rows.others[k] as usize));
                    }
                    rows.lengths.push((rows.others.len() - start) as u32);
                }
            });
        let mut offsets = std::mem::take(&mut self.offsets);
        let mut others = std::mem::take(&mut self.others);
        let mut flags = std::mem::take(&mut self.bonded);
        let mut reach = std::mem::take(&mut self.contact_distance);
        offsets.clear();
        offsets.push(0);
        others.clear();
        flags.clear();
        reach.clear();
        for rows in &scratch[..chunks] {
            for &len in &rows.lengths {
                let last = offsets[offsets.len() - 1];
                offsets.push(last + len);
            }
            others.extend_from_slice(&rows.others);
            flags.extend_from_slice(&rows.bonded);
            reach.extend_from_slice(&rows.reach);
        }
        self.contact_distance = reach;
        self.scratch = scratch;
        self.hash = hash;
        self.offsets = offsets;
        self.others = others;
        self.bonded = flags;
        self.anchor.clear();
        self.anchor.extend_from_slice(positions);
        self.energy.resize(n, 0.0);
        self.built = true;
        self.rebuilds += 1;
    }

    /// Calls `found(j)` for every candidate `j` of particle `i` at `positions`: within its
    /// contact distance plus the skin, in the 27 cells around it (each bucket visited once).
    #[inline]
    fn candidates_of(
        &self,
        grid: &Grid,
        hash: &Hash,
        positions: &[Vec3],
        i: usize,
        mut found: impl FnMut(u32),
    ) {
        let xi = positions[i];
        let ri = self.radii[i];
        let ki = grid.key(xi);
        let mut seen = [usize::MAX; 27];
        let mut c = 0;
        for dx in -1..=1i64 {
            for dy in -1..=1i64 {
                for dz in -1..=1i64 {
                    let k = [
                        ki[0].wrapping_add(dx),
                        ki[1].wrapping_add(dy),
                        ki[2].wrapping_add(dz),
                    ];
                    let b = grid.bucket(k);
                    if seen[..c].contains(&b) {
                        continue;
                    }
                    seen[c] = b;
                    c += 1;
                    let (lo, hi) = (hash.start[b] as usize, hash.start[b + 1] as usize);
                    for (&j, pj) in hash.sorted[lo..hi].iter().zip(&hash.points[lo..hi]) {
                        let ju = j as usize;
                        if ju == i {
                            continue;
                        }
                        let d = [pj[0] - xi[0], pj[1] - xi[1], pj[2] - xi[2]];
                        let d2 = dot(d, d);
                        // The radii bound first: the rest distance (a square root) only for
                        // the few that pass it.
                        let bound = self.params.distance_factor * (ri + pj[3]) + self.skin;
                        if d2 >= bound * bound {
                            continue;
                        }
                        let reach = self.distance(i, ju) + self.skin;
                        if d2 < reach * reach {
                            found(j);
                        }
                    }
                }
            }
        }
    }

    /// Marks the bonds `(i, j)` (either direction) as broken: the pairs feel contact from now
    /// on. Pairs not in the list are left to the next build, which asks `bonded` again.
    pub fn unbond(&mut self, broken: &[(u32, u32)]) {
        if !self.built {
            return;
        }
        for &(i, j) in broken {
            for (a, b) in [(i, j), (j, i)] {
                let Some(range) = self.row(a as usize) else {
                    continue;
                };
                if let Ok(k) = self.others[range.clone()].binary_search(&b) {
                    self.bonded[range.start + k] = 0;
                }
            }
        }
    }

    fn row(&self, i: usize) -> Option<std::ops::Range<usize>> {
        let lo = *self.offsets.get(i)? as usize;
        let hi = *self.offsets.get(i + 1)? as usize;
        Some(lo..hi)
    }

    /// Adds the contact forces (N) at `positions` (m) with `velocities` (m/s) and `masses`
    /// (kg) into `forces`, over a step of `dt` (s; it caps friction). Call
    /// [`SelfContact::prepare`] before each step.
    pub fn add_forces(
        &self,
        dt: f64,
        positions: &[Vec3],
        velocities: &[Vec3],
        masses: &[f64],
        forces: &mut [Vec3],
    ) -> SelfContactStats {
        if !self.built {
            return SelfContactStats::default();
        }
        let inv_dt = if dt > 0.0 { 1.0 / dt } else { 0.0 };
        let SelfContactParams {
            damping_ratio,
            friction,
            ..
        } = self.params;
        forces
            .par_iter_mut()
            .enumerate()
            .map(|(i, f)| {
                let mut stats = SelfContactStats::default();
                let Some(range) = self.row(i) else {
                    return stats;
                };
                for p in range {
                    let Some((n, overlap, d_c, k)) = self.touching(i, p, positions) else {
                        continue;
                    };
                    let j = self.others[p] as usize;
                    let (mi, mj) = (masses[i], masses[j]);
                    let m = mi * mj / (mi + mj);
                    let coeffs = Coeffs {
                        k,
                        damp: 2.0 * damping_ratio * k.sqrt(),
                        mu: friction,
                    };
                    let v_rel = sub(velocities[i], velocities[j]);
                    add_assign(f, penalty_force(overlap, n, v_rel, m, inv_dt, &coeffs));
                    if i < j {
                        stats.pairs += 1;
                    }
                    stats.max_overlap = stats.max_overlap.max(overlap);
                    stats.max_overlap_share = stats.max_overlap_share.max(overlap / d_c);
                }
                stats
            })
            .reduce(SelfContactStats::default, SelfContactStats::merge)
    }

    /// The pair `(i, j)` (row position `p`) when it touches at `q`: the unit direction from
    /// `j` towards `i`, the overlap (m), the contact distance (m) and the series stiffness
    /// (N/m).
    #[inline]
    fn touching(&self, i: usize, p: usize, q: &[Vec3]) -> Option<(Vec3, f64, f64, f64)> {
        if self.bonded[p] != 0 {
            return None;
        }
        let j = self.others[p] as usize;
        let d_c = self.contact_distance[p];
        let dx = sub(q[i], q[j]);
        let d2 = dot(dx, dx);
        if d2 >= d_c * d_c {
            return None;
        }
        let (n, dist) = if d2 > f64::MIN_POSITIVE {
            let dist = d2.sqrt();
            (scale(dx, 1.0 / dist), dist)
        } else {
            // Coincident centres: a fixed axis, opposite for the two.
            ([0.0, 0.0, if i < j { -1.0 } else { 1.0 }], 0.0)
        };
        let (ki, kj) = (self.stiffness[i], self.stiffness[j]);
        let k = if ki + kj > 0.0 {
            ki * kj / (ki + kj)
        } else {
            0.0
        };
        Some((n, d_c - dist, d_c, k))
    }

    /// The penalty energy (J) of the pairs touching at end positions `q` (m) of an implicit
    /// step, `k_ij overlap^2 / 2` each; with `grad`, adds its gradient (N) into it. Damping
    /// and friction are left out (the implicit step damps on its own); call
    /// [`SelfContact::prepare`] before the step.
    pub fn potential(&mut self, q: &[Vec3], grad: Option<&mut [Vec3]>) -> f64 {
        if !self.built || self.energy.len() != q.len() {
            return 0.0;
        }
        let mut energy = std::mem::take(&mut self.energy);
        let this = &*self;
        let per_particle = |i: usize, e: &mut f64, g: Option<&mut Vec3>| {
            let mut sum = 0.0;
            let mut gi = [0.0; 3];
            if let Some(range) = this.row(i) {
                for p in range {
                    if let Some((n, overlap, _, k)) = this.touching(i, p, q) {
                        sum += 0.5 * k * overlap * overlap;
                        // d/dq_i of k o^2 / 2 with o = d_c - |q_i - q_j|: -k o n.
                        add_assign(&mut gi, scale(n, -k * overlap));
                    }
                }
            }
            *e = sum;
            if let Some(g) = g {
                add_assign(g, gi);
            }
        };
        match grad {
            Some(grad) => energy
                .par_iter_mut()
                .zip(grad.par_iter_mut())
                .enumerate()
                .for_each(|(i, (e, g))| per_particle(i, e, Some(g))),
            None => energy
                .par_iter_mut()
                .enumerate()
                .for_each(|(i, e)| per_particle(i, e, None)),
        }
        // Each pair was counted from both ends.
        let total = 0.5 * energy.iter().sum::<f64>();
        self.energy = energy;
        total
    }

    /// Adds to `out` (N/m) the springs of the pairs touching each particle at positions `q`
    /// (m), as the colliders' hint counts the pairs penetrating: the contact Hessian's diagonal
    /// block there, for the implicit step's matrix.
    pub fn curvature_hint(&self, q: &[Vec3], out: &mut [f64]) {
        if !self.built || q.len() != out.len() {
            return;
        }
        out.par_iter_mut().enumerate().for_each(|(i, c)| {
            for p in self.row(i).into_iter().flatten() {
                if let Some((_, _, _, k)) = self.touching(i, p, q) {
                    *c += k;
                }
            }
        });
    }

    /// The statistics of the pairs touching at positions `q` (m), as [`SelfContact::add_forces`]
    /// reports them.
    pub fn stats_at(&self, q: &[Vec3]) -> SelfContactStats {
        if !self.built {
            return SelfContactStats::default();
        }
        (0..q.len())
            .into_par_iter()
            .map(|i| {
                let mut stats = SelfContactStats::default();
                for p in self.row(i).into_iter().flatten() {
                    if let Some((_, overlap, d_c, _)) = self.touching(i, p, q) {
                        if i < self.others[p] as usize {
                            stats.pairs += 1;
                        }
                        stats.max_overlap = stats.max_overlap.max(overlap);
                        stats.max_overlap_share = stats.max_overlap_share.max(overlap / d_c);
                    }
                }
                stats
            })
            .reduce(SelfContactStats::default, SelfContactStats::merge)
    }

    /// The highest angular frequency squared (1/s^2) contact may add to particles of
    /// `masses` (kg): with `A = max k_i / m_i`, a pair's series spring on its reduced mass
    /// rings at `omega^2 <= A` (`k_ij <= A m_i m_j / (m_i + m_j)`), and by Gershgorin's bound a
    /// particle touching [`MAX_TOUCHING`] others at once at most that many times faster
    /// (equal masses). Damping is left out: it only lowers the frequency.
    pub fn max_omega2(&self, masses: &[f64]) -> f64 {
        let a = self
            .stiffness
            .iter()
            .zip(masses)
            .map(|(&k, &m)| if m > 0.0 { k / m } else { 0.0 })
            .fold(0.0, f64::max);
        MAX_TOUCHING * a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(distance: f64) -> (SelfContact, Vec<Vec3>) {
        // Two particles far apart at rest (contact distance = r_i + r_j = 1).
        let rest = vec![[0.0; 3], [10.0, 0.0, 0.0]];
        let c = SelfContact::new(
            rest,
            vec![0.5, 0.5],
            vec![100.0, 300.0],
            SelfContactParams {
                distance_factor: 1.0,
                damping_ratio: 0.0,
                friction: 0.0,
                // A skin of 0.25 m.
                skin_factor: 0.5,
                ..SelfContactParams::default()
            },
        )
        .unwrap();
        (c, vec![[0.0; 3], [distance, 0.0, 0.0]])
    }

    #[test]
    fn overlap_pushes_apart_with_the_series_spring() {
        let (mut c, x) = pair(0.9);
        let v = vec![[0.0; 3]; 2];
        assert!(c.prepare(&x, &v, 1e-3, &|_, _| false));
        let mut f = vec![[0.0; 3]; 2];
        let stats = c.add_forces(1e-3, &x, &v, &[1.0, 1.0], &mut f);
        // k = 100 * 300 / 400 = 75 N/m over 0.1 m of overlap.
        assert!(
            (f[0][0] + 7.5).abs() < 1e-12 && (f[1][0] - 7.5).abs() < 1e-12,
            "{f:?}"
        );
        assert_eq!(f[0], [-f[1][0], -f[1][1], -f[1][2]]);
        assert_eq!(stats.pairs, 1);
        assert!((stats.max_overlap_share - 0.1).abs() < 1e-12);
    }

    #[test]
    fn bonded_pairs_feel_nothing_until_unbonded() {
        let (mut c, x) = pair(0.5);
        let v = vec![[0.0; 3]; 2];
        c.prepare(&x, &v, 1e-3, &|_, _| true);
        let mut f = vec![[0.0; 3]; 2];
        c.add_forces(1e-3, &x, &v, &[1.0, 1.0], &mut f);
        assert_eq!(f, vec![[0.0; 3]; 2]);
        c.unbond(&[(1, 0)]);
        c.add_forces(1e-3, &x, &v, &[1.0, 1.0], &mut f);
        assert!(f[0][0] < 0.0 && f[1][0] > 0.0);
    }

    #[test]
    fn rest_distance_caps_the_contact_distance() {
        // At rest 0.4 apart (closer than the radii's 1.0): contact only below 0.9 * 0.4.
        let rest = vec![[0.0; 3], [0.4, 0.0, 0.0]];
        let mut c = SelfContact::new(
            rest,
            vec![0.5, 0.5],
            vec![1.0, 1.0],
            SelfContactParams::default(),
        )
        .unwrap();
        let v = vec![[0.0; 3]; 2];
        for (d, touching) in [(0.4, false), (0.37, false), (0.35, true)] {
            let x = vec![[0.0; 3], [d, 0.0, 0.0]];
            c.invalidate();
            c.prepare(&x, &v, 1e-3, &|_, _| false);
            let mut f = vec![[0.0; 3]; 2];
            let s = c.add_forces(1e-3, &x, &v, &[1.0, 1.0], &mut f);
            assert_eq!(s.pairs == 1, touching, "at {d}: {s:?}");
        }
    }

    #[test]
    fn the_list_is_rebuilt_only_past_half_the_skin() {
        let (mut c, mut x) = pair(2.0);
        let v = vec![[0.0; 3]; 2];
        assert!(c.prepare(&x, &v, 0.0, &|_, _| false));
        // Skin 0.25 m: the two may close in by less than that. Moving one by 0.2 m keeps the
        // list, 0.06 m more does not.
        x[1][0] -= 0.2;
        assert!(!c.prepare(&x, &v, 0.0, &|_, _| false));
        x[1][0] -= 0.06;
        assert!(c.prepare(&x, &v, 0.0, &|_, _| false));
        assert_eq!(c.rebuilds(), 2);
        // Both moved together by 10 m: nothing changed between them.
        let shifted: Vec<Vec3> = x.iter().map(|p| [p[0] + 10.0, p[1] - 10.0, p[2]]).collect();
        assert!(!c.prepare(&shifted, &v, 0.0, &|_, _| false));
        // The velocity over the step counts: at 0.1 m/s towards each other, 1.5 s closes them
        // by 0.3 m.
        let apart = vec![[0.1, 0.0, 0.0], [-0.1, 0.0, 0.0]];
        assert!(!c.prepare(&x, &apart, 1.0, &|_, _| false));
        assert!(c.prepare(&x, &apart, 1.5, &|_, _| false));
        // A particle that ran away to NaN rebuilds.
        x[0][2] = f64::NAN;
        assert!(c.prepare(&x, &v, 0.0, &|_, _| false));
        assert_eq!(c.rebuilds(), 4);
    }

    /// Two free particles of 1 kg thrown at each other at 1 m/s each on the contact spring
    /// (`k` = 75 N/m) with `damping_ratio`: the ratio of their parting to closing speed.
    fn restitution(damping_ratio: f64) -> f64 {
        let (mut c, mut x) = pair(2.0);
        c.params.damping_ratio = damping_ratio;
        let mut v = vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]];
        let m = [1.0, 1.0];
        // The pair rings at omega = sqrt(k / m_reduced) = sqrt(150): 1/500 of its period.
        let dt = 2.0 * std::f64::consts::PI / 150f64.sqrt() / 500.0;
        let mut f = vec![[0.0; 3]; 2];
        for _ in 0..20_000 {
            for i in 0..2 {
                for k in 0..3 {
                    v[i][k] += 0.5 * dt * f[i][k] / m[i];
                    x[i][k] += dt * v[i][k];
                }
            }
            c.prepare(&x, &v, dt, &|_, _| false);
            f = vec![[0.0; 3]; 2];
            c.add_forces(dt, &x, &v, &m, &mut f);
            for i in 0..2 {
                for k in 0..3 {
                    v[i][k] += 0.5 * dt * f[i][k] / m[i];
                }
            }
        }
        (v[1][0] - v[0][0]) / 2.0
    }

    /// The restitution of a spring-dashpot that may not pull, in closed form: the overlap is
    /// `x = v0 / w_d exp(-zeta w t) sin(w_d t)` until the force `k x + c x'` falls to zero
    /// (found by bisection), and the parting speed is `-x'` then.
    fn exact_restitution(zeta: f64) -> f64 {
        let w = 1.0;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let x = |t: f64| (-zeta * w * t).exp() * (wd * t).sin() / wd;
        let xdot =
            |t: f64| (-zeta * w * t).exp() * ((wd * t).cos() - zeta * w / wd * (wd * t).sin());
        let force = |t: f64| w * w * x(t) + 2.0 * zeta * w * xdot(t);
        let (mut lo, mut hi) = (0.5 * std::f64::consts::PI / wd, std::f64::consts::PI / wd);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if force(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        -xdot(lo)
    }

    #[test]
    fn pair_bounces_with_the_spring_dashpot_restitution() {
        // Undamped: an elastic bounce (velocity Verlet at 500 steps per period: 1e-4).
        assert!((restitution(0.0) - 1.0).abs() < 1e-4);
        // Damped: the closed form of a dashpot that may not pull, which keeps more than the
        // linear spring-dashpot's exp(-zeta pi / sqrt(1 - zeta^2)). The step's error is
        // measured at most 2.3e-4 at 500 steps per period.
        for zeta in [0.1, 0.2, 0.4] {
            let (e, exact) = (restitution(zeta), exact_restitution(zeta));
            let linear = (-zeta * std::f64::consts::PI / (1.0 - zeta * zeta).sqrt()).exp();
            assert!(exact > linear);
            assert!(
                (e - exact).abs() < 1e-3,
                "zeta {zeta}: e {e}, exact {exact}"
            );
        }
    }

    #[test]
    fn the_potential_gradient_is_its_derivative() {
        // Four particles, far apart at rest, squeezed together at q.
        let rest = (0..4).map(|k| [10.0 * k as f64, 0.0, 0.0]).collect();
        let mut c = SelfContact::new(
            rest,
            vec![0.5, 0.6, 0.4, 0.5],
            vec![100.0, 200.0, 50.0, 80.0],
            SelfContactParams::default(),
        )
        .unwrap();
        let q = vec![
            [0.0, 0.0, 0.0],
            [0.8, 0.1, 0.0],
            [0.5, 0.7, 0.2],
            [1.2, 0.6, -0.3],
        ];
        c.prepare(&q, &[[0.0; 3]; 4], 0.0, &|i, j| {
            (i, j) == (0, 3) || (i, j) == (3, 0)
        });
        let mut g = vec![[0.0; 3]; 4];
        let e = c.potential(&q, Some(&mut g));
        assert!(e > 0.0);
        // Central differences with h = 1e-6 m: the truncation error is O(h^2 k), far below
        // the 1e-6 relative tolerance on forces of order 10 N.
        let h = 1e-6;
        for i in 0..4 {
            for k in 0..3 {
                let mut qp = q.clone();
                let mut qm = q.clone();
                qp[i][k] += h;
                qm[i][k] -= h;
                let fd = (c.potential(&qp, None) - c.potential(&qm, None)) / (2.0 * h);
                assert!(
                    (fd - g[i][k]).abs() < 1e-6 * (1.0 + g[i][k].abs()),
                    "{i} {k}: {fd} vs {}",
                    g[i][k]
                );
            }
        }
        // The explicit forces are the negative gradient (no damping at rest).
        let mut f = vec![[0.0; 3]; 4];
        c.add_forces(1e-3, &q, &[[0.0; 3]; 4], &[1.0; 4], &mut f);
        for i in 0..4 {
            for k in 0..3 {
                assert!((f[i][k] + g[i][k]).abs() < 1e-12 * (1.0 + g[i][k].abs()));
            }
        }
        assert_eq!(
            c.stats_at(&q).pairs,
            c.add_forces(1e-3, &q, &[[0.0; 3]; 4], &[1.0; 4], &mut f)
                .pairs
        );
    }

    #[test]
    fn bad_coefficients_are_refused() {
        let p = SelfContactParams {
            rest_factor: 1.5,
            ..SelfContactParams::default()
        };
        assert!(SelfContact::new(vec![[0.0; 3]], vec![1.0], vec![1.0], p).is_err());
        let p = SelfContactParams {
            friction: f64::NAN,
            ..SelfContactParams::default()
        };
        assert!(SelfContact::new(vec![[0.0; 3]], vec![1.0], vec![1.0], p).is_err());
        let p = SelfContactParams::default();
        assert!(SelfContact::new(vec![[0.0; 3]], vec![1.0, 2.0], vec![1.0], p).is_err());
    }
}
