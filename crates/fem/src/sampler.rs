//! Interpolation of nodal fields at fixed rest points (e.g. peridynamic particles at the
//! barycentres of another mesh of the same body).

use crate::basis::{Basis, P1, P2};
use crate::error::FemError;
use crate::math::{dot, norm, sub, Vec3};
use crate::mesh::{Mesh, Order};

/// Containing element and shape-function weights of each sample point, found once.
#[derive(Debug, Clone)]
pub struct Sampler {
    npe: usize,
    /// Per point: the element's node ids.
    nodes: Vec<u32>,
    /// Per point: the shape-function values at the point.
    weights: Vec<f64>,
    elements: Vec<u32>,
}

impl Sampler {
    /// Locates `points` (m, rest configuration) in `mesh`, snapping points at most
    /// `1e-9` of the mesh's bounding-box diagonal outside it to the nearest element.
    pub fn new(mesh: &Mesh, points: &[Vec3]) -> Result<Self, FemError> {
        let (lo, hi) = bounds(mesh.nodes());
        Self::with_tolerance(mesh, points, 1e-9 * norm(sub(hi, lo)))
    }

    /// As [`Sampler::new`], with the snapping tolerance `tolerance` (m). A snapped point is
    /// moved to the closest point of the nearest element (to its barycentric coordinates
    /// clipped to the element, which is the closest point for points a hair outside a face).
    pub fn with_tolerance(mesh: &Mesh, points: &[Vec3], tolerance: f64) -> Result<Self, FemError> {
        let grid = Grid::new(mesh);
        let npe = mesh.nodes_per_element();
        let mut nodes = Vec::with_capacity(points.len() * npe);
        let mut weights = Vec::with_capacity(points.len() * npe);
        let mut elements = Vec::with_capacity(points.len());
        for (index, &p) in points.iter().enumerate() {
            let (e, l, distance) = grid.locate(mesh, p, tolerance);
            if distance > tolerance {
                return Err(FemError::PointOutside {
                    index,
                    point: p,
                    distance,
                    tolerance,
                });
            }
            nodes.extend_from_slice(mesh.element(e));
            match mesh.order() {
                Order::Linear => weights.extend_from_slice(&P1::values(l)),
                Order::Quadratic => weights.extend_from_slice(&P2::values(l)),
            }
            elements.push(e as u32);
        }
        Ok(Self {
            npe,
            nodes,
            weights,
            elements,
        })
    }

    /// Number of sample points.
    pub fn len(&self) -> usize {
        self.elements.len()
    }

    /// Whether there are no sample points.
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// The element holding each point.
    pub fn elements(&self) -> &[u32] {
        &self.elements
    }

    /// The nodal field `nodal` (one value per node: positions in m, displacements, velocities)
    /// interpolated at every point, into `out`.
    ///
    /// # Panics
    /// If `out` does not have one entry per point, or `nodal` is shorter than the mesh's nodes.
    #[track_caller]
    pub fn interpolate_into(&self, nodal: &[Vec3], out: &mut [Vec3]) {
        assert_eq!(out.len(), self.len(), "out: one per sample point");
        for (p, o) in out.iter_mut().enumerate() {
            let mut s = [0.0; 3];
            for k in p * self.npe..(p + 1) * self.npe {
                let v = nodal[self.nodes[k] as usize];
                let w = self.weights[k];
                s = [s[0] + w * v[0], s[1] + w * v[1], s[2] + w * v[2]];
            }
            *o = s;
        }
    }

    /// The nodal field interpolated at every point (see [`Sampler::interpolate_into`]); with
    /// current node positions this gives the points' current positions (m).
    pub fn interpolate(&self, nodal: &[Vec3]) -> Vec<Vec3> {
        let mut out = vec![[0.0; 3]; self.len()];
        self.interpolate_into(nodal, &mut out);
        out
    }
}

fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

/// Uniform grid of element bounding boxes.
struct Grid {
    lo: Vec3,
    cell: f64,
    dims: [usize; 3],
    offsets: Vec<usize>,
    items: Vec<u32>,
}

impl Grid {
    fn new(mesh: &Mesh) -> Self {
        let (lo, hi) = bounds(mesh.nodes());
        let volume: f64 = mesh.volumes().iter().sum();
        // About one element-sized cell per element.
        let cell = (volume / mesh.element_count() as f64).cbrt() * 1.5;
        let dims = std::array::from_fn(|d| (((hi[d] - lo[d]) / cell).floor() as usize + 1).max(1));
        let boxes: Vec<([usize; 3], [usize; 3])> = mesh
            .tets()
            .iter()
            .map(|t| {
                let (a, b) = bounds(&t.map(|v| mesh.nodes()[v as usize]));
                (
                    Self::cell_of(lo, cell, dims, a),
                    Self::cell_of(lo, cell, dims, b),
                )
            })
            .collect();
        let index = |c: [usize; 3]| c[0] + dims[0] * (c[1] + dims[1] * c[2]);
        let mut offsets = vec![0usize; dims[0] * dims[1] * dims[2] + 1];
        let each = |f: &mut dyn FnMut(usize, usize)| {
            for (e, (a, b)) in boxes.iter().enumerate() {
                for k in a[2]..=b[2] {
                    for j in a[1]..=b[1] {
                        for i in a[0]..=b[0] {
                            f(e, index([i, j, k]));
                        }
                    }
                }
            }
        };
        each(&mut |_, c| offsets[c + 1] += 1);
        for c in 0..offsets.len() - 1 {
            offsets[c + 1] += offsets[c];
        }
        let mut fill = offsets.clone();
        let mut items = vec![0u32; *offsets.last().unwrap_or(&0)];
        each(&mut |e, c| {
            items[fill[c]] = e as u32;
            fill[c] += 1;
        });
        Self {
            lo,
            cell,
            dims,
            offsets,
            items,
        }
    }

    fn cell_of(lo: Vec3, cell: f64, dims: [usize; 3], p: Vec3) -> [usize; 3] {
        std::array::from_fn(|d| {
            let c = ((p[d] - lo[d]) / cell).floor();
            if c.is_nan() || c < 0.0 {
                0
            } else {
                (c as usize).min(dims[d] - 1)
            }
        })
    }

    /// Element, clipped barycentric coordinates and distance (m) of the element nearest `p`:
    /// the first containing element found, else the nearest within the cells around `p`,
    /// searched out to `tolerance` beyond one cell.
    fn locate(&self, mesh: &Mesh, p: Vec3, tolerance: f64) -> (usize, [f64; 4], f64) {
        let reach = 1 + (tolerance / self.cell).ceil() as usize;
        let centre = Self::cell_of(self.lo, self.cell, self.dims, p);
        let mut best = (usize::MAX, [0.25; 4], f64::INFINITY);
        let range =
            |d: usize| centre[d].saturating_sub(reach)..=(centre[d] + reach).min(self.dims[d] - 1);
        // The point's own cell first: a containing element there ends the search.
        let own = centre[0] + self.dims[0] * (centre[1] + self.dims[1] * centre[2]);
        for &e in &self.items[self.offsets[own]..self.offsets[own + 1]] {
            let l = mesh.barycentric(e as usize, p);
            if l.iter().all(|&v| v >= 0.0) {
                return (e as usize, l, 0.0);
            }
        }
        for k in range(2) {
            for j in range(1) {
                for i in range(0) {
                    let c = i + self.dims[0] * (j + self.dims[1] * k);
                    for &e in &self.items[self.offsets[c]..self.offsets[c + 1]] {
                        let e = e as usize;
                        let (l, dist) = clip(mesh, e, p);
                        if dist < best.2 || (dist == best.2 && e < best.0) {
                            best = (e, l, dist);
                        }
                    }
                }
            }
        }
        best
    }
}

/// Barycentric coordinates of `p` in element `e` clipped to the element (negative ones set to
/// zero, the rest renormalised), and the distance (m) from `p` to that clipped point.
fn clip(mesh: &Mesh, e: usize, p: Vec3) -> ([f64; 4], f64) {
    let mut l = mesh.barycentric(e, p);
    if l.iter().all(|&v| v >= 0.0) {
        return (l, 0.0);
    }
    for v in &mut l {
        *v = v.max(0.0);
    }
    let s: f64 = l.iter().sum();
    for v in &mut l {
        *v /= s;
    }
    let t = mesh.tets()[e];
    let q: Vec3 =
        std::array::from_fn(|d| (0..4).map(|a| l[a] * mesh.nodes()[t[a] as usize][d]).sum());
    let r = sub(p, q);
    (l, dot(r, r).sqrt())
}
