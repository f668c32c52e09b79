//! The candidate pairs of self-contact: vertex-triangle and edge-edge pairs within the band
//! plus a skin, found through a uniform grid and kept until some vertex has moved half the
//! skin away from the vertices' mean move. Pairs that are neighbours in the mesh, or that lie within the inset distance of each
//! other in the rest (material) configuration, are left out when the list is built.
//!
//! The list is derived state: any pair within the band now was within `band + skin` when the
//! list was built (each of its vertices moved less than half the skin beyond the common mean
//! move, and a distance between convex combinations changes by no more than the largest
//! difference of two moves), and the list is sorted, so which step built it changes nothing
//! in what the forces add up to.

use hashbrown::HashMap;
use rayon::prelude::*;

use perifrac_physics::math::{add, norm_squared, scale, sub, Vec3};

use crate::mesh::ShellMesh;
use crate::proximity::{point_triangle_distance, segment_distance};

/// Vertices (or edges) per task when the list is built: fixed, so the tasks and their
/// concatenation do not depend on the thread count.
const CHUNK: usize = 256;

/// Distances (m) that decide which pairs are listed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Reach {
    /// Pairs closer than this repel.
    pub band: f64,
    /// Pairs closer than this at rest are never listed.
    pub inset: f64,
    /// Margin of the list beyond the band.
    pub skin: f64,
}

/// Which vertices share an edge: CSR of sorted neighbours, rebuilt when the mesh changes.
#[derive(Debug, Clone, Default)]
struct Adjacency {
    start: Vec<u32>,
    nbr: Vec<u32>,
}

impl Adjacency {
    fn build(&mut self, mesh: &ShellMesh) {
        let n = mesh.num_vertices();
        self.start.clear();
        self.start.resize(n + 1, 0);
        for e in mesh.edges() {
            self.start[e.v[0] as usize + 1] += 1;
            self.start[e.v[1] as usize + 1] += 1;
        }
        for i in 0..n {
            self.start[i + 1] += self.start[i];
        }
        self.nbr.clear();
        self.nbr.resize(self.start[n] as usize, 0);
        let mut fill: Vec<u32> = self.start[..n].to_vec();
        for e in mesh.edges() {
            for (a, b) in [(e.v[0], e.v[1]), (e.v[1], e.v[0])] {
                self.nbr[fill[a as usize] as usize] = b;
                fill[a as usize] += 1;
            }
        }
        for i in 0..n {
            self.nbr[self.start[i] as usize..self.start[i + 1] as usize].sort_unstable();
        }
    }

    /// `a == b` or `a` and `b` share an edge.
    fn near(&self, a: u32, b: u32) -> bool {
        let row = &self.nbr[self.start[a as usize] as usize..self.start[a as usize + 1] as usize];
        a == b || row.binary_search(&b).is_ok()
    }
}

/// Axis-aligned box `[min, max]` (m).
type Aabb = [Vec3; 2];

fn bounds<const N: usize>(p: [Vec3; N]) -> Aabb {
    let mut b = [p[0], p[0]];
    for q in &p[1..] {
        for k in 0..3 {
            b[0][k] = b[0][k].min(q[k]);
            b[1][k] = b[1][k].max(q[k]);
        }
    }
    b
}

/// A uniform grid over primitives, each filed under every cell its box, padded, overlaps;
/// with cells no smaller than the largest padded box, that is at most 8 cells.
#[derive(Debug, Clone, Default)]
struct Grid {
    inv_cell: f64,
    pad: f64,
    boxes: Vec<Aabb>,
    /// (cell key, primitive), sorted.
    keys: Vec<(u64, u32)>,
    /// Cell key to its range in `keys`.
    cells: HashMap<u64, [u32; 2]>,
}

/// Bits per axis in a cell key; cells further apart than 2^21 share keys, which only adds
/// candidates that the distance test then drops.
const KEY_BITS: u32 = 21;

fn cell_of(p: Vec3, inv: f64) -> [i64; 3] {
    p.map(|c| (c * inv).floor() as i64)
}

fn key(c: [i64; 3]) -> u64 {
    let m = (1u64 << KEY_BITS) - 1;
    ((c[0] as u64 & m) << (2 * KEY_BITS)) | ((c[1] as u64 & m) << KEY_BITS) | (c[2] as u64 & m)
}

impl Grid {
    /// Sets `count` boxes, the `i`-th to `fill(i)`.
    fn set_boxes(&mut self, count: usize, fill: impl Fn(usize) -> Aabb + Sync) {
        self.boxes.resize(count, [[0.0; 3]; 2]);
        self.boxes
            .par_iter_mut()
            .with_min_len(4 * CHUNK)
            .enumerate()
            .for_each(|(i, b)| *b = fill(i));
    }

    /// The box of primitive `i` padded by the grid's pad (m).
    fn padded(&self, i: usize) -> Aabb {
        let b = &self.boxes[i];
        [b[0].map(|c| c - self.pad), b[1].map(|c| c + self.pad)]
    }

    /// The range of cells `[lo, hi]` a padded box overlaps.
    fn range(&self, b: &Aabb) -> [[i64; 3]; 2] {
        [cell_of(b[0], self.inv_cell), cell_of(b[1], self.inv_cell)]
    }

    /// Files the primitives by their boxes padded by `pad` (m) in cells of `cell` (m).
    fn file(&mut self, cell: f64, pad: f64) {
        self.inv_cell = 1.0 / cell;
        self.pad = pad;
        self.keys.clear();
        for i in 0..self.boxes.len() {
            let [lo, hi] = self.range(&self.padded(i));
            for ix in lo[0]..=hi[0] {
                for iy in lo[1]..=hi[1] {
                    for iz in lo[2]..=hi[2] {
                        self.keys.push((key([ix, iy, iz]), i as u32));
                    }
                }
            }
        }
        self.keys.par_sort_unstable();
        self.cells.clear();
        let mut i = 0;
        while i < self.keys.len() {
            let mut j = i + 1;
            while j < self.keys.len() && self.keys[j].0 == self.keys[i].0 {
                j += 1;
            }
            self.cells.insert(self.keys[i].0, [i as u32, j as u32]);
            i = j;
        }
    }

    /// The primitives filed in cell `c`.
    fn in_cell(&self, c: [i64; 3]) -> impl Iterator<Item = u32> + '_ {
        let [lo, hi] = self.cells.get(&key(c)).copied().unwrap_or([0, 0]);
        self.keys[lo as usize..hi as usize].iter().map(|&(_, i)| i)
    }

    fn largest_extent(boxes: &[Aabb]) -> f64 {
        boxes
            .par_iter()
            .with_min_len(4 * CHUNK)
            .map(|b| (0..3).map(|k| b[1][k] - b[0][k]).fold(0.0, f64::max))
            .reduce(|| 0.0, f64::max)
    }
}

fn boxes_within(a: &Aabb, b: &Aabb, r: f64) -> bool {
    (0..3).all(|k| a[0][k] <= b[1][k] + r && b[0][k] <= a[1][k] + r)
}

/// The candidate pairs and what builds them (buffers kept between builds).
#[derive(Debug, Clone)]
pub(crate) struct Candidates {
    reach: Reach,
    /// (vertex, triangle) pairs, sorted.
    pub vf: Vec<[u32; 2]>,
    /// (edge, edge) pairs, the first the lower, sorted.
    pub ee: Vec<[u32; 2]>,
    /// Positions the list was built at (m).
    x_ref: Vec<Vec3>,
    /// False when the mesh may have changed since the adjacency was built.
    topology: bool,
    adjacency: Adjacency,
    triangles: Grid,
    edges: Grid,
    vf_chunks: Vec<Vec<[u32; 2]>>,
    ee_chunks: Vec<Vec<[u32; 2]>>,
    /// Builds so far.
    pub builds: u64,
}

impl Candidates {
    pub fn new(reach: Reach) -> Candidates {
        Candidates {
            reach,
            vf: Vec::new(),
            ee: Vec::new(),
            x_ref: Vec::new(),
            topology: false,
            adjacency: Adjacency::default(),
            triangles: Grid::default(),
            edges: Grid::default(),
            vf_chunks: Vec::new(),
            ee_chunks: Vec::new(),
            builds: 0,
        }
    }

    /// The mesh changed (fracture): the next update rebuilds everything.
    pub fn invalidate(&mut self) {
        self.topology = false;
    }

    /// Rebuilds the list when the mesh changed or a vertex moved half the skin from the mean
    /// move since the last build; returns whether it did.
    pub fn update(&mut self, mesh: &ShellMesh, x: &[Vec3]) -> bool {
        let stale = !self.topology || self.x_ref.len() != x.len() || {
            // Moves are measured from their mean: a pair's distance changes by no more than
            // the difference of its vertices' moves, whatever common part is taken out, so a
            // shell that only travels keeps its list.
            let mut mean = [0.0; 3];
            for (p, q) in x.iter().zip(&self.x_ref) {
                mean = add(mean, sub(*p, *q));
            }
            let mean = scale(mean, 1.0 / x.len().max(1) as f64);
            let limit = 0.25 * self.reach.skin * self.reach.skin;
            x.par_iter()
                .with_min_len(16 * CHUNK)
                .zip(&self.x_ref)
                .any(|(p, q)| norm_squared(sub(sub(*p, *q), mean)) > limit)
        };
        if stale {
            self.build(mesh, x);
        }
        stale
    }

    fn build(&mut self, mesh: &ShellMesh, x: &[Vec3]) {
        if !self.topology || self.x_ref.len() != x.len() {
            self.adjacency.build(mesh);
            self.topology = true;
        }
        self.x_ref.clear();
        self.x_ref.extend_from_slice(x);
        self.builds += 1;
        let reach = self.reach.band + self.reach.skin;
        let tris = mesh.triangles();
        let edges = mesh.edges();
        let tri_at = |t: usize| tris[t].map(|i| x[i as usize]);
        let edge_at = |e: usize| edges[e].v.map(|i| x[i as usize]);
        // Boxes first (the cell size needs the largest), then the grids.
        self.triangles.set_boxes(tris.len(), |t| bounds(tri_at(t)));
        self.edges.set_boxes(edges.len(), |e| bounds(edge_at(e)));
        // Triangles padded by the reach (a vertex within reach of one lies in its padded
        // box), edges by half of it (two within reach overlap once padded).
        let cell = Grid::largest_extent(&self.triangles.boxes) + 2.0 * reach;
        self.triangles.file(cell, reach);
        self.edges.file(cell, 0.5 * reach);

        let Candidates {
            reach: limits,
            adjacency,
            triangles,
            edges: edge_grid,
            vf_chunks,
            ee_chunks,
            vf,
            ee,
            ..
        } = self;
        let rest = mesh.vertices();
        chunked(vf_chunks, vf, x.len(), |v, buf| {
            let p = x[v];
            for t in triangles.in_cell(cell_of(p, triangles.inv_cell)) {
                let b = &triangles.boxes[t as usize];
                if !boxes_within(&[p, p], b, reach)
                    || point_triangle_distance(p, tri_at(t as usize)) >= reach
                {
                    continue;
                }
                let tri = tris[t as usize];
                if tri.iter().any(|&u| adjacency.near(v as u32, u)) {
                    continue;
                }
                let r = tri.map(|i| rest[i as usize]);
                if point_triangle_distance(rest[v], r) < limits.inset {
                    continue;
                }
                buf.push([v as u32, t]);
            }
        });
        chunked(ee_chunks, ee, edges.len(), |e, buf| {
            let pe = edge_grid.padded(e);
            let [a, b] = edges[e].v;
            let [lo, hi] = edge_grid.range(&pe);
            for ix in lo[0]..=hi[0] {
                for iy in lo[1]..=hi[1] {
                    for iz in lo[2]..=hi[2] {
                        let here = [ix, iy, iz];
                        for g in edge_grid.in_cell(here) {
                            let gi = g as usize;
                            if gi <= e {
                                continue;
                            }
                            // Overlapping padded boxes, taken in the one cell that
                            // holds the low corner of their overlap.
                            let pg = edge_grid.padded(gi);
                            if !boxes_within(&pe, &pg, 0.0) {
                                continue;
                            }
                            let corner = [0, 1, 2].map(|k| pe[0][k].max(pg[0][k]));
                            if cell_of(corner, edge_grid.inv_cell) != here {
                                continue;
                            }
                            let [c0, c1] = edges[gi].v;
                            if [c0, c1].iter().any(|&u| {
                                u == a || u == b || adjacency.near(a, u) || adjacency.near(b, u)
                            }) {
                                continue;
                            }
                            if segment_distance(edge_at(e), edge_at(gi)) >= reach {
                                continue;
                            }
                            let rp = [rest[a as usize], rest[b as usize]];
                            let rq = [rest[c0 as usize], rest[c1 as usize]];
                            if segment_distance(rp, rq) < limits.inset {
                                continue;
                            }
                            buf.push([e as u32, g]);
                        }
                    }
                }
            }
        });
    }
}

/// Runs `each(item, buf)` for items `0..count` in fixed chunks of [`CHUNK`] (in parallel, one
/// buffer of `chunks` each), sorts what each item pushed, and writes the buffers in order into
/// `out`: the same list for any thread count.
fn chunked(
    chunks: &mut Vec<Vec<[u32; 2]>>,
    out: &mut Vec<[u32; 2]>,
    count: usize,
    each: impl Fn(usize, &mut Vec<[u32; 2]>) + Sync,
) {
    let used = count.div_ceil(CHUNK);
    if chunks.len() < used {
        chunks.resize_with(used, Vec::new);
    }
    chunks[..used]
        .par_iter_mut()
        .enumerate()
        .for_each(|(c, buf)| {
            buf.clear();
            for item in c * CHUNK..((c + 1) * CHUNK).min(count) {
                let first = buf.len();
                each(item, buf);
                buf[first..].sort_unstable();
            }
        });
    out.clear();
    for buf in &chunks[..used] {
        out.extend_from_slice(buf);
    }
}
