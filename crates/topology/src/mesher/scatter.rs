//! Deterministic well-spaced points in an axis-aligned box, for [`super::unstructured`].
//!
//! The box's 8 corners, evenly spaced points along its 12 edges, Poisson-disk points on each of
//! its 6 faces (Bridson's algorithm in the face's plane, grown from the face's edge points) and
//! Poisson-disk points inside (the same in 3D, grown from everything on the boundary). Every
//! point keeps at least [`MIN_DISTANCE`]` * h` from every other (corners and edge points
//! excepted where the box is thinner than that), face points keep
//! [`BOUNDARY_MARGIN`]` * MIN_DISTANCE * h` from their face's edges and inside points as much
//! from the faces. Points on a face have the face's coordinate exactly, points on an edge both
//! of its coordinates, so the box's boundary is conformed exactly by any triangulation of them.

use super::delaunay::splitmix64;
use super::unstructured::UnstructuredError;

/// The smallest distance between two scattered points, as a fraction of the spacing `h`.
pub const MIN_DISTANCE: f64 = 0.75;

/// How far face points stay from their face's edges, and inside points from the faces, as a
/// fraction of the smallest distance `MIN_DISTANCE * h`: close enough that no gap opens along
/// the boundary, far enough that no point sits just above a face (a flat tet).
pub const BOUNDARY_MARGIN: f64 = 0.6;

/// Candidates tried around each active point before it is retired (Bridson's `k`).
const ATTEMPTS: usize = 30;

/// The most points a scatter may make: about 20 million (some 130 million tets).
pub const MAX_POINTS: f64 = 2.0e7;

/// Where a scattered point lies on the box; also how it may move without leaving that place.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// One of the 8 corners: it never moves.
    Corner,
    /// On an edge parallel to axis `axis` (0 = x, 1 = y, 2 = z), strictly between its corners.
    Edge {
        /// The edge's direction.
        axis: usize,
    },
    /// On a face normal to axis `axis`, strictly inside it.
    Face {
        /// The face's normal direction.
        axis: usize,
    },
    /// Strictly inside the box.
    Interior,
}

/// Scattered points and where each lies.
#[derive(Debug, Clone, PartialEq)]
pub struct Scatter {
    /// Point positions (length).
    pub points: Vec<[f64; 3]>,
    /// Where each point lies, parallel to `points`.
    pub placement: Vec<Placement>,
}

/// A small deterministic generator (splitmix64 stream) of uniform numbers.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator whose stream is fixed by `seed`.
    pub fn new(seed: u64) -> Self {
        Rng(splitmix64(seed ^ 0x5851_f42d_4c95_7f2d))
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        // splitmix64's stream: the state advances by its increment, the output is its mix.
        let out = splitmix64(self.0);
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        out
    }

    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[0, n)` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        (((self.next_u64() >> 32) * n as u64) >> 32) as usize
    }
}

/// Whether `min..max` is a box this module can scatter in: finite, positive extent.
pub(crate) fn check_box(min: [f64; 3], max: [f64; 3]) -> Result<(), UnstructuredError> {
    let ok = (0..3).all(|d| min[d].is_finite() && max[d].is_finite() && max[d] > min[d]);
    if ok && (0..3).all(|d| (max[d] - min[d]).is_finite()) {
        Ok(())
    } else {
        Err(UnstructuredError::BadBox { min, max })
    }
}

/// About how many points [`scatter_box`] makes for spacing `h` (an overestimate for the
/// limit check, never below the 8 corners).
pub(crate) fn estimated_points(min: [f64; 3], max: [f64; 3], h: f64) -> f64 {
    let n = [0, 1, 2].map(|d| (max[d] - min[d]) / h + 2.0);
    n[0] * n[1] * n[2]
}

/// Well-spaced points in the box `min..max` (length) at spacing `h` (length; the spacing of the
/// edge points, about the mean edge length of their Delaunay tets), the same for the same
/// `seed`. An error for a box with a non-finite or non-positive extent, a non-finite or
/// non-positive `h`, or more than [`MAX_POINTS`] points.
pub fn scatter_box(
    min: [f64; 3],
    max: [f64; 3],
    h: f64,
    seed: u64,
) -> Result<Scatter, UnstructuredError> {
    check_box(min, max)?;
    if !(h.is_finite() && h > 0.0) {
        return Err(UnstructuredError::BadSpacing { h });
    }
    let estimate = estimated_points(min, max, h);
    if estimate.is_nan() || estimate > MAX_POINTS {
        return Err(UnstructuredError::TooManyPoints { estimate });
    }
    let r = MIN_DISTANCE * h;
    let mut s = Sampler::new(min, max, r);
    let mut rng = Rng::new(seed);
    for corner in 0..8 {
        let p = [0, 1, 2].map(|d| if corner >> d & 1 == 0 { min[d] } else { max[d] });
        s.add(p, Placement::Corner);
    }
    for axis in 0..3 {
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        let length = max[axis] - min[axis];
        let n = ((length / h).round() as usize).max(1);
        for side in 0..4 {
            let mut p = [0.0; 3];
            p[u] = if side & 1 == 0 { min[u] } else { max[u] };
            p[w] = if side & 2 == 0 { min[w] } else { max[w] };
            for i in 1..n {
                p[axis] = min[axis] + length * (i as f64 / n as f64);
                // Far from the origin rounding could put the point on a corner.
                if p[axis] > min[axis] && p[axis] < max[axis] {
                    s.add(p, Placement::Edge { axis });
                }
            }
        }
    }
    for axis in 0..3 {
        for side in [min[axis], max[axis]] {
            s.fill_face(axis, side, &mut rng);
        }
    }
    s.fill_interior(&mut rng);
    Ok(Scatter {
        points: s.points,
        placement: s.placement,
    })
}

/// Bridson-style dart throwing with a background grid of cells of side `r`.
struct Sampler {
    min: [f64; 3],
    max: [f64; 3],
    r: f64,
    dims: [usize; 3],
    /// First point of each grid cell, then `next` links ([`u32::MAX`] ends).
    head: Vec<u32>,
    next: Vec<u32>,
    points: Vec<[f64; 3]>,
    placement: Vec<Placement>,
    active: Vec<u32>,
}

impl Sampler {
    fn new(min: [f64; 3], max: [f64; 3], r: f64) -> Self {
        let dims = [0, 1, 2].map(|d| (((max[d] - min[d]) / r).ceil() as usize).max(1));
        Sampler {
            min,
            max,
            r,
            dims,
            head: vec![u32::MAX; dims[0] * dims[1] * dims[2]],
            next: Vec::new(),
            points: Vec::new(),
            placement: Vec::new(),
            active: Vec::new(),
        }
    }

    #[inline]
    fn cell_of(&self, p: [f64; 3]) -> [usize; 3] {
        [0, 1, 2].map(|d| {
            let c = ((p[d] - self.min[d]) / self.r).floor();
            (c.max(0.0) as usize).min(self.dims[d] - 1)
        })
    }

    fn add(&mut self, p: [f64; 3], placement: Placement) {
        let [i, j, k] = self.cell_of(p);
        let cell = i + self.dims[0] * (j + self.dims[1] * k);
        let id = self.points.len() as u32;
        self.next.push(self.head[cell]);
        self.head[cell] = id;
        self.points.push(p);
        self.placement.push(placement);
    }

    /// Whether no point lies closer than `r` to `p`.
    fn is_free(&self, p: [f64; 3]) -> bool {
        let r2 = self.r * self.r;
        let c = self.cell_of(p);
        let range = |d: usize| c[d].saturating_sub(1)..(c[d] + 2).min(self.dims[d]);
        for k in range(2) {
            for j in range(1) {
                for i in range(0) {
                    let mut q = self.head[i + self.dims[0] * (j + self.dims[1] * k)];
                    while q != u32::MAX {
                        let o = self.points[q as usize];
                        let d2 = (0..3).map(|d| (o[d] - p[d]) * (o[d] - p[d])).sum::<f64>();
                        if d2 < r2 {
                            return false;
                        }
                        q = self.next[q as usize];
                    }
                }
            }
        }
        true
    }

    /// Whether `p[d]` keeps the boundary margin from both ends of the box along `d`.
    #[inline]
    fn inside(&self, p: [f64; 3], d: usize) -> bool {
        let m = BOUNDARY_MARGIN * self.r;
        p[d] >= self.min[d] + m && p[d] <= self.max[d] - m
    }

    /// Poisson-disk points strictly inside the face normal to `axis` at coordinate `plane`,
    /// grown from the points already on that face (its corners and edges).
    fn fill_face(&mut self, axis: usize, plane: f64, rng: &mut Rng) {
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        let r2 = self.r * self.r;
        self.active.clear();
        self.active.extend(
            (0..self.points.len() as u32).filter(|&v| self.points[v as usize][axis] == plane),
        );
        while !self.active.is_empty() {
            let a = rng.below(self.active.len());
            let q = self.points[self.active[a] as usize];
            let mut placed = false;
            for _ in 0..ATTEMPTS {
                // Uniform in the annulus r..2r, by rejection from its bounding square.
                let (du, dw) = loop {
                    let du = self.r * (4.0 * rng.uniform() - 2.0);
                    let dw = self.r * (4.0 * rng.uniform() - 2.0);
                    let d2 = du * du + dw * dw;
                    if d2 >= r2 && d2 <= 4.0 * r2 {
                        break (du, dw);
                    }
                };
                let mut p = q;
                p[axis] = plane;
                p[u] += du;
                p[w] += dw;
                if self.inside(p, u) && self.inside(p, w) && self.is_free(p) {
                    self.add(p, Placement::Face { axis });
                    self.active.push((self.points.len() - 1) as u32);
                    placed = true;
                    break;
                }
            }
            if !placed {
                self.active.swap_remove(a);
            }
        }
    }

    /// Poisson-disk points strictly inside the box, grown from every point on its boundary.
    fn fill_interior(&mut self, rng: &mut Rng) {
        let r2 = self.r * self.r;
        self.active.clear();
        self.active.extend(0..self.points.len() as u32);
        while !self.active.is_empty() {
            let a = rng.below(self.active.len());
            let q = self.points[self.active[a] as usize];
            let mut placed = false;
            for _ in 0..ATTEMPTS {
                // Uniform in the spherical shell r..2r, by rejection from its bounding cube.
                let d = loop {
                    let d = [0, 1, 2].map(|_| self.r * (4.0 * rng.uniform() - 2.0));
                    let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    if d2 >= r2 && d2 <= 4.0 * r2 {
                        break d;
                    }
                };
                let p = [q[0] + d[0], q[1] + d[1], q[2] + d[2]];
                if (0..3).all(|d| self.inside(p, d)) && self.is_free(p) {
                    self.add(p, Placement::Interior);
                    self.active.push((self.points.len() - 1) as u32);
                    placed = true;
                    break;
                }
            }
            if !placed {
                self.active.swap_remove(a);
            }
        }
    }
}
