//! Smoother crack surfaces in the output (issue 13, item 3). A crack can only run along tet
//! faces, so on a lattice mesh it is a staircase of the lattice's few face directions. Here
//! each crack vertex of a frame's [`Surface`] is relaxed towards the plane that the crack
//! faces around it fit (area-weighted mean normal and centroid of the crack faces within two
//! rings), a share at a time over a few passes: steps flatten, while a vertex where the crack
//! faces around it disagree (a piece's corner, a lone tet, both faces of a thin sliver) stays,
//! and so does every piece too small to have a crack plane of its own.
//! A vertex that also touches the outer surface moves only within the outer surface's tangent
//! plane, and not at all where the outer surface has an edge. Each vertex moves at most a share
//! of its shortest edge, and any face turned or shrunk too far has its vertices put back: the
//! surface keeps its connectivity, so a closed, 2-manifold piece stays one. Surface only: the
//! tet mesh and the particles are untouched, so the physics does not move.

use crate::faces::{cross, dot, norm, sub};
use crate::surface::Surface;

/// How far crack faces are relaxed towards their local plane ([`Surface::smooth_cracks`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrackSmoothing {
    /// Relaxation passes (each from the positions the last one left).
    pub passes: usize,
    /// Share of a vertex's distance to its fitted plane moved per pass, in (0, 1].
    pub step: f64,
    /// Least agreement `|sum a_f n_f| / sum a_f` of the crack faces around a vertex for it to
    /// move (1: all parallel; 0.707: two equal faces at right angles; 0: a closed piece).
    pub min_agreement: f64,
    /// Largest distance a vertex may end from where the mesh put it, as a share of its
    /// shortest edge there.
    pub max_move: f64,
    /// Pieces of at most this many faces keep their faces as cut: a piece that small has no
    /// crack plane of its own (two rings around a vertex cover most of it), and relaxing its
    /// crack faces towards their mean would flatten it against its outer faces.
    pub min_piece_faces: usize,
}

impl Default for CrackSmoothing {
    /// Chosen on `perifrac bench look`'s split bar and wall (BENCHMARKS.md, "The look of the
    /// cut").
    fn default() -> Self {
        CrackSmoothing {
            passes: 32,
            step: 0.5,
            min_agreement: 0.6,
            max_move: 1.0,
            // A piece of RIGID_PIECE_TETS tets has at most four faces per tet: every piece a
            // frame puts back rigidly into its rest shape keeps that shape.
            min_piece_faces: 4 * crate::RIGID_PIECE_TETS,
        }
    }
}

/// What [`Surface::smooth_cracks`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SmoothReport {
    /// Vertices that ended somewhere else.
    pub moved: usize,
    /// Vertices held back in some pass because a face around them would have folded over or
    /// shrunk too far.
    pub held: usize,
}

/// A face may turn by less than this much (cosine of 90 degrees) from its unsmoothed normal:
/// a staircase riser turns by up to a right angle towards the crack plane, a face turned
/// further is folded over.
const MIN_NORMAL_COS: f64 = 0.0;
/// A face may keep no less than this share of its unsmoothed area.
const MIN_AREA_SHARE: f64 = 0.1;
/// Outer faces around a vertex agreeing less than this (about 18 degrees apart) make an edge
/// of the outer surface: the vertex stays.
const OUTER_AGREEMENT: f64 = 0.95;

/// Twice the area vector of face `f` at `p`.
fn area_vector(p: &[[f64; 3]], f: &[u32; 3]) -> [f64; 3] {
    let [a, b, c] = f.map(|k| p[k as usize]);
    cross(sub(b, a), sub(c, a))
}

impl Surface {
    /// Relaxes the crack vertices towards their local crack plane as `options` say (module
    /// docs). Deterministic: every pass reads the last pass's positions only.
    pub fn smooth_cracks(&mut self, options: &CrackSmoothing) -> SmoothReport {
        let n = self.vertices.len();
        if options.passes == 0 || !self.crack.iter().any(|&c| c != 0) {
            return SmoothReport::default();
        }
        // Faces around each vertex (CSR), without their corners.
        let (start, around) = self.faces_around_vertices();
        let around: Vec<u32> = around.into_iter().map(|(f, _)| f).collect();
        let faces_at = |v: usize| &around[start[v]..start[v + 1]];
        let original = self.vertices.clone();
        // Shortest edge at each vertex, for the move limit.
        let mut shortest = vec![f64::INFINITY; n];
        for f in &self.faces {
            for k in 0..3 {
                let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
                let l = norm(sub(original[a], original[b]));
                shortest[a] = shortest[a].min(l);
                shortest[b] = shortest[b].min(l);
            }
        }
        let pieces = self
            .piece
            .iter()
            .map(|&p| p as usize + 1)
            .max()
            .unwrap_or(0);
        let mut piece_faces = vec![0usize; pieces];
        for &p in &self.piece {
            piece_faces[p as usize] += 1;
        }
        // The vertices that may move, each with the crack faces within two rings of it (CSR,
        // fixed for all passes), and the faces whose shape a move can change.
        let active: Vec<u32> = (0..n as u32)
            .filter(|&v| {
                faces_at(v as usize).iter().any(|&f| {
                    self.crack[f as usize] != 0
                        && piece_faces[self.piece[f as usize] as usize] > options.min_piece_faces
                })
            })
            .collect();
        if active.is_empty() {
            return SmoothReport::default();
        }
        let mut ring_start = Vec::with_capacity(active.len() + 1);
        let mut rings: Vec<u32> = Vec::new();
        let mut ring: Vec<u32> = Vec::new();
        ring_start.push(0);
        for &v in &active {
            ring.clear();
            for &f in faces_at(v as usize) {
                if self.crack[f as usize] == 0 {
                    continue;
                }
                for &w in &self.faces[f as usize] {
                    ring.extend(
                        faces_at(w as usize)
                            .iter()
                            .filter(|&&g| self.crack[g as usize] != 0),
                    );
                }
            }
            ring.sort_unstable();
            ring.dedup();
            rings.extend_from_slice(&ring);
            ring_start.push(rings.len());
        }
        let mut in_ring = vec![false; self.faces.len()];
        for &g in &rings {
            in_ring[g as usize] = true;
        }
        let ring_faces: Vec<u32> = (0..self.faces.len() as u32)
            .filter(|&g| in_ring[g as usize])
            .collect();
        let mut watched_mark = vec![false; self.faces.len()];
        for &v in &active {
            for &f in faces_at(v as usize) {
                watched_mark[f as usize] = true;
            }
        }
        let watched: Vec<u32> = (0..self.faces.len() as u32)
            .filter(|&f| watched_mark[f as usize])
            .collect();
        // Each watched face's area vector as cut, and its length: what every pass checks
        // against.
        let watched_as_cut: Vec<([f64; 3], f64)> = watched
            .iter()
            .map(|&f| {
                let m = area_vector(&original, &self.faces[f as usize]);
                (m, norm(m))
            })
            .collect();
        // Per pass, each ring face's area vector (twice the area, along the normal), area and
        // area-weighted centroid.
        let mut face_data = vec![([0.0; 3], 0.0, [0.0; 3]); self.faces.len()];
        let mut next = original.clone();
        let mut held = vec![false; n];
        // Stop once no vertex moves more than this in a pass (length): a millionth of the
        // shortest edge that may move.
        let settled = 1e-6
            * active
                .iter()
                .map(|&v| shortest[v as usize])
                .fold(f64::INFINITY, f64::min);
        for _ in 0..options.passes {
            let p = &self.vertices;
            for &g in &ring_faces {
                let face = &self.faces[g as usize];
                let m = area_vector(p, face);
                let a = norm(m);
                let c = face.map(|k| p[k as usize]);
                let centre = std::array::from_fn(|i| a * (c[0][i] + c[1][i] + c[2][i]) / 3.0);
                face_data[g as usize] = (m, a, centre);
            }
            for (i, &v) in active.iter().enumerate() {
                let v = v as usize;
                next[v] = p[v];
                let (mut sum_n, mut sum_a, mut centre) = ([0.0; 3], 0.0, [0.0; 3]);
                for &g in &rings[ring_start[i]..ring_start[i + 1]] {
                    let (m, a, c) = &face_data[g as usize];
                    for k in 0..3 {
                        sum_n[k] += m[k];
                        centre[k] += c[k];
                    }
                    sum_a += a;
                }
                let len = norm(sum_n);
                if sum_a <= 0.0 || len < options.min_agreement * sum_a {
                    continue;
                }
                let normal = sum_n.map(|c| c / len);
                let centre = centre.map(|c| c / sum_a);
                let off = dot(sub(p[v], centre), normal);
                let mut d = normal.map(|c| -options.step * off * c);
                // Touching the outer surface: slide within it, or stay at its edges.
                let (mut outer, mut outer_a) = ([0.0; 3], 0.0);
                for &f in faces_at(v) {
                    if self.crack[f as usize] == 0 {
                        let m = area_vector(p, &self.faces[f as usize]);
                        outer_a += norm(m);
                        for k in 0..3 {
                            outer[k] += m[k];
                        }
                    }
                }
                if outer_a > 0.0 {
                    let l = norm(outer);
                    if l < OUTER_AGREEMENT * outer_a {
                        continue;
                    }
                    let m = outer.map(|c| c / l);
                    let along = dot(d, m);
                    d = std::array::from_fn(|k| d[k] - along * m[k]);
                }
                let mut q: [f64; 3] = std::array::from_fn(|k| p[v][k] + d[k]);
                // Never further than the limit from where the mesh put it.
                let from = sub(q, original[v]);
                let dist = norm(from);
                let limit = options.max_move * shortest[v];
                if dist > limit {
                    q = std::array::from_fn(|k| original[v][k] + from[k] * limit / dist);
                }
                next[v] = q;
            }
            // Undo this pass's move of every vertex of a face it folds over or shrinks too
            // far (against the face as cut), until none does: each pass starts and ends sound.
            loop {
                let mut any = false;
                for (&f, &(was, lw)) in watched.iter().zip(&watched_as_cut) {
                    let f = &self.faces[f as usize];
                    let now = area_vector(&next, f);
                    let ln = norm(now);
                    let bad = lw > 0.0
                        && (ln < MIN_AREA_SHARE * lw || dot(was, now) <= MIN_NORMAL_COS * lw * ln);
                    if bad {
                        for &v in f {
                            let v = v as usize;
                            if next[v] != self.vertices[v] {
                                next[v] = self.vertices[v];
                                held[v] = true;
                                any = true;
                            }
                        }
                    }
                }
                if !any {
                    break;
                }
            }
            // The largest move this pass made (held vertices made none).
            let mut largest = 0.0f64;
            for &v in &active {
                let v = v as usize;
                largest = largest.max(norm(sub(next[v], self.vertices[v])));
                self.vertices[v] = next[v];
            }
            if largest <= settled {
                break;
            }
        }
        SmoothReport {
            moved: (0..n).filter(|&v| self.vertices[v] != original[v]).count(),
            held: held.iter().filter(|&&r| r).count(),
        }
    }
}
