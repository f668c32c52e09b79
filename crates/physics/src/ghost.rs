//! Ghost particles across a body's flat faces (issue 18; docs/DECISIONS.md, "Ghost particles
//! across the faces"): the families a face cuts are completed by mirror images of the particles
//! within a horizon of it, whose displacements are fixed linear combinations of real ones.
//!
//! A free face's ghost `g`, the image of particle `p`, moves as `u_p + F_p (X_g - X_p)` (with
//! [`GhostFit::Quadratic`] the fit's second-order terms as well), `F_p` the least-squares
//! gradient of the displacement over `p`'s real family (weights `omega V_j`,
//! `omega = delta / r`). A clamped face's ghost moves as minus its source (the odd image: zero
//! displacement on the face, to first order). Either way `y_g = s_g + sum_k c_gk y_k` over real
//! particles `k`: an affine map of the real positions, so the energy stays a function of the
//! real particles, the force on real `k` gains `c_gk f_g` from each ghost that reads it (the
//! transpose of the map, gathered per real particle, so no atomics), and a free face's ghosts,
//! exact for every affine field, keep the energy objective.
//!
//! The ghosts join the families of the real particles within a horizon of them as passive
//! particles appended after the real ones ([`crate::ChenModel::with_passive`]): they store no
//! energy and carry no force state, so the model's loops run unchanged over the extended
//! families, and [`Ghosted`] shows the integrators the real particles only. Under fracture a
//! ghost is dropped once its source's family loses a bond (docs/DECISIONS.md, "Ghosts under
//! fracture and plasticity").

use perifrac_checkpoint::{expect_count, CheckpointError, Reader, Writer};
use rayon::prelude::*;

use crate::error::PhysicsError;
use crate::family::Family;
use crate::fracture::Damage;
use crate::material::fit::cholesky_solve;
use crate::material::{ChenMaterial, ChenModel, ChenOptions, ForceModel, Spread};
use crate::math::{add, axpy, dot, norm, norm_squared, scale, sub, Vec3};
use crate::par::map_particles;
use crate::particles::Discretization;

/// How a face treats what lies beyond it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaceKind {
    /// A free face: its ghosts continue the displacement fitted over their source's family.
    Free,
    /// A clamped face: its ghosts move as minus their source, so the displacement vanishes on
    /// the face (to first order); images of the free faces' ghosts near it included.
    Clamped,
}

/// A flat face of the body: a point on it (m), its outward normal (any length) and its kind.
/// The plane is taken as unbounded: every particle within a horizon inside it is mirrored, so
/// the faces given must bound the body where it lies within a horizon of them (a box's faces).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GhostPlane {
    /// A point on the face (m).
    pub point: Vec3,
    /// The outward normal (non-zero; normalised on use).
    pub normal: Vec3,
    /// Free or clamped.
    pub kind: FaceKind,
}

impl GhostPlane {
    /// The six faces of the axis-aligned box `[min, max]` (m), all free, in the order -x, +x,
    /// -y, +y, -z, +z.
    pub fn box_faces(min: Vec3, max: Vec3) -> [GhostPlane; 6] {
        std::array::from_fn(|f| {
            let (axis, high) = (f / 2, f % 2 == 1);
            let mut point = min;
            let mut normal = [0.0; 3];
            if high {
                point = max;
            }
            normal[axis] = if high { 1.0 } else { -1.0 };
            GhostPlane {
                point,
                normal,
                kind: FaceKind::Free,
            }
        })
    }
}

/// Where a body's faces are, for [`GhostLayer::build_with`]: the faces near a point and
/// whether a point lies inside the body. A list of planes is one ([`GhostLayer::build`]: unbounded
/// planes, nothing inside); a mesh's boundary another (`perifrac_topology::BoundaryPlanes` gives its planes).
pub trait GhostFaces: Sync {
    /// Appends to `out` the faces within `horizon` (m) of the point `x` (m), nearest first
    /// where the order matters (only the first three free ones are mirrored across).
    fn near(&self, x: Vec3, horizon: f64, out: &mut Vec<GhostPlane>);

    /// Whether `x` (m) lies inside the body: an image there is dropped.
    fn inside(&self, x: Vec3) -> bool {
        let _ = x;
        false
    }

    /// Whether [`GhostFaces::near`] can give a clamped face at all (false spares the build a
    /// query at every free image's position).
    fn has_clamped(&self) -> bool {
        true
    }
}

/// A list of planes as [`GhostFaces`]: every one of them, unbounded, for every point
/// ([`GhostLayer::build_with`] keeps those the point lies within a horizon inside).
struct Planes<'a>(&'a [GhostPlane]);

impl GhostFaces for Planes<'_> {
    fn near(&self, _x: Vec3, _horizon: f64, out: &mut Vec<GhostPlane>) {
        out.extend_from_slice(self.0);
    }

    fn has_clamped(&self) -> bool {
        self.0.iter().any(|p| p.kind == FaceKind::Clamped)
    }
}

/// The field a free face's ghost extrapolates from its source's family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GhostFit {
    /// The least-squares gradient: exact for affine fields.
    Affine,
    /// Gradient and second derivatives: exact for quadratic fields (bending near a face), at a
    /// larger gain (docs/DECISIONS.md: a stable step 0.57 times the fitted default's on the
    /// 40 x 4 x 4 bar). A source whose family cannot fit it falls back to the affine fit.
    Quadratic,
}

/// What a ghost layer's build found.
#[derive(Debug, Clone, PartialEq)]
pub struct GhostReport {
    /// Ghosts kept.
    pub ghosts: usize,
    /// Directed bonds between real particles and ghosts (each pair once a direction).
    pub bonds: usize,
    /// Images dropped because no real particle lies within a horizon of them among their
    /// source and its family.
    pub unbonded: usize,
    /// Images dropped because their source's family cannot fit even a gradient within the
    /// gain bound ([`GHOST_GAIN_BOUND`] unless built with another).
    pub unfitted: usize,
    /// Ghosts kept whose quadratic fit fell back to the affine one (singular, or past the gain
    /// bound; a clamped face's image of such a ghost counted too).
    pub affine_fallbacks: usize,
    /// Bonds left out because a ghost lies closer to the real particle than
    /// [`GHOST_SHORTEST_BOND`] of that particle's shortest real bond.
    pub short: usize,
    /// Each ghost's gain, the sum of its combination's coefficients' magnitudes (1 for a copy
    /// of its source): how much it amplifies what it reads.
    pub gain: Spread,
}

/// Ghosts of a discretisation across the given faces: their combinations, the fold of their
/// forces back onto the real particles, and the extended discretisation (real particles first,
/// then the ghosts) a model runs over.
#[derive(Debug, Clone)]
pub struct GhostLayer {
    real: usize,
    /// Per ghost, the constant `s_g` of its position's map (m).
    shift: Vec<Vec3>,
    /// Per ghost, its terms `(k, c_gk)` over real particles (CSR).
    combo_offsets: Vec<u32>,
    combo: Vec<(u32, f64)>,
    /// Per real particle, the ghosts that read it, `(g, c_gk)` by ghost (CSR).
    fold_offsets: Vec<u32>,
    fold: Vec<(u32, f64)>,
    /// Per real particle, the ghosts whose source it is (CSR).
    images_offsets: Vec<u32>,
    images_of: Vec<u32>,
    extended: Discretization,
    report: GhostReport,
}

/// The largest gain (the sum of a ghost's coefficients' magnitudes) a fit may take. Past it the
/// quadratic fit falls back to the affine one and the affine one drops the image (NaN fails
/// the test too). A ghost's bonds stiffen with its gain, so the bound keeps the stable step:
/// at 100 the quadratic fit's few outliers shortened it to 0.17 to 0.84 of the fitted
/// correction's on the shared meshes (0.03 on `bunny.mesh`, with the short bonds below), at 20
/// it is 0.63 to 1.6 of it (docs/DECISIONS.md, "Ghosts on real meshes"). The bench's bars
/// are barely touched: their quadratic gains have a median of 10 to 12, the largest kept
/// was 20.6 from 30 x 3 x 3 cells up; affine gains stay under 7 on boxes.
pub const GHOST_GAIN_BOUND: f64 = 20.0;

/// A ghost does not bond to a real particle it lies closer to than this fraction of that
/// particle's shortest real bond: the image of a particle a sliver's width under the surface
/// lands beside it, and a bond that short (its stiffness grows as `1 / r^3`) set a stable step
/// 30 times shorter than the fitted correction's on `bunny.mesh` (docs/DECISIONS.md).
pub const GHOST_SHORTEST_BOND: f64 = 0.5;

/// Number of basis terms of the quadratic fit: `x, y, z, x^2/2, y^2/2, z^2/2, xy, xz, yz`.
const TERMS: usize = 9;

/// The fit's basis terms of an offset `d` over the horizon (dimensionless); the quadratic
/// terms are zero for an affine fit.
fn basis(d: Vec3, delta: f64, fit: GhostFit) -> [f64; TERMS] {
    let [x, y, z] = d.map(|c| c / delta);
    match fit {
        GhostFit::Affine => [x, y, z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        GhostFit::Quadratic => [
            x,
            y,
            z,
            x * x / 2.0,
            y * y / 2.0,
            z * z / 2.0,
            x * y,
            x * z,
            y * z,
        ],
    }
}

/// The coefficients `(k, c)` of the ghost at `at` (m) from source `p`: `u_p` plus the fitted
/// field's change from `X_p` to `at`, the fit over `p`'s real family. `None` when the family's
/// moment is singular for `fit`.
fn fitted_terms(
    disc: &Discretization,
    p: usize,
    at: Vec3,
    fit: GhostFit,
    gain_bound: f64,
) -> Option<Vec<(u32, f64)>> {
    let (fam, x, vol) = (disc.family(), disc.rest_positions(), disc.volumes());
    let delta = disc.horizon();
    let used = match fit {
        GhostFit::Affine => 3,
        GhostFit::Quadratic => TERMS,
    };
    let mut m = [[0.0; TERMS]; TERMS];
    for k in fam.range(p) {
        let j = fam.neighbours()[k] as usize;
        let w = delta / fam.rest_lengths()[k] * vol[j];
        let phi = basis(sub(x[j], x[p]), delta, fit);
        for a in 0..used {
            for b in 0..used {
                m[a][b] += w * phi[a] * phi[b];
            }
        }
    }
    // unused terms decouple: identity rows solve to zero
    for (a, row) in m.iter_mut().enumerate().skip(used) {
        row[a] = 1.0;
    }
    let k = cholesky_solve(m, basis(sub(at, x[p]), delta, fit))?;
    let mut terms = Vec::with_capacity(fam.range(p).len() + 1);
    let mut own = 1.0;
    for b in fam.range(p) {
        let j = fam.neighbours()[b] as usize;
        let w = delta / fam.rest_lengths()[b] * vol[j];
        let phi = basis(sub(x[j], x[p]), delta, fit);
        let c = w * phi.iter().zip(&k).map(|(a, b)| a * b).sum::<f64>();
        own -= c;
        terms.push((j as u32, c));
    }
    terms.push((p as u32, own));
    terms.sort_unstable_by_key(|t| t.0);
    let gain: f64 = terms.iter().map(|t| t.1.abs()).sum();
    (gain <= gain_bound).then_some(terms)
}

/// Bonds left out as too short, over the images that keep some (an image left with none is
/// counted as unbonded instead).
fn kept_short(found: &[(Vec3, Vec<u32>, usize)]) -> usize {
    found
        .iter()
        .filter(|f| !f.1.is_empty())
        .map(|f| 2 * f.2)
        .sum()
}

/// `s + sum c y_k` over `terms`, in their order (the same arithmetic at rest and in motion,
/// so a ghost sits at its rest position bit for bit when the real particles do).
#[inline]
fn combine(shift: Vec3, terms: &[(u32, f64)], y: &[Vec3]) -> Vec3 {
    terms
        .iter()
        .fold(shift, |s, &(k, c)| axpy(s, c, y[k as usize]))
}

/// A plane with its normal made unit.
fn unit_plane(i: usize, p: &GhostPlane) -> Result<(Vec3, Vec3, FaceKind), PhysicsError> {
    let len = norm(p.normal);
    if !(len.is_finite() && len > 0.0 && p.point.iter().all(|c| c.is_finite())) {
        return Err(PhysicsError::BadSetting(format!(
            "ghost plane {i}: point {:?} and normal {:?} must be finite, the normal non-zero",
            p.point, p.normal
        )));
    }
    Ok((p.point, scale(p.normal, 1.0 / len), p.kind))
}

/// Depth of `x` inside the plane `(point, unit normal)` (m; negative outside).
#[inline]
fn depth(plane: &(Vec3, Vec3, FaceKind), x: Vec3) -> f64 {
    dot(sub(plane.0, x), plane.1)
}

/// `x` mirrored across the plane.
#[inline]
fn mirror(plane: &(Vec3, Vec3, FaceKind), x: Vec3) -> Vec3 {
    axpy(x, 2.0 * depth(plane, x), plane.1)
}

/// The most faces near one particle that are mirrored across (nearest first): a box's
/// particle in a bar thinner than a horizon each way is near four.
const MAX_NEAR_FACES: usize = 6;

/// Whether two faces of the set `set` (bits over `near`) face opposite ways (normals more than
/// 120 degrees apart): the two sides of a part thinner than a horizon, whose composed
/// reflection is a translation across the part, not an image of a corner.
fn opposed(near: &[(Vec3, Vec3, FaceKind)], set: u32) -> bool {
    let member: Vec<&(Vec3, Vec3, FaceKind)> = (0..near.len())
        .filter(|b| set & (1 << b) != 0)
        .map(|b| &near[b])
        .collect();
    member
        .iter()
        .enumerate()
        .any(|(a, p)| member[a + 1..].iter().any(|q| dot(p.1, q.1) < -0.5))
}

/// The pairs `(row, value)` that `items` gives (twice: once to count, once to fill) as CSR
/// rows `0..rows`, each row's values in the order given.
fn csr<T, I>(rows: usize, items: impl Fn() -> I) -> (Vec<u32>, Vec<T>)
where
    T: Copy + Default,
    I: Iterator<Item = (u32, T)>,
{
    let mut offsets = vec![0u32; rows + 1];
    for (r, _) in items() {
        offsets[r as usize + 1] += 1;
    }
    for r in 0..rows {
        offsets[r + 1] += offsets[r];
    }
    let mut next = offsets[..rows].to_vec();
    let mut values = vec![T::default(); offsets[rows] as usize];
    for (r, v) in items() {
        let slot = &mut next[r as usize];
        values[*slot as usize] = v;
        *slot += 1;
    }
    (offsets, values)
}

/// A ghost's terms `(k, c_gk)` over real particles (dimensionless coefficients).
type Terms = Vec<(u32, f64)>;

/// A ghost before its bonds are found.
struct Image {
    /// Position (m) as the mirror puts it.
    at: Vec3,
    /// Real particle whose volume and material it takes.
    source: u32,
    shift: Vec3,
    terms: Terms,
    /// Whether its quadratic fit fell back to the affine one.
    fell_back: bool,
}

impl GhostLayer {
    /// Mirrors the particles of `disc` across `planes`: each particle within a horizon inside
    /// a free face (up to three at once: a box's edges and corners get the images across
    /// both or all three faces; never two opposite faces together), then every real particle
    /// or free ghost within a horizon inside a clamped face. A ghost bonds to the real
    /// particles within a horizon of it among its source and the source's family (never
    /// across a cut the families do not cross); images with none are dropped.
    pub fn build(
        disc: &Discretization,
        planes: &[GhostPlane],
        fit: GhostFit,
    ) -> Result<GhostLayer, PhysicsError> {
        for (i, p) in planes.iter().enumerate() {
            unit_plane(i, p)?;
        }
        Self::build_with(disc, &Planes(planes), fit)
    }

    /// [`GhostLayer::build`] with the faces near each point found by `faces` (a mesh's
    /// boundary, or a list of planes): of the faces it gives, those with the point within a
    /// horizon inside are used (the first six at most), and the particle is mirrored across
    /// every set of up to three of them no two of which face opposite ways (a thin part's two
    /// sides are mirrored across one at a time). Images `faces` puts inside the body are
    /// dropped, and so are those whose fit's gain passes [`GHOST_GAIN_BOUND`] on both fits.
    /// Faces with a zero or non-finite normal are skipped.
    pub fn build_with(
        disc: &Discretization,
        faces: &dyn GhostFaces,
        fit: GhostFit,
    ) -> Result<GhostLayer, PhysicsError> {
        Self::build_bounded(disc, faces, fit, GHOST_GAIN_BOUND)
    }

    /// [`GhostLayer::build_with`] with another bound on the fits' gains than
    /// [`GHOST_GAIN_BOUND`] (a study's, or a test's that wants every fit kept).
    pub fn build_bounded(
        disc: &Discretization,
        faces: &dyn GhostFaces,
        fit: GhostFit,
        gain_bound: f64,
    ) -> Result<GhostLayer, PhysicsError> {
        let n = disc.len();
        let delta = disc.horizon();
        let x = disc.rest_positions();
        // the faces within a horizon inside of `at`, unit normals, free and clamped apart
        let near = |at: Vec3| {
            let mut out = Vec::new();
            faces.near(at, delta, &mut out);
            out.iter()
                .enumerate()
                .filter_map(|(i, p)| unit_plane(i, p).ok())
                .filter(|p| {
                    let d = depth(p, at);
                    d > 0.0 && d < delta
                })
                .partition::<Vec<_>, _>(|p| p.2 == FaceKind::Free)
        };
        // each real particle's near faces, asked for once
        let mut near_real = vec![(Vec::new(), Vec::new()); n];
        map_particles(&mut near_real, |i| near(x[i]));
        // free images: every non-empty set of up to three near faces, mirrored in turn
        let sets: Vec<(u32, Vec3)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|i| {
                // a particle near more faces than this is in a part thinner than a horizon
                // every way; the nearest are kept
                let near = &near_real[i].0[..near_real[i].0.len().min(MAX_NEAR_FACES)];
                (1u32..1 << near.len())
                    .filter(|&set| set.count_ones() <= 3 && !opposed(near, set))
                    .map(|set| {
                        let at = (0..near.len())
                            .filter(|b| set & (1 << b) != 0)
                            .fold(x[i], |at, b| mirror(&near[b], at));
                        (i as u32, at)
                    })
                    .filter(|&(_, at)| !faces.inside(at))
                    .collect::<Vec<_>>()
            })
            .collect();
        let fitted: Vec<Option<(Terms, bool)>> = sets
            .par_iter()
            .map(|&(p, at)| {
                let p = p as usize;
                match fitted_terms(disc, p, at, fit, gain_bound) {
                    Some(t) => Some((t, false)),
                    None if fit == GhostFit::Quadratic => {
                        fitted_terms(disc, p, at, GhostFit::Affine, gain_bound).map(|t| (t, true))
                    }
                    None => None,
                }
            })
            .collect();
        let mut unfitted = 0;
        let mut images = Vec::with_capacity(sets.len());
        for (&(source, at), f) in sets.iter().zip(fitted) {
            let Some((terms, fell_back)) = f else {
                unfitted += 1;
                continue;
            };
            // s = X_g - sum c X_k: zero to round-off for an exact fit, kept so that the rest
            // position is the one the map gives
            let shift = sub(at, combine([0.0; 3], &terms, x));
            images.push(Image {
                at,
                source,
                shift,
                terms,
                fell_back,
            });
        }
        // clamped faces: real particles and free ghosts within a horizon, each moving as
        // minus its source: y_g = X_g + X_s - y_s
        let mut clamp_images = Vec::new();
        for (i, &xi) in x.iter().enumerate() {
            for plane in &near_real[i].1 {
                let at = mirror(plane, xi);
                clamp_images.push(Image {
                    at,
                    source: i as u32,
                    shift: add(at, xi),
                    terms: vec![(i as u32, -1.0)],
                    fell_back: false,
                });
            }
        }
        // each free image asks for the clamped faces near it, unless there are none to find
        if faces.has_clamped() {
            for g in &images {
                for plane in near(g.at).1 {
                    let at = mirror(&plane, g.at);
                    clamp_images.push(Image {
                        at,
                        source: g.source,
                        shift: add(at, sub(g.at, g.shift)),
                        terms: g.terms.iter().map(|&(k, c)| (k, -c)).collect(),
                        fell_back: g.fell_back,
                    });
                }
            }
        }
        images.extend(clamp_images);
        Self::bond(disc, images, unfitted)
    }

    /// Finds each image's real neighbours, drops the unbonded, and builds the layer.
    fn bond(
        disc: &Discretization,
        mut images: Vec<Image>,
        unfitted: usize,
    ) -> Result<GhostLayer, PhysicsError> {
        let n = disc.len();
        let delta = disc.horizon();
        let x = disc.rest_positions();
        let fam = disc.family();
        let h2 = delta * delta;
        // per real particle, the square of the shortest ghost bond it takes
        let mut least = vec![0.0; n];
        map_particles(&mut least, |i| {
            let r = fam.rest_lengths()[fam.range(i)]
                .iter()
                .fold(f64::INFINITY, |a, &b| a.min(b));
            (GHOST_SHORTEST_BOND * r).powi(2)
        });
        // each image's rest position as its map gives it, and its real neighbours, sorted:
        // those within a horizon of it among its source and the source's family. Across a
        // flat face (and across orthogonal ones together) every real particle within a
        // horizon of an image is within one of its source, so this only leaves out bonds
        // that would cross what the families do not (a crack, a slot, a reentrant corner)
        let found: Vec<(Vec3, Vec<u32>, usize)> = images
            .par_iter()
            .map(|g| {
                let at = combine(g.shift, &g.terms, x);
                let mut short = 0;
                let mut near: Vec<u32> = fam
                    .row(g.source as usize)
                    .iter()
                    .copied()
                    .chain([g.source])
                    .filter(|&j| {
                        let r2 = norm_squared(sub(x[j as usize], at));
                        let keep = r2 >= least[j as usize];
                        short += usize::from(r2 < h2 && !keep);
                        r2 < h2 && keep
                    })
                    .collect();
                near.sort_unstable();
                (at, near, short)
            })
            .collect();
        drop(least);
        let unbonded = found.iter().filter(|f| f.1.is_empty()).count();
        let short = kept_short(&found);
        let kept: Vec<usize> = (0..images.len())
            .filter(|&g| !found[g].1.is_empty())
            .collect();
        let affine_fallbacks = kept.iter().filter(|&&im| images[im].fell_back).count();
        let m = kept.len();
        // counted before any u32 index is made of them
        let bonds = 2 * kept.iter().map(|&im| found[im].1.len()).sum::<usize>();
        let total = fam.num_bonds().saturating_add(bonds);
        if total > u32::MAX as usize || n + m > u32::MAX as usize {
            return Err(PhysicsError::TooManyBonds(total));
        }
        // per real particle, the ghosts in its family (ascending)
        let (ghost_offsets, ghost_rows) = csr(n, || {
            kept.iter()
                .enumerate()
                .flat_map(|(g, &im)| found[im].1.iter().map(move |&j| (j, (n + g) as u32)))
        });
        let mut offsets = Vec::with_capacity(n + m + 1);
        let mut neighbours = Vec::with_capacity(total);
        offsets.push(0u32);
        for i in 0..n {
            neighbours.extend_from_slice(fam.row(i));
            let r = ghost_offsets[i] as usize..ghost_offsets[i + 1] as usize;
            neighbours.extend_from_slice(&ghost_rows[r]);
            offsets.push(neighbours.len() as u32);
        }
        drop((ghost_offsets, ghost_rows));
        for &im in &kept {
            neighbours.extend_from_slice(&found[im].1);
            offsets.push(neighbours.len() as u32);
        }
        let mut rest = x.to_vec();
        rest.extend(kept.iter().map(|&im| found[im].0));
        drop(found);
        let mut volumes = disc.volumes().to_vec();
        let mut materials = disc.materials().to_vec();
        for &im in &kept {
            let s = images[im].source as usize;
            volumes.push(disc.volumes()[s]);
            materials.push(disc.materials()[s]);
        }
        let family = Family::from_rows(&rest, offsets, neighbours);
        let extended = Discretization::from_parts(rest, volumes, materials, delta, family);
        // the combinations (moved out of the images), and their transpose by real particle,
        // each real particle's ghosts in ghost order
        let mut combo_offsets = Vec::with_capacity(m + 1);
        combo_offsets.push(0u32);
        let terms: usize = kept.iter().map(|&im| images[im].terms.len()).sum();
        if terms > u32::MAX as usize {
            return Err(PhysicsError::TooManyBonds(terms));
        }
        let mut combo = Vec::with_capacity(terms);
        let mut shift = Vec::with_capacity(m);
        let mut source = Vec::with_capacity(m);
        for &im in &kept {
            let image = &mut images[im];
            combo.extend_from_slice(&image.terms);
            image.terms = Vec::new();
            combo_offsets.push(combo.len() as u32);
            shift.push(image.shift);
            source.push(image.source);
        }
        drop(images);
        let (fold_offsets, fold) = csr(n, || {
            (0..m).flat_map(|g| {
                let r = combo_offsets[g] as usize..combo_offsets[g + 1] as usize;
                combo[r].iter().map(move |&(k, c)| (k, (g as u32, c)))
            })
        });
        // per real particle, the ghosts it is the source of
        let (images_offsets, images_of) =
            csr(n, || source.iter().enumerate().map(|(g, &s)| (s, g as u32)));
        let gains = (0..m)
            .map(|g| {
                let r = combo_offsets[g] as usize..combo_offsets[g + 1] as usize;
                combo[r].iter().map(|t| t.1.abs()).sum()
            })
            .collect();
        let report = GhostReport {
            ghosts: m,
            bonds,
            unbonded,
            unfitted,
            affine_fallbacks,
            short,
            gain: Spread::of(gains),
        };
        Ok(GhostLayer {
            real: n,
            shift,
            combo_offsets,
            combo,
            fold_offsets,
            fold,
            images_offsets,
            images_of,
            extended,
            report,
        })
    }

    /// Number of real particles.
    pub fn num_real(&self) -> usize {
        self.real
    }

    /// Number of ghosts.
    pub fn num_ghosts(&self) -> usize {
        self.shift.len()
    }

    /// The real particles, then the ghosts (rest positions, volumes and materials of their
    /// sources), with the extended families: what the model runs over.
    pub fn extended(&self) -> &Discretization {
        &self.extended
    }

    /// What the build found.
    pub fn report(&self) -> &GhostReport {
        &self.report
    }

    /// Ghost `g`'s terms `(k, c_gk)` over real particles.
    pub fn terms(&self, g: usize) -> &[(u32, f64)] {
        &self.combo[self.combo_offsets[g] as usize..self.combo_offsets[g + 1] as usize]
    }

    /// The ghosts whose source is real particle `k`: its images (a clamped face's images of
    /// its free ghosts included).
    pub fn images_of(&self, k: usize) -> &[u32] {
        &self.images_of[self.images_offsets[k] as usize..self.images_offsets[k + 1] as usize]
    }

    /// Writes the real positions `y` (m) and the ghosts' positions they give into `out` (real
    /// particles first, then the ghosts).
    pub fn expand(&self, y: &[Vec3], out: &mut [Vec3]) {
        let n = self.real;
        assert_eq!(y.len(), n, "positions: one per real particle");
        assert_eq!(
            out.len(),
            n + self.num_ghosts(),
            "one slot per particle and ghost"
        );
        let (real, ghosts) = out.split_at_mut(n);
        real.copy_from_slice(y);
        map_particles(ghosts, |g| combine(self.shift[g], self.terms(g), y));
    }

    /// The forces on the real particles from `ext`, the forces on every particle and ghost
    /// (N): each real particle's own plus `c_gk f_g` from every ghost `g` that reads it,
    /// gathered in ghost order.
    pub fn fold(&self, ext: &[Vec3], forces: &mut [Vec3]) {
        let n = self.real;
        assert_eq!(
            ext.len(),
            n + self.num_ghosts(),
            "one force per particle and ghost"
        );
        assert_eq!(forces.len(), n, "forces: one per real particle");
        map_particles(forces, |k| {
            let r = self.fold_offsets[k] as usize..self.fold_offsets[k + 1] as usize;
            self.fold[r]
                .iter()
                .fold(ext[k], |f, &(g, w)| axpy(f, w, ext[n + g as usize]))
        });
    }

    /// Heap bytes.
    pub fn memory_bytes(&self) -> usize {
        24 * self.shift.len()
            + 4 * (self.combo_offsets.len() + self.fold_offsets.len())
            + 4 * (self.images_offsets.len() + self.images_of.len())
            + 16 * (self.combo.len() + self.fold.len())
            + self.extended.memory_bytes()
    }
}

/// A model whose particles a ghost layer can cut out of every family: how a ghost whose
/// source's family broke is dropped.
pub trait Isolate {
    /// Cuts the passive particles `newly` (ghosts, none cut before) out of every family: their
    /// bonds become broken, counted as damage at neither end.
    fn isolate(&mut self, newly: &[u32]);
}

impl Isolate for ChenModel {
    fn isolate(&mut self, newly: &[u32]) {
        ChenModel::isolate(self, newly)
    }
}

/// A model over a body and its ghosts, shown to the integrators as the real particles only:
/// positions in, the ghosts' written from them; the ghosts' forces folded back out.
///
/// Under fracture every bond, a ghost's too, breaks by the model's criterion, and a ghost is
/// dropped (cut out of every family, [`Isolate`]) as soon as a bond of its source's family
/// breaks: its combination reads that family, which then no longer moves as one piece. The
/// damage state shown ([`ForceModel::damage`]) is over the real bonds alone, and so are the
/// broken pairs reported.
#[derive(Debug, Clone)]
pub struct Ghosted<M> {
    inner: M,
    real: Discretization,
    layer: GhostLayer,
    /// Positions of every particle and ghost (m), the last expanded.
    y: Vec<Vec3>,
    /// Forces on every particle and ghost (N).
    f: Vec<Vec3>,
    /// The damage state of the real bonds, copied from the inner model's, when it has one.
    damage: Option<Damage>,
    /// Per particle and ghost, whether it is cut out of every family (real ones never).
    dropped: Vec<bool>,
    /// The pairs the inner model broke in the last check (extended indices).
    broken: Vec<(u32, u32)>,
    /// The ghosts the last check dropped (extended indices).
    newly: Vec<u32>,
}

impl<M: ForceModel + Isolate> Ghosted<M> {
    /// Wraps `inner`, a model over `layer.extended()` whose ghosts are passive (they must store
    /// no energy, as [`ChenModel::with_passive`] makes them; this is not checked), for the real
    /// particles of `real`. Refused when the sizes differ.
    pub fn new(real: Discretization, layer: GhostLayer, inner: M) -> Result<Self, PhysicsError> {
        let total = layer.extended().len();
        if real.len() != layer.num_real() {
            return Err(PhysicsError::LengthMismatch {
                what: "real particles of the ghost layer",
                expected: real.len(),
                got: layer.num_real(),
            });
        }
        if inner.num_particles() != total {
            return Err(PhysicsError::LengthMismatch {
                what: "particles and ghosts of the inner model",
                expected: total,
                got: inner.num_particles(),
            });
        }
        // each extended row starts with the real row (what `Damage::copy_real` reads)
        let (rf, ef) = (real.family(), layer.extended().family());
        if let Some(i) = (0..real.len()).find(|&i| !ef.row(i).starts_with(rf.row(i))) {
            return Err(PhysicsError::BadSetting(format!(
                "the ghost layer was built over another discretisation: particle {i}'s family \
                 differs"
            )));
        }
        let damage = inner.damage().map(|d| d.for_real(real.family()));
        Ok(Ghosted {
            inner,
            real,
            layer,
            y: vec![[0.0; 3]; total],
            f: vec![[0.0; 3]; total],
            damage,
            dropped: vec![false; total],
            broken: Vec::new(),
            newly: Vec::new(),
        })
    }

    /// The model over the particles and their ghosts.
    pub fn inner(&self) -> &M {
        &self.inner
    }

    /// The ghosts.
    pub fn layer(&self) -> &GhostLayer {
        &self.layer
    }

    /// Number of ghosts dropped so far (their source's family broke).
    pub fn dropped_ghosts(&self) -> usize {
        self.dropped.iter().filter(|&&d| d).count()
    }

    /// After the inner model's check broke `self.broken`: appends the real pairs to `broken`,
    /// drops the ghosts whose source lost a bond, and copies the real bonds' states. Returns
    /// whether any ghost was dropped (the forces of the check's pass then read its bonds).
    fn settle(&mut self, broken: &mut Vec<(u32, u32)>) -> bool {
        if self.broken.is_empty() {
            if let Some(d) = self.damage.as_mut() {
                d.clear_overshoot();
            }
            return false;
        }
        let n = self.real.len();
        self.newly.clear();
        for &(i, j) in &self.broken {
            // a ghost's bonds (j >= n) are not the mesh's
            if (j as usize) < n {
                broken.push((i, j));
                for s in [i, j] {
                    for &g in self.layer.images_of(s as usize) {
                        let slot = &mut self.dropped[n + g as usize];
                        if !*slot {
                            *slot = true;
                            self.newly.push((n + g as usize) as u32);
                        }
                    }
                }
            }
        }
        let any = !self.newly.is_empty();
        if any {
            self.inner.isolate(&self.newly);
        }
        self.sync_damage();
        any
    }

    /// Copies the real bonds' states from the inner model's damage.
    fn sync_damage(&mut self) {
        if let (Some(real), Some(ext)) = (self.damage.as_mut(), self.inner.damage()) {
            real.copy_real(self.real.family(), self.layer.extended().family(), ext);
        }
    }
}

impl Ghosted<ChenModel> {
    /// Chen's model over `disc` with ghosts across `planes`, fitted as `fit`: the correction's
    /// constants (`c_i`, `b_i`, the fitted dilatation) over the completed families.
    pub fn chen(
        disc: Discretization,
        materials: &[ChenMaterial],
        options: ChenOptions,
        planes: &[GhostPlane],
        fit: GhostFit,
    ) -> Result<Self, PhysicsError> {
        let layer = GhostLayer::build(&disc, planes, fit)?;
        Self::chen_with_layer(disc, layer, materials, options)
    }

    /// Chen's model over `disc` with the ghosts of `layer` (built over `disc`, by
    /// [`GhostLayer::build_with`] for faces other than planes).
    pub fn chen_with_layer(
        disc: Discretization,
        layer: GhostLayer,
        materials: &[ChenMaterial],
        options: ChenOptions,
    ) -> Result<Self, PhysicsError> {
        let n = disc.len();
        let inner = ChenModel::with_passive(layer.extended().clone(), materials, options, n)?;
        Ghosted::new(disc, layer, inner)
    }
}

impl<M: ForceModel + Isolate> ForceModel for Ghosted<M> {
    fn num_particles(&self) -> usize {
        self.real.len()
    }

    fn discretization(&self) -> &Discretization {
        &self.real
    }

    fn masses(&self) -> &[f64] {
        &self.inner.masses()[..self.real.len()]
    }

    fn update_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        self.layer.expand(y, &mut self.y);
        self.inner.update_forces(&self.y, &mut self.f);
        self.layer.fold(&self.f, forces);
    }

    fn trial_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        self.layer.expand(y, &mut self.y);
        self.inner.trial_forces(&self.y, &mut self.f);
        self.layer.fold(&self.f, forces);
    }

    fn forces_vanish_at(&self, y: &[Vec3]) -> bool {
        // at the real rest positions the ghosts are at theirs bit for bit (`combine`)
        y == self.real.rest_positions()
            && self
                .inner
                .forces_vanish_at(self.inner.discretization().rest_positions())
    }

    fn elastic_energy(&mut self, y: &[Vec3]) -> f64 {
        self.layer.expand(y, &mut self.y);
        self.inner.elastic_energy(&self.y)
    }

    fn break_bonds(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>) {
        self.layer.expand(y, &mut self.y);
        self.broken.clear();
        self.inner.break_bonds(&self.y, &mut self.broken);
        self.settle(broken);
    }

    fn break_bonds_and_update_forces(
        &mut self,
        y: &[Vec3],
        broken: &mut Vec<(u32, u32)>,
        forces: &mut [Vec3],
    ) {
        self.layer.expand(y, &mut self.y);
        self.broken.clear();
        self.inner
            .break_bonds_and_update_forces(&self.y, &mut self.broken, &mut self.f);
        if self.settle(broken) {
            // the pass read the bonds of the ghosts just dropped: their forces again, the
            // history as the pass left it
            self.inner.trial_forces(&self.y, &mut self.f);
        }
        self.layer.fold(&self.f, forces);
    }

    fn silling_askari_step(&self) -> f64 {
        self.inner.silling_askari_step()
    }

    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
            + self.real.memory_bytes()
            + self.layer.memory_bytes()
            + 24 * (self.y.len() + self.f.len())
            + self.damage.as_ref().map_or(0, Damage::memory_bytes)
            + self.dropped.len()
            + 8 * self.broken.capacity()
            + 4 * self.newly.capacity()
    }

    fn damage(&self) -> Option<&Damage> {
        self.damage.as_ref()
    }

    fn break_overshoot(&self) -> f64 {
        // the ghosts' bonds' too: a step that saw them go late is as late
        self.inner.break_overshoot()
    }

    fn save_state(&self, w: &mut Writer) {
        w.tag("ghosts");
        w.usize(self.layer.num_ghosts());
        let dropped: Vec<u8> = self.dropped[self.real.len()..]
            .iter()
            .map(|&d| u8::from(d))
            .collect();
        w.array(&dropped);
        self.inner.save_state(w);
    }

    fn restore_state(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("ghosts")?;
        let m = self.layer.num_ghosts();
        expect_count("ghosts", m, r.usize("ghosts")?)?;
        let mut dropped = vec![0u8; m];
        r.array_into("dropped ghosts", &mut dropped)?;
        if let Some(&b) = dropped.iter().find(|&&b| b > 1) {
            return Err(CheckpointError::Invalid {
                what: "dropped ghosts".into(),
                message: format!("flag {b} is neither kept (0) nor dropped (1)"),
            });
        }
        // the inner state's bond states hold the drops (and a drop moves no count)
        self.inner.restore_state(r)?;
        let n = self.real.len();
        for (slot, &b) in self.dropped[n..].iter_mut().zip(&dropped) {
            *slot = b == 1;
        }
        self.sync_damage();
        Ok(())
    }
}
