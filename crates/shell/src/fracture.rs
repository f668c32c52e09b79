//! Shell fracture (Gingold et al. 2004): a triangle fails where the principal elastic strain on
//! either face of the shell (`E_m + z E_c` at `z = +-h/2`) passes a threshold, and splits along
//! the line perpendicular to that principal direction through one of its vertices; the
//! neighbour across the split edge is split too, so the crack runs vertex - new point -
//! opposite vertex and opens at the new point. A split point that would fall within `budge` of
//! an edge's end moves that vertex onto the line instead (a vertex budge), its change of strain
//! taken up by the plastic offsets, and the crack follows the existing edge.
//!
//! Cracks are kept as flags on triangle edges. After each round of splits every vertex whose
//! triangles fall into more than one fan once cracked edges are taken out is split into one
//! vertex per fan (as the solid's tet mesh splits vertices), which opens the crack; a crack tip
//! stays one vertex until the crack reaches it again from another side.

use std::collections::BTreeSet;

use rayon::prelude::*;

use perifrac_physics::math::{add, cross, dot, norm, scale, sub, Vec3};

use crate::error::ShellError;
use crate::mesh::{Role, ShellMesh, NONE};
use crate::model::ShellModel;
use crate::plastic::{combine, coordinates};

/// No split or budge makes a triangle with an angle under this (deg); a split that would goes
/// through the nearer vertex instead.
pub const MIN_ANGLE: f64 = 15.0;

/// No split makes an edge shorter than this share of the mesh's shortest edge at the start:
/// splits within splits would otherwise shrink triangles (and the stable step) without bound.
pub const MIN_EDGE_SHARE: f64 = 0.25;

/// When a shell breaks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellFracture {
    /// Principal tensile strain at which a triangle breaks (dimensionless, > 0).
    pub tensile: f64,
    /// Magnitude of the principal compressive strain at which it breaks (dimensionless, > 0;
    /// the paper uses one threshold for both).
    pub compressive: f64,
    /// A split point closer than this share of its edge's length to an end budges that vertex
    /// instead (dimensionless, in [0, 0.5); the tests and benchmarks use 0.25; 0 never
    /// budges).
    pub budge: f64,
    /// Share of the membrane stress across a new crack that the triangles beside it give up
    /// into their plastic offsets (in [0, 1]; 1, as the tests and benchmarks use: a free edge
    /// carries none): the paper's absorption of elastic strain at the crack, which takes the
    /// broken triangles' energy and keeps them from breaking again at once. Bending is not
    /// released (see docs/DECISIONS.md, "Release at the crack").
    pub release: f64,
    /// Fracture energy `G_c` (J/m^2), when the material gives one: a triangle also breaks
    /// where its principal strain passes [`energy_strain`] across its width along the
    /// principal direction (the lower of that and the strain thresholds governs).
    pub energy: Option<f64>,
}

impl ShellFracture {
    /// Checks the thresholds are finite and > 0, `budge` in [0, 0.5) and `release` in [0, 1].
    pub fn new(
        tensile: f64,
        compressive: f64,
        budge: f64,
        release: f64,
    ) -> Result<ShellFracture, ShellError> {
        for (what, value) in [
            ("shell tensile fracture strain", tensile),
            ("shell compressive fracture strain", compressive),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ShellError::BadSetting {
                    what,
                    expected: "finite and > 0",
                    value,
                });
            }
        }
        if !(0.0..0.5).contains(&budge) {
            return Err(ShellError::BadSetting {
                what: "shell budge share",
                expected: "in [0, 0.5)",
                value: budge,
            });
        }
        if !(0.0..=1.0).contains(&release) {
            return Err(ShellError::BadSetting {
                what: "shell release share",
                expected: "in [0, 1]",
                value: release,
            });
        }
        Ok(ShellFracture {
            tensile,
            compressive,
            budge,
            release,
            energy: None,
        })
    }

    /// These settings with the fracture energy `g_c` (J/m^2, finite and > 0) as a threshold
    /// too.
    pub fn with_energy(mut self, g_c: f64) -> Result<ShellFracture, ShellError> {
        if !(g_c.is_finite() && g_c > 0.0) {
            return Err(ShellError::BadSetting {
                what: "shell fracture energy (J/m^2)",
                expected: "finite and > 0",
                value: g_c,
            });
        }
        self.energy = Some(g_c);
        Ok(self)
    }
}

/// The principal strain (1) at which a triangle `width` wide (m) along the principal direction
/// releases `g_c` (J/m^2) per unit area of crack: `sqrt(4 g_c / ((1 - nu^2) young width))`.
///
/// A split runs through a vertex perpendicular to the principal direction, so the triangle's
/// area is half the split's length times `width`. Releasing the stress across the split (as
/// [`ShellFracture::release`] 1 does; a share under 1 raises the threshold by one over its
/// square root) frees `(1 - nu^2) young e^2 / 2` a unit volume under
/// stress along the principal direction alone (the strain along the crack stays). Over the
/// triangle, per unit area of crack, that is `(1 - nu^2) young e^2 width / 4`; setting it to
/// `g_c` gives the threshold (docs/DECISIONS.md, "Shell fracture energy").
pub fn energy_strain(g_c: f64, young: f64, poisson: f64, width: f64) -> f64 {
    (4.0 * g_c / ((1.0 - poisson * poisson) * young * width)).sqrt()
}

/// The width (m) of the triangle with plane points `pts` along the unit direction `dir`.
fn width_along(pts: &[[f64; 2]; 3], dir: [f64; 2]) -> f64 {
    let p = pts.map(|q| q[0] * dir[0] + q[1] * dir[1]);
    p[0].max(p[1]).max(p[2]) - p[0].min(p[1]).min(p[2])
}

/// The largest principal strain of `t` over its threshold, in tension or compression, with its
/// direction. `pts` (the triangle's plane points) and `energy` `(g_c, young, poisson)` give the
/// energy threshold, when the material has one.
fn face_ratio(
    t: [f64; 3],
    params: &ShellFracture,
    energy: Option<(f64, f64, f64, &[[f64; 2]; 3])>,
) -> (f64, [f64; 2]) {
    let [(hi, dhi), (lo, dlo)] = principal(t);
    let limit = |strain: f64, dir: [f64; 2]| match energy {
        // Only `release` of the energy goes at a split: the threshold rises to make up.
        Some((g, e, nu, pts)) => {
            strain.min(energy_strain(g, e, nu, width_along(pts, dir)) / params.release.sqrt())
        }
        None => strain,
    };
    let up = hi / limit(params.tensile, dhi);
    let down = -lo / limit(params.compressive, dlo);
    if down > up {
        (down, dlo)
    } else {
        (up, dhi)
    }
}

/// The fracture state kept with a model: its thresholds and which triangle edges are cracks.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FractureState {
    pub params: ShellFracture,
    /// No split makes an edge shorter than this (m): MIN_EDGE_SHARE of the shortest edge
    /// the mesh had when fracture was switched on.
    pub min_edge: f64,
    /// Per triangle, whether its edge opposite each vertex is a crack.
    pub crack: Vec<[bool; 3]>,
    /// Per triangle, the triangle it was split from (its own index for the shell's own):
    /// splits append, so it is always lower for a split-off one.
    pub split_from: Vec<u32>,
}

/// One triangle that broke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractureEvent {
    /// The triangle (index before the round's changes).
    pub face: usize,
    /// Its principal strain over the threshold (> 1).
    pub ratio: f64,
    /// Whether a vertex was budged (moved onto the line) instead of a new one made; false also
    /// when the crack went along an existing edge without moving a vertex.
    pub budged: bool,
}

/// What a round of fracture did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FractureReport {
    /// The triangles that broke, in the order they were split.
    pub events: Vec<FractureEvent>,
    /// For each vertex added (in order, after the old ones), the two vertices it came from:
    /// the ends of the edge it was put on, or the vertex it was split from twice.
    pub added: Vec<[u32; 2]>,
    /// Whether the mesh or the rest state changed (also when no triangle broke but some
    /// beside a crack gave up the stress across it).
    pub changed: bool,
}

/// The eigenvalues of a symmetric 2x2 `[xx, yy, xy]`, largest first, with the unit eigenvector
/// of each.
fn principal(t: [f64; 3]) -> [(f64, [f64; 2]); 2] {
    let mean = 0.5 * (t[0] + t[1]);
    let half = 0.5 * (t[0] - t[1]);
    let r = (half * half + t[2] * t[2]).sqrt();
    [mean + r, mean - r].map(|lambda| {
        let (a, b) = ([t[2], lambda - t[0]], [lambda - t[1], t[2]]);
        let v = if a[0] * a[0] + a[1] * a[1] >= b[0] * b[0] + b[1] * b[1] {
            a
        } else {
            b
        };
        let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
        if l > 0.0 {
            (lambda, [v[0] / l, v[1] / l])
        } else {
            (lambda, [1.0, 0.0])
        }
    })
}

/// The rest triangle's vertices in its plane's frame (the frame of its strains: `u` along
/// `p0 -> p1`, `w = n x u`).
fn plane_points(p: [Vec3; 3]) -> [[f64; 2]; 3] {
    let e = sub(p[1], p[0]);
    let u = scale(e, 1.0 / norm(e));
    let n = cross(e, sub(p[2], p[0]));
    let w = cross(scale(n, 1.0 / norm(n)), u);
    let d = sub(p[2], p[0]);
    [[0.0, 0.0], [norm(e), 0.0], [dot(d, u), dot(d, w)]]
}

#[inline]
fn lerp(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    add(a, scale(sub(b, a), t))
}

/// The arrays a round of fracture edits.
struct Edit {
    rest: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
    ps: Vec<[f64; 3]>,
    pphi: Vec<[f64; 3]>,
    crack: Vec<[bool; 3]>,
    split_from: Vec<u32>,
    added: Vec<[u32; 2]>,
}

impl Edit {
    /// Splits triangle `f` from its vertex `i` to the point `q` (already made) at `t` along its
    /// opposite edge (from vertex `i + 1` to `i + 2`): `f` keeps `(v, a, q)`, a new triangle
    /// takes `(v, q, b)`; the new edge is a crack; plastic offsets carry over (the new edge's
    /// squared-length offset from the triangle's plastic metric, exact for a uniform one).
    fn split(&mut self, f: usize, i: usize, q: u32, t: f64) {
        let tri = self.tris[f];
        let (v, a, b) = (tri[i], tri[(i + 1) % 3], tri[(i + 2) % 3]);
        let (ev, ea, eb) = (i, (i + 1) % 3, (i + 2) % 3);
        let ps = self.ps[f];
        let pphi = self.pphi[f];
        let crack = self.crack[f];
        let new_edge = ps[eb] + t * t * ps[ev] + t * (ps[ea] - ps[eb] - ps[ev]);
        self.tris[f] = [v, a, q];
        self.ps[f] = [t * t * ps[ev], new_edge, ps[eb]];
        self.pphi[f] = [pphi[ev], 0.0, pphi[eb]];
        self.crack[f] = [crack[ev], true, crack[eb]];
        let u = 1.0 - t;
        self.tris.push([v, q, b]);
        self.split_from.push(f as u32);
        self.ps.push([u * u * ps[ev], ps[ea], new_edge]);
        self.pphi.push([pphi[ev], pphi[ea], 0.0]);
        self.crack.push([crack[ev], crack[ea], true]);
    }

    /// Marks the edge `(a, b)` a crack in every triangle that has it.
    fn mark(&mut self, a: u32, b: u32, faces: &[u32]) {
        for &f in faces {
            if f == NONE {
                continue;
            }
            let t = self.tris[f as usize];
            for k in 0..3 {
                let (p, q) = (t[(k + 1) % 3], t[(k + 2) % 3]);
                if (p == a && q == b) || (p == b && q == a) {
                    self.crack[f as usize][k] = true;
                }
            }
        }
    }
}

impl ShellModel {
    /// The same shell breaking as `params` says (it keeps plastic offsets for the budges).
    pub fn with_fracture(mut self, params: ShellFracture) -> ShellModel {
        let nf = self.faces.len();
        if self.plastic.is_none() {
            self.plastic = Some(crate::plastic::PlasticState::new(None, nf));
        }
        let shortest = self
            .rest_length2
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min)
            .sqrt();
        self.fracture = Some(FractureState {
            params,
            min_edge: MIN_EDGE_SHARE * shortest,
            crack: vec![[false; 3]; nf],
            split_from: (0..nf as u32).collect(),
        });
        self
    }

    /// The fracture thresholds, when the shell breaks.
    pub fn fracture_params(&self) -> Option<ShellFracture> {
        self.fracture.as_ref().map(|f| f.params)
    }

    /// Per triangle, whether its edge opposite each vertex is a crack (empty for a shell that
    /// does not break).
    pub fn crack_edges(&self) -> &[[bool; 3]] {
        self.fracture.as_ref().map_or(&[], |f| &f.crack)
    }

    /// Per triangle, the triangle it was split from: its own index for a triangle the shell
    /// started with, a lower one for a triangle a fracture split off (empty for a shell that
    /// does not break). Following it from a triangle down to an index under an earlier
    /// triangle count gives the triangle it was part of then.
    pub fn split_from(&self) -> &[u32] {
        self.fracture.as_ref().map_or(&[], |f| &f.split_from)
    }

    /// The triangle that triangle `t` was part of when the mesh had `count` triangles (`t`
    /// itself when `t < count`), following [`ShellModel::split_from`] down.
    pub fn part_of(&self, t: usize, count: usize) -> usize {
        let from = self.split_from();
        let mut t = t;
        while t >= count {
            // splits append, so every split-off triangle's origin is a lower index
            debug_assert!((from[t] as usize) < t);
            t = from[t] as usize;
        }
        t
    }

    /// Each triangle's largest principal elastic strain on either face of the shell over its
    /// threshold (tensile or compressive): above 1 it breaks; with the principal direction in
    /// its rest frame. Empty for a shell that does not break.
    pub fn fracture_ratios(&mut self, x: &[Vec3]) -> Result<Vec<(f64, [f64; 2])>, ShellError> {
        self.check_positions(x.len())?;
        let Some(params) = self.fracture.as_ref().map(|fs| fs.params) else {
            return Ok(Vec::new());
        };
        self.edge_pass(x);
        Ok((0..self.faces.len())
            .map(|f| self.triangle_ratio(f, &params))
            .collect())
    }

    /// Triangle `f`'s largest principal elastic strain on either face over its threshold, with
    /// the principal direction in its rest frame, from the last edge pass.
    fn triangle_ratio(&self, f: usize, params: &ShellFracture) -> (f64, [f64; 2]) {
        let r = &self.faces[f];
        let e = self.mesh.face_edges()[f];
        let mut s = e.map(|k| self.edge_work[k as usize].s);
        let mut d = e.map(|k| self.edge_work[k as usize].dphi);
        if let Some(p) = &self.plastic {
            for k in 0..3 {
                s[k] -= p.s[f][k];
                d[k] -= p.phi[f][k];
            }
        }
        let (em, ec) = (combine(&r.m, s), combine(&r.n, d));
        let rest = self.mesh.vertices();
        let pts = params
            .energy
            .map(|_| plane_points(self.mesh.triangles()[f].map(|i| rest[i as usize])));
        let (young, nu) = (self.material.young, self.material.poisson);
        let energy = params
            .energy
            .zip(pts.as_ref())
            .map(|(g, p)| (g, young, nu, p));
        let h = self.material.thickness;
        let mut best = (0.0, [1.0, 0.0]);
        for z in [0.5 * h, -0.5 * h] {
            let t = [em[0] + z * ec[0], em[1] + z * ec[1], em[2] + z * ec[2]];
            // The largest tension against the tensile threshold and the largest compression
            // against the compressive one: both, as they may differ.
            let (ratio, dir) = face_ratio(t, params, energy);
            if ratio > best.0 {
                best = (ratio, dir);
            }
        }
        best
    }

    /// Breaks every triangle over its threshold at positions `x` (m), velocities `v` (m/s):
    /// splits (or budges), opens the cracks by splitting vertices, and rebuilds the rest state.
    /// `x` and `v` grow by the vertices added; the report says where each came from. Nothing
    /// happens for a shell that does not break or when no triangle is over; on an error the
    /// model, `x` and `v` are left as they were.
    pub fn fracture(
        &mut self,
        x: &mut Vec<Vec3>,
        v: &mut Vec<Vec3>,
    ) -> Result<FractureReport, ShellError> {
        if self.fracture.is_none() || self.worst_fracture_ratio(x)? <= 1.0 {
            return Ok(FractureReport::default());
        }
        let (mut xs, mut vs) = (x.clone(), v.clone());
        let report = self.fracture_into(&mut xs, &mut vs)?;
        *x = xs;
        *v = vs;
        Ok(report)
    }

    /// The largest of [`ShellModel::fracture_ratios`] at `x` (0 for a shell that does not
    /// break), computed in parallel without allocating.
    pub fn worst_fracture_ratio(&mut self, x: &[Vec3]) -> Result<f64, ShellError> {
        self.check_positions(x.len())?;
        let Some(params) = self.fracture.as_ref().map(|fs| fs.params) else {
            return Ok(0.0);
        };
        self.edge_pass(x);
        let this = &*self;
        Ok((0..this.faces.len())
            .into_par_iter()
            .with_min_len(512)
            .map(|f| this.triangle_ratio(f, &params).0)
            .reduce(|| 0.0, f64::max))
    }

    fn fracture_into(
        &mut self,
        x: &mut Vec<Vec3>,
        v: &mut Vec<Vec3>,
    ) -> Result<FractureReport, ShellError> {
        let ratios = self.fracture_ratios(x)?;
        let mut over: Vec<(usize, f64, [f64; 2])> = ratios
            .iter()
            .enumerate()
            .filter(|(_, r)| r.0 > 1.0)
            .map(|(f, r)| (f, r.0, r.1))
            .collect();
        let mut report = FractureReport::default();
        if over.is_empty() {
            return Ok(report);
        }
        // The most strained first; ties by index: the same order for any thread count.
        over.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let (Some(fs), Some(pl)) = (&self.fracture, &self.plastic) else {
            return Ok(report);
        };
        let budge = fs.params.budge;
        let min_edge = fs.min_edge;
        let nf = self.faces.len();
        let n0 = x.len();
        // Elastic coordinates before the round, for the triangles a budge changes.
        let elastic: Vec<([f64; 3], [f64; 3])> = {
            let fe = self.mesh.face_edges();
            (0..nf)
                .map(|f| {
                    let e = fe[f];
                    let mut s = e.map(|k| self.edge_work[k as usize].s);
                    let mut d = e.map(|k| self.edge_work[k as usize].dphi);
                    for k in 0..3 {
                        s[k] -= pl.s[f][k];
                        d[k] -= pl.phi[f][k];
                    }
                    (s, d)
                })
                .collect()
        };
        let mesh = &self.mesh;
        let mut on_boundary = vec![false; n0];
        for e in mesh.edges() {
            if e.is_boundary() {
                on_boundary[e.v[0] as usize] = true;
                on_boundary[e.v[1] as usize] = true;
            }
        }
        let mut edit = Edit {
            rest: mesh.vertices().to_vec(),
            tris: mesh.triangles().to_vec(),
            ps: pl.s.clone(),
            pphi: pl.phi.clone(),
            crack: fs.crack.clone(),
            split_from: fs.split_from.clone(),
            added: Vec::new(),
        };
        let mut touched = vec![false; nf];
        let mut absorb: BTreeSet<usize> = BTreeSet::new();
        // The triangles beside a new crack, with the crack's rest direction: the stress across
        // the crack goes (`release` of it).
        let mut released: std::collections::BTreeMap<usize, Vec3> = Default::default();
        for &(f, ratio, dir) in &over {
            if touched[f] {
                continue;
            }
            let tri = mesh.triangles()[f];
            let pts = plane_points(tri.map(|i| mesh.vertices()[i as usize]));
            let proj = pts.map(|p| p[0] * dir[0] + p[1] * dir[1]);
            // The line through a vertex perpendicular to `dir` crosses the opposite edge
            // only for the vertex whose projection lies between the other two.
            let i = (0..3)
                .find(|&i| {
                    let (a, b) = (proj[(i + 1) % 3], proj[(i + 2) % 3]);
                    (a.min(b)..=a.max(b)).contains(&proj[i])
                })
                .unwrap_or(0);
            let (pa, pb) = (proj[(i + 1) % 3], proj[(i + 2) % 3]);
            let t = if pb != pa {
                ((proj[i] - pa) / (pb - pa)).clamp(0.0, 1.0)
            } else {
                0.5
            };
            let (vv, a, b) = (tri[i], tri[(i + 1) % 3], tri[(i + 2) % 3]);
            let edge = mesh.edges()[mesh.face_edges()[f][i] as usize];
            let g = if edge.faces[0] as usize == f {
                edge.faces[1]
            } else {
                edge.faces[0]
            };
            if g != NONE && touched[g as usize] {
                continue;
            }
            let (ra, rb, rv) = (
                mesh.vertices()[a as usize],
                mesh.vertices()[b as usize],
                mesh.vertices()[vv as usize],
            );
            let rq = lerp(ra, rb, t);
            // A split whose pieces would have an angle under MIN_ANGLE (the secondary split's
            // included), or that falls within `budge` of an end, goes through the nearer end
            // instead.
            let short = |p: Vec3| norm(sub(p, rq)) < min_edge;
            let mut sliver = min_angle([rv, ra, rq]).min(min_angle([rv, rq, rb])) < MIN_ANGLE
                || short(rv)
                || short(ra)
                || short(rb);
            if g != NONE {
                let gt = mesh.triangles()[g as usize];
                if let Some(&w) = gt.iter().find(|&&w| w != a && w != b) {
                    let rw = mesh.vertices()[w as usize];
                    sliver |= min_angle([rw, rb, rq]).min(min_angle([rw, rq, ra])) < MIN_ANGLE
                        || short(rw);
                }
            }
            let near = if t < budge || (sliver && t < 0.5) {
                Some(a)
            } else if t > 1.0 - budge || sliver {
                Some(b)
            } else {
                None
            };
            if let Some(c) = near {
                // Moving c changes every edge whose four-vertex stencil holds it: the
                // triangles on both sides of those take the change.
                let around: Vec<usize> = faces_of_stencil(mesh, c);
                if around.iter().any(|&g| touched[g]) {
                    continue;
                }
                // The crack runs along (v, c) and, unless c is on a boundary (where one cut
                // edge opens it), on along the edge from c that best continues the line, so
                // that c opens.
                let mut cut = vec![(vv, c)];
                if !on_boundary[c as usize] {
                    if let Some(u) = continuation(mesh, vv, c) {
                        cut.push((c, u));
                    }
                }
                let fresh = cut.iter().any(|&(p, q)| !is_crack(mesh, &edit, p, q));
                if !fresh {
                    // The line runs along a crack already there: the triangle is beside it and
                    // the crack cannot take the stress across it, so that stress goes (as for
                    // the triangles beside a new crack); nothing breaks.
                    released.insert(f, sub(edit.rest[c as usize], rv));
                    touched[f] = true;
                    continue;
                }
                // Budge: c moves onto the line (rest and current positions) when it is not on
                // a boundary and no triangle around it would get an angle under MIN_ANGLE or
                // turn over.
                let with_c = faces_around(mesh, c);
                let moved = !on_boundary[c as usize] && budge_keeps_quality(mesh, &with_c, c, rq);
                if moved {
                    edit.rest[c as usize] = rq;
                    x[c as usize] = lerp(x[a as usize], x[b as usize], t);
                    absorb.extend(around.iter().copied());
                }
                for &(p, q) in &cut {
                    let faces = faces_around(mesh, p);
                    let along = sub(edit.rest[q as usize], edit.rest[p as usize]);
                    for &g in &faces {
                        if mesh.triangles()[g].contains(&q) {
                            released.insert(g, along);
                        }
                    }
                    let faces: Vec<u32> = faces.iter().map(|&f| f as u32).collect();
                    edit.mark(p, q, &faces);
                }
                for &g in &around {
                    touched[g] = true;
                }
                report.events.push(FractureEvent {
                    face: f,
                    ratio,
                    budged: moved,
                });
                continue;
            }
            let q = (n0 + edit.added.len()) as u32;
            edit.rest.push(rq);
            x.push(lerp(x[a as usize], x[b as usize], t));
            v.push(lerp(v[a as usize], v[b as usize], t));
            edit.added.push([a, b]);
            edit.split(f, i, q, t);
            touched[f] = true;
            touched.push(true);
            released.insert(f, sub(rq, rv));
            released.insert(edit.tris.len() - 1, sub(rq, rv));
            if g != NONE {
                let gt = edit.tris[g as usize];
                // g runs b -> a; its vertex opposite the edge splits it from b towards a.
                let j = (0..3)
                    .find(|&j| gt[(j + 1) % 3] == b && gt[(j + 2) % 3] == a)
                    .unwrap_or(0);
                edit.split(g as usize, j, q, 1.0 - t);
                touched[g as usize] = true;
                touched.push(true);
                let along = sub(rq, edit.rest[edit.tris[g as usize][j] as usize]);
                released.insert(g as usize, along);
                released.insert(edit.tris.len() - 1, along);
            }
            report.events.push(FractureEvent {
                face: f,
                ratio,
                budged: false,
            });
        }
        report.changed = true;
        // A round that only releases stress beside cracks already there (no split, no budge)
        // leaves the mesh as it is: only the plastic offsets change, below.
        if !report.events.is_empty() {
            open_cracks(&mut edit, x, v);
            report.added = edit.added.clone();
            let Edit {
                rest,
                tris,
                ps,
                pphi,
                crack,
                split_from,
                ..
            } = edit;
            let mesh = ShellMesh::new(rest, tris)?;
            self.rebuild(mesh, Some((ps, pphi)))?;
            if let Some(fs) = &mut self.fracture {
                fs.crack = crack;
                fs.split_from = split_from;
            }
        }
        // A budge changes the strains of the triangles around the vertex; the plastic offsets
        // take the change, so their elastic strain coordinates stay as they were.
        // Then the triangles beside the new cracks lose `release` of the membrane stress
        // across the crack (the paper's absorption of elastic strain at the crack, limited to
        // what a free edge cannot carry): the energy that broke them goes, the strain along
        // the crack stays, and they do not break again at once on the strain they had. Their
        // bending offsets are left alone: taking the curvature at a kink as the rest shape
        // made the small triangles beside cracks run away (docs/DECISIONS.md, "Release at the
        // crack").
        let release = self.fracture.as_ref().map_or(0.0, |f| f.params.release);
        if !absorb.is_empty() || (release > 0.0 && !released.is_empty()) {
            self.edge_pass(x);
            let (fe, edges) = (self.mesh.face_edges(), self.mesh.edges());
            if let Some(pl) = &mut self.plastic {
                for &f in &absorb {
                    for (k, &e) in fe[f].iter().enumerate() {
                        pl.s[f][k] = self.edge_work[e as usize].s - elastic[f].0[k];
                        pl.phi[f][k] = if edges[e as usize].is_boundary() {
                            0.0
                        } else {
                            self.edge_work[e as usize].dphi - elastic[f].1[k]
                        };
                    }
                }
                let nu = self.material.poisson;
                let rest = self.mesh.vertices();
                for (&f, &along) in &released {
                    let t = self.mesh.triangles()[f].map(|i| rest[i as usize]);
                    let r = &self.faces[f];
                    let dir = in_plane(t, along);
                    let s: [f64; 3] = fe[f].map(|e| self.edge_work[e as usize].s);
                    let es = [s[0] - pl.s[f][0], s[1] - pl.s[f][1], s[2] - pl.s[f][2]];
                    let keep = coordinates(&r.m, free_edge(combine(&r.m, es), dir, nu));
                    for k in 0..3 {
                        pl.s[f][k] += release * (es[k] - keep[k]);
                        // A boundary edge (the new crack's among them) bends freely: no
                        // bending offset there.
                        if edges[fe[f][k] as usize].is_boundary() {
                            pl.phi[f][k] = 0.0;
                        }
                    }
                }
            }
        }
        Ok(report)
    }
}

/// The unit direction, in the rest frame of triangle `p` (`u` along `p0 -> p1`, `w = n x u`),
/// of the rest vector `d`.
fn in_plane(p: [Vec3; 3], d: Vec3) -> [f64; 2] {
    let e = sub(p[1], p[0]);
    let u = scale(e, 1.0 / norm(e));
    let n = cross(e, sub(p[2], p[0]));
    let w = cross(scale(n, 1.0 / norm(n)), u);
    let (a, b) = (dot(d, u), dot(d, w));
    let l = (a * a + b * b).sqrt();
    if l > 0.0 {
        [a / l, b / l]
    } else {
        [1.0, 0.0]
    }
}

/// The strain `[xx, yy, xy]` left when a free edge along unit `t` sheds the stress across it
/// (plane stress, Poisson's ratio `nu`): the strain along the edge `e_tt` stays (its
/// neighbours along the crack hold it), and the rest takes the values that carry no traction
/// across, `e_nn = -nu e_tt` and `e_tn = 0`, so `e_tt (t t - nu n n)`: the least membrane energy
/// with that `e_tt`, so a release never adds energy. (Keeping the stress along the edge instead
/// can add energy: releasing again and again, a triangle beside a crack pumped it up.)
fn free_edge(e: [f64; 3], t: [f64; 2], nu: f64) -> [f64; 3] {
    let n = [-t[1], t[0]];
    let s = t[0] * t[0] * e[0] + t[1] * t[1] * e[1] + 2.0 * t[0] * t[1] * e[2];
    [
        s * (t[0] * t[0] - nu * n[0] * n[0]),
        s * (t[1] * t[1] - nu * n[1] * n[1]),
        s * (t[0] * t[1] - nu * n[0] * n[1]),
    ]
}

/// The smallest interior angle (deg) of a triangle.
fn min_angle(p: [Vec3; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let a = sub(p[(k + 1) % 3], p[k]);
            let b = sub(p[(k + 2) % 3], p[k]);
            let c = dot(a, b) / (dot(a, a) * dot(b, b)).sqrt();
            c.clamp(-1.0, 1.0).acos().to_degrees()
        })
        .fold(180.0, f64::min)
}

/// The triangles that have vertex `c`.
fn faces_around(mesh: &ShellMesh, c: u32) -> Vec<usize> {
    let mut out: Vec<usize> = mesh
        .stencil(c as usize)
        .iter()
        .filter(|(_, role)| matches!(role, Role::Start | Role::End))
        .flat_map(|&(k, _)| mesh.edges()[k as usize].faces)
        .filter(|&g| g != NONE)
        .map(|g| g as usize)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// The triangles beside every edge whose four-vertex stencil holds vertex `c`.
fn faces_of_stencil(mesh: &ShellMesh, c: u32) -> Vec<usize> {
    let mut out: Vec<usize> = mesh
        .stencil(c as usize)
        .iter()
        .flat_map(|&(k, _)| mesh.edges()[k as usize].faces)
        .filter(|&g| g != NONE)
        .map(|g| g as usize)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Whether the edge `(p, q)` is already a crack in a triangle that has it.
fn is_crack(mesh: &ShellMesh, edit: &Edit, p: u32, q: u32) -> bool {
    faces_around(mesh, p).iter().any(|&f| {
        let t = edit.tris[f];
        (0..3).any(|k| {
            let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            ((a == p && b == q) || (a == q && b == p)) && edit.crack[f][k]
        })
    })
}

/// The neighbour `u` of `c` whose edge best continues the direction from `v` to `c` (rest
/// positions): the largest cosine, if any neighbour is ahead at all.
fn continuation(mesh: &ShellMesh, v: u32, c: u32) -> Option<u32> {
    let x = mesh.vertices();
    let dir = sub(x[c as usize], x[v as usize]);
    let mut best: Option<(f64, u32)> = None;
    for &(k, role) in mesh.stencil(c as usize) {
        let e = mesh.edges()[k as usize];
        let u = match role {
            Role::Start => e.v[1],
            Role::End => e.v[0],
            _ => continue,
        };
        if u == v {
            continue;
        }
        let d = sub(x[u as usize], x[c as usize]);
        let cos = dot(d, dir) / (dot(d, d) * dot(dir, dir)).sqrt();
        if cos > 0.0 && best.is_none_or(|(b, _)| cos > b) {
            best = Some((cos, u));
        }
    }
    best.map(|(_, u)| u)
}

/// Whether moving vertex `c` to rest position `target` keeps every triangle around it above
/// MIN_ANGLE and facing the same way.
fn budge_keeps_quality(mesh: &ShellMesh, around: &[usize], c: u32, target: Vec3) -> bool {
    let x = mesh.vertices();
    around.iter().all(|&f| {
        let t = mesh.triangles()[f];
        let old = t.map(|i| x[i as usize]);
        let new = t.map(|i| if i == c { target } else { x[i as usize] });
        let n0 = cross(sub(old[1], old[0]), sub(old[2], old[0]));
        let n1 = cross(sub(new[1], new[0]), sub(new[2], new[0]));
        dot(n0, n1) > 0.0 && min_angle(new) >= MIN_ANGLE
    })
}

/// Splits every vertex whose triangles form more than one fan once the cracked edges are taken
/// out: the fan holding its lowest-numbered triangle keeps the vertex, each other fan gets a
/// copy (rest and current position, velocity).
fn open_cracks(edit: &mut Edit, x: &mut Vec<Vec3>, v: &mut Vec<Vec3>) {
    let n = edit.rest.len();
    let mut start = vec![0usize; n + 1];
    for t in &edit.tris {
        for &i in t {
            start[i as usize + 1] += 1;
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around = vec![0usize; start[n]];
    for (f, t) in edit.tris.iter().enumerate() {
        for &i in t {
            around[fill[i as usize]] = f;
            fill[i as usize] += 1;
        }
    }
    let mut parent: Vec<usize> = Vec::new();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for vert in 0..n {
        let faces = &around[start[vert]..start[vert + 1]];
        if faces.len() < 2 {
            continue;
        }
        parent.clear();
        parent.extend(0..faces.len());
        // Two triangles at this vertex join through an edge (vert, o) they share unless
        // either marks it cracked.
        for (k1, &f1) in faces.iter().enumerate() {
            for (k2, &f2) in faces.iter().enumerate().skip(k1 + 1) {
                let (t1, t2) = (edit.tris[f1], edit.tris[f2]);
                for l1 in 0..3 {
                    let o = t1[l1];
                    if o as usize == vert || !t2.contains(&o) {
                        continue;
                    }
                    let l2 = (0..3).find(|&l| t2[l] != o && t2[l] as usize != vert);
                    let Some(l2) = l2 else { continue };
                    // The shared edge (vert, o) is opposite the third vertex in each triangle.
                    let e1 = (0..3).find(|&l| t1[l] != o && t1[l] as usize != vert);
                    let Some(e1) = e1 else { continue };
                    if edit.crack[f1][e1] || edit.crack[f2][l2] {
                        continue;
                    }
                    let (r1, r2) = (root(&mut parent, k1), root(&mut parent, k2));
                    parent[r1] = r2;
                }
            }
        }
        let mut fans: Vec<usize> = (0..faces.len())
            .map(|k| root(&mut parent, k))
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        if fans.len() < 2 {
            continue;
        }
        // The fan of the lowest-numbered triangle keeps the vertex.
        let first = root(&mut parent, 0);
        fans.retain(|&r| r != first);
        for r in fans {
            let copy = edit.rest.len() as u32;
            edit.rest.push(edit.rest[vert]);
            x.push(x[vert]);
            v.push(v[vert]);
            edit.added.push([vert as u32, vert as u32]);
            for (k, &f) in faces.iter().enumerate() {
                if root(&mut parent, k) == r {
                    for i in edit.tris[f].iter_mut() {
                        if *i as usize == vert {
                            *i = copy;
                        }
                    }
                }
            }
        }
    }
}
