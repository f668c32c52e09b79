//! An unstructured tet mesh of an axis-aligned box: no lattice direction for cracks to follow.
//!
//! The box's corners, edges, faces and inside are scattered with well-spaced points
//! ([`super::scatter`]) and tetrahedralised by Delaunay ([`super::delaunay`]). Every face of
//! the points' convex hull lies on a face of the box (points on a face have its coordinate
//! exactly), so the mesh's boundary is the box's, exactly. The Delaunay tie rule for coplanar
//! points never makes a flat tet on a box face; one would be dropped (and counted in
//! [`UnstructuredReport::flat_dropped`]) should it ever appear.
//!
//! Slivers are then removed in two phases. Vertices may move only where they lie: inside
//! points anywhere (keeping [`MOVE_MARGIN`]` * h` from the faces), face points within their
//! face, edge points along their edge, corners never.
//!
//! 1. Perturbation with re-triangulation ([`ROUNDS`] rounds at most): one vertex of each tet
//!    with a smallest dihedral angle below [`TARGET_DEG`], worst tets first and each pick at
//!    least three edges from every other, is moved at random by up to [`MAX_STEP`]` * h`; the
//!    moved points are triangulated again, and each move is kept only where the tets around it
//!    got better (their sorted smallest dihedral angles, compared lexicographically), else
//!    undone. The best point set seen is kept.
//! 2. Smoothing with the tets fixed ([`SWEEPS`] sweeps at most): each movable vertex of a tet
//!    within 5 degrees of the worst (and below [`SMOOTH_TARGET_DEG`]) tries
//!    [`SMOOTH_TRIES`] random positions around its best so far, in a shrinking ball, and takes
//!    the one that raises the smallest dihedral angle of its star, keeping every tet of the star
//!    positively oriented; a vertex that found nothing tries again only after a neighbour
//!    moved. The mesh is then no longer exactly Delaunay, which nothing needs.
//!
//! Measured (release build, boxes of cubic cells of side 1 from the origin, seeds 1 to 5; the
//! smallest tet volume in cells' volumes; the time is the whole call on this workspace's
//! 2-core machine while another build ran):
//!
//! | cells | tets / Kuhn's `6 nx ny nz` | min dihedral (deg) | max dihedral (deg) | min volume | time |
//! |---|---|---|---|---|---|
//! | 24 x 24 x 3 | 0.988 to 1.007 | 24.9 | 155.2 | 0.030 | 0.40 to 0.46 s |
//! | 48 x 8 x 8 | 0.987 to 0.997 | 23.5 | 155.3 | 0.028 | 0.71 to 0.74 s |
//! | 8 x 8 x 8 | 0.969 to 1.008 | 23.4 | 158.4 | 0.034 | 0.10 to 0.14 s |
//! | 16 x 16 x 16 | 0.995 to 1.009 | 21.5 | 155.3 | 0.012 | 0.76 to 0.90 s |
//! | 10 x 10 x 1 | 0.905 to 0.952 | 25.1 | 151.4 | 0.062 | 0.02 to 0.03 s |
//! | 4 x 4 x 1 | 0.948 to 1.062 | 25.0 | 147.7 | 0.064 | under 0.01 s |
//!
//! The default wall (0.6 x 0.6 x 0.06 m, 24 x 24 x 3 cells, seed 1) measured 20.4 degrees
//! through `examples/unstructured_box.rs` when the scenes took it up.
//! Over seeds 1 to 10 the smallest dihedral angle stayed above 20.6 degrees and the largest
//! below 158.5. The time grows about linearly: 44 x 44 x 44 cells (85 000 points, 516 000 tets)
//! take about 19 s (10 s perturbing, 8 s smoothing), min dihedral 22.2 degrees. The direction
//! histogram of interior faces (area times in-plane normal, 12 bins over 180 degrees) of a
//! 24 x 24 x 3 box peaks at 1.04 to 1.09 times its mean over seeds 1 to 10, against 4.4 for
//! the Kuhn lattice.

use super::delaunay::{delaunay, orient, DelaunayError};
use super::scatter::{check_box, estimated_points, scatter_box, Placement, Rng, MAX_POINTS};
use crate::faces::{cross, dot, signed_volume, sub, FACE_CORNERS};
use crate::quality::dihedral_angles_deg;

/// Why an unstructured box cannot be meshed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UnstructuredError {
    /// A corner coordinate is not finite, or the box is empty or inverted along an axis.
    #[error(
        "the box {min:?}..{max:?} needs finite corners and a positive extent along every axis"
    )]
    BadBox {
        /// The lower corner given (length).
        min: [f64; 3],
        /// The upper corner given (length).
        max: [f64; 3],
    },
    /// A cell count is zero.
    #[error("the cell counts {cells:?} must all be at least 1")]
    ZeroCells {
        /// The cell counts given.
        cells: [usize; 3],
    },
    /// The point spacing is not finite and positive.
    #[error("the point spacing {h} must be finite and positive")]
    BadSpacing {
        /// The spacing given (length).
        h: f64,
    },
    /// The mesh would need more points than [`MAX_POINTS`].
    #[error(
        "the mesh would need about {estimate:.3e} points, more than the {MAX_POINTS:.0e} allowed"
    )]
    TooManyPoints {
        /// The estimated number of points.
        estimate: f64,
    },
    /// The Delaunay tetrahedralisation failed (an internal error: the scattered points always
    /// span the box).
    #[error("the tetrahedralisation of the scattered points failed: {cause}")]
    Triangulation {
        /// What the tetrahedralisation reported.
        cause: DelaunayError,
    },
    /// A tet came out flat or inverted other than flat on a box face (an internal error).
    #[error("tet {tet} of the unstructured box is not positively oriented")]
    Inverted {
        /// Index of the tet.
        tet: usize,
    },
}

/// Tets per `V / h^3` (box volume over spacing cubed) of this module's meshes: the first guess
/// of the spacing for a tet count. The Delaunay tetrahedralisation of the scatter gives about
/// 8.8 (on a unit cube at `h = 0.02` and on a 24 x 24 x 3 slab at `h = 1`); sliver removal
/// lowers it about 2%. One re-scatter corrects the guess when the count is off by over 3%.
const TETS_PER_SPACING_CUBE: f64 = 8.7;

/// Perturbation with re-triangulation works on tets whose smallest dihedral angle is below this
/// (degrees).
pub const TARGET_DEG: f64 = 15.0;

/// Perturbation rounds at most (each one or two Delaunay tetrahedralisations).
pub const ROUNDS: usize = 8;

/// Largest perturbation of a vertex, as a fraction of the spacing `h`.
pub const MAX_STEP: f64 = 0.3;

/// How close a moved vertex may come to a box face it does not lie on (and a face vertex to the
/// face's edges, an edge vertex to the edge's corners), as a fraction of the spacing `h`.
pub const MOVE_MARGIN: f64 = 0.15;

/// Smoothing stops working on tets once their smallest dihedral angle reaches this (degrees).
pub const SMOOTH_TARGET_DEG: f64 = 25.0;

/// Smoothing works on tets within this many degrees of the worst one.
const SMOOTH_WINDOW_DEG: f64 = 5.0;

/// Smoothing sweeps at most.
pub const SWEEPS: usize = 40;

/// Random positions each smoothed vertex tries per sweep.
pub const SMOOTH_TRIES: usize = 20;

/// Measures of an unstructured box mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct UnstructuredReport {
    /// Point spacing used, in cells (1 is one cell's side along each axis).
    pub spacing: f64,
    /// The Kuhn lattice's tet count for the same cells, `6 nx ny nz`.
    pub lattice_tets: usize,
    /// Smallest dihedral angle over all tets (degrees).
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle over all tets (degrees).
    pub max_dihedral_deg: f64,
    /// Smallest tet volume (length^3).
    pub min_volume: f64,
    /// Flat tets on a box face dropped (none expected).
    pub flat_dropped: usize,
    /// Perturbation rounds run.
    pub rounds: usize,
    /// Perturbation moves tried.
    pub moves_tried: usize,
    /// Perturbation moves kept.
    pub moves_kept: usize,
    /// Smoothing sweeps run.
    pub sweeps: usize,
}

/// An unstructured box mesh and its measures.
#[derive(Debug, Clone, PartialEq)]
pub struct UnstructuredMesh {
    /// Vertex positions (length).
    pub vertices: Vec<[f64; 3]>,
    /// Tets of vertex indices, positively oriented ([`signed_volume`] `> 0`).
    pub tets: Vec<[u32; 4]>,
    /// Its measures.
    pub report: UnstructuredReport,
}

/// An unstructured tet mesh of the box `min..max` (length) with about as many tets as the Kuhn
/// lattice of `cells` (`6 nx ny nz`, see [`crate::primitives::box_data`]), the same for the same
/// `seed`: `(vertices, tets)`, tets positively oriented. See [`unstructured_box`] for the errors
/// and the measures.
// The plain arrays of `crate::primitives::box_data`, in a `Result`.
#[allow(clippy::type_complexity)]
pub fn unstructured_box_data(
    min: [f64; 3],
    max: [f64; 3],
    cells: [usize; 3],
    seed: u64,
) -> Result<(Vec<[f64; 3]>, Vec<[u32; 4]>), UnstructuredError> {
    let mesh = unstructured_box(min, max, cells, seed)?;
    Ok((mesh.vertices, mesh.tets))
}

/// [`unstructured_box_data`] with its measures.
///
/// The mesh is made in cell units (every cell a unit cube) and stretched onto the box, so its
/// spacing along each axis follows the cells, as the lattice's does: cubic cells give an
/// isotropic mesh, flat cells flat tets (as they give flat lattice tets), and the dihedral
/// angles reported are those of the stretched tets. An error for a box with a non-finite or
/// non-positive extent, a zero cell count, or more than [`MAX_POINTS`] points.
pub fn unstructured_box(
    min: [f64; 3],
    max: [f64; 3],
    cells: [usize; 3],
    seed: u64,
) -> Result<UnstructuredMesh, UnstructuredError> {
    check_box(min, max)?;
    if cells.contains(&0) {
        return Err(UnstructuredError::ZeroCells { cells });
    }
    // Meshed in cell units (each cell a unit cube), then stretched onto the box: the spacing
    // follows the cells along each axis, as the lattice's does. In f64: a product that
    // overflows usize is rejected by the point estimate.
    let size = cells.map(|c| c as f64);
    let lattice = 6.0 * size[0] * size[1] * size[2];
    let mut h = (TETS_PER_SPACING_CUBE / 6.0).cbrt();
    let estimate = estimated_points([0.0; 3], size, h);
    if estimate.is_nan() || estimate > MAX_POINTS {
        return Err(UnstructuredError::TooManyPoints { estimate });
    }
    let mut scatter = scatter_box([0.0; 3], size, h, seed)?;
    let mut tets = triangulate(&scatter.points)?;
    // One correction of the spacing: boundary layers make small boxes' density differ.
    let ratio = tets.len() as f64 / lattice;
    if (ratio - 1.0).abs() > 0.03 {
        h *= ratio.cbrt();
        scatter = scatter_box([0.0; 3], size, h, seed)?;
        tets = triangulate(&scatter.points)?;
    }
    let mut points = scatter.points;
    let mut improver = Improver {
        placement: &scatter.placement,
        min: [0.0; 3],
        max: size,
        h,
        rng: Rng::new(seed ^ 0x0dd5_11ce),
        moves_kept: 0,
        moves_tried: 0,
    };
    let rounds = improver.perturb(&mut points, &mut tets)?;
    let sweeps = improver.smooth(&mut points, &tets);
    let on_one_face = |tet: &[u32; 4]| {
        (0..3).any(|d| {
            [0.0, size[d]]
                .iter()
                .any(|&side| tet.iter().all(|&v| points[v as usize][d] == side))
        })
    };
    let mut flat_dropped = 0;
    tets.retain(|tet| {
        let p = tet.map(|v| points[v as usize]);
        let flat = orient(p[0], p[1], p[2], p[3]) == 0.0 && on_one_face(tet);
        flat_dropped += flat as usize;
        !flat
    });
    let (points, tets) = morton_order(&points, &tets, size);
    // Coordinates 0 and n map to min and max exactly, so boundary points stay on the box.
    let vertices: Vec<[f64; 3]> = points
        .iter()
        .map(|u| {
            [0, 1, 2].map(|d| {
                if u[d] == 0.0 {
                    min[d]
                } else if u[d] == size[d] {
                    max[d]
                } else {
                    min[d] + (max[d] - min[d]) * (u[d] / size[d])
                }
            })
        })
        .collect();
    let mut report = UnstructuredReport {
        spacing: h,
        lattice_tets: lattice as usize,
        min_dihedral_deg: f64::INFINITY,
        max_dihedral_deg: f64::NEG_INFINITY,
        min_volume: f64::INFINITY,
        flat_dropped,
        rounds,
        moves_tried: improver.moves_tried,
        moves_kept: improver.moves_kept,
        sweeps,
    };
    for (t, tet) in tets.iter().enumerate() {
        let p = tet.map(|v| vertices[v as usize]);
        let volume = signed_volume(p[0], p[1], p[2], p[3]);
        if orient(p[0], p[1], p[2], p[3]) <= 0.0 || volume <= 0.0 {
            return Err(UnstructuredError::Inverted { tet: t });
        }
        report.min_volume = report.min_volume.min(volume);
        for a in dihedral_angles_deg(p) {
            report.min_dihedral_deg = report.min_dihedral_deg.min(a);
            report.max_dihedral_deg = report.max_dihedral_deg.max(a);
        }
    }
    Ok(UnstructuredMesh {
        vertices,
        tets,
        report,
    })
}

/// Tets sorted along a Morton (Z-order) curve through their barycentres, and vertices renumbered
/// in order of first use: neighbours in space are neighbours in memory, as in the lattice, so a
/// particle's bonds (particle `t` is tet `t`) gather from nearby memory. Ties keep the
/// Delaunay order, so the result is deterministic. Measured on the default wall (10,441
/// particles, 2 threads): 48 steps per second in the Delaunay order, 53 sorted (58 on the
/// lattice wall), with the same bonds broken and fragments.
fn morton_order(
    points: &[[f64; 3]],
    tets: &[[u32; 4]],
    size: [f64; 3],
) -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    const BITS: u32 = 21;
    let scale =
        ((1u64 << BITS) - 1) as f64 / size.iter().cloned().fold(f64::MIN_POSITIVE, f64::max);
    let spread = |mut x: u64| {
        // Bit k of x to bit 3k.
        x &= (1 << BITS) - 1;
        x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
        x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
        x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
        x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
        x = (x | (x << 2)) & 0x1249_2492_4924_9249;
        x
    };
    let mut keyed: Vec<(u64, usize)> = tets
        .iter()
        .enumerate()
        .map(|(t, tet)| {
            let c: [f64; 3] = std::array::from_fn(|d| {
                tet.iter().map(|&v| points[v as usize][d]).sum::<f64>() / 4.0
            });
            let q = c.map(|x| (x * scale).clamp(0.0, ((1u64 << BITS) - 1) as f64) as u64);
            (spread(q[0]) | spread(q[1]) << 1 | spread(q[2]) << 2, t)
        })
        .collect();
    keyed.sort_unstable();
    let mut new_id = vec![u32::MAX; points.len()];
    let mut sorted_points = Vec::with_capacity(points.len());
    let sorted_tets = keyed
        .iter()
        .map(|&(_, t)| {
            tets[t].map(|v| {
                let id = &mut new_id[v as usize];
                if *id == u32::MAX {
                    *id = sorted_points.len() as u32;
                    sorted_points.push(points[v as usize]);
                }
                *id
            })
        })
        .collect();
    (sorted_points, sorted_tets)
}

/// The Delaunay tets of `points`.
fn triangulate(points: &[[f64; 3]]) -> Result<Vec<[u32; 4]>, UnstructuredError> {
    delaunay(points).map_err(|cause| UnstructuredError::Triangulation { cause })
}

/// The smallest dihedral angle of each tet (degrees).
fn min_angles(points: &[[f64; 3]], tets: &[[u32; 4]]) -> Vec<f64> {
    tets.iter().map(|&tet| tet_min_angle(points, tet)).collect()
}

/// The smallest dihedral angle of `tet` (degrees), from its corners in ascending index order,
/// so that the same tet gives the same bits in any triangulation.
fn tet_min_angle(points: &[[f64; 3]], tet: [u32; 4]) -> f64 {
    let mut sorted = tet;
    sorted.sort_unstable();
    max_cos(sorted.map(|v| points[v as usize]))
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// The largest cosine of the six dihedral angles of a tet (that of its smallest angle).
#[inline]
fn max_cos(p: [[f64; 3]; 4]) -> f64 {
    let normals = FACE_CORNERS.map(|[a, b, c]| {
        let n = cross(sub(p[b], p[a]), sub(p[c], p[a]));
        let l = dot(n, n).sqrt();
        [n[0] / l, n[1] / l, n[2] / l]
    });
    // The faces meeting at an edge are those opposite the other two corners (k, l); the
    // dihedral angle's cosine is minus their outward normals' dot product.
    let mut worst = f64::NEG_INFINITY;
    for (k, l) in [(2, 3), (1, 3), (1, 2), (0, 3), (0, 2), (0, 1)] {
        worst = worst.max(-dot(normals[k], normals[l]));
    }
    worst
}

/// Whether the sorted smallest angles `new` beat `old`: lexicographically larger over their
/// common length (an unchanged worst tet compares equal and passes to the next).
fn better(new: &[f64], old: &[f64]) -> bool {
    for (a, b) in new.iter().zip(old) {
        if a > b {
            return true;
        }
        if a < b {
            return false;
        }
    }
    false
}

/// Vertex to tets incidence (compressed rows, tets ascending), as the mesh builds it.
struct Stars {
    offsets: Vec<usize>,
    tets: Vec<u32>,
}

impl Stars {
    fn new(vertices: usize, tets: &[[u32; 4]]) -> Self {
        let (offsets, tets) = crate::build::build_star(vertices, tets);
        Stars { offsets, tets }
    }

    #[inline]
    fn of(&self, v: u32) -> &[u32] {
        &self.tets[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }
}

/// The sliver removal's settings and counters.
struct Improver<'a> {
    placement: &'a [Placement],
    min: [f64; 3],
    max: [f64; 3],
    h: f64,
    rng: Rng,
    moves_kept: usize,
    moves_tried: usize,
}

impl Improver<'_> {
    /// Perturbation rounds with re-triangulation on `points` and their Delaunay `tets`, both
    /// left at the best state seen (by smallest dihedral angle). Returns the rounds run.
    fn perturb(
        &mut self,
        points: &mut Vec<[f64; 3]>,
        tets: &mut Vec<[u32; 4]>,
    ) -> Result<usize, UnstructuredError> {
        let n = points.len();
        let mut quality = min_angles(points, tets);
        let worst_of = |q: &[f64]| q.iter().copied().fold(f64::INFINITY, f64::min);
        let mut best_min = worst_of(&quality);
        let mut best = (points.clone(), tets.clone());
        // Scratch, reused across rounds; a stamp marks what belongs to the current pick.
        let mut stamp = 0u32;
        let mut locked = vec![0u32; n];
        let mut in_region = vec![0u32; n];
        let mut old_seen: Vec<u32> = Vec::new();
        let mut new_seen: Vec<u32> = Vec::new();
        let mut region: Vec<u32> = Vec::new();
        let mut old_q: Vec<f64> = Vec::new();
        let mut new_q: Vec<f64> = Vec::new();
        let mut moves: Vec<(u32, [f64; 3])> = Vec::new();
        let mut rounds = 0;
        while rounds < ROUNDS {
            let mut bad: Vec<u32> = (0..tets.len() as u32)
                .filter(|&t| quality[t as usize] < TARGET_DEG)
                .collect();
            if bad.is_empty() {
                break;
            }
            rounds += 1;
            bad.sort_by(|&a, &b| quality[a as usize].total_cmp(&quality[b as usize]));
            let stars = Stars::new(n, tets);
            // One movable vertex per bad tet, at least three edges from every other pick.
            stamp += 1;
            moves.clear();
            for &t in &bad {
                let mut candidates = [0u32; 4];
                let mut count = 0;
                for v in tets[t as usize] {
                    if self.placement[v as usize] != Placement::Corner
                        && locked[v as usize] != stamp
                    {
                        candidates[count] = v;
                        count += 1;
                    }
                }
                if count == 0 {
                    continue;
                }
                let v = candidates[self.rng.below(count)];
                for &s in stars.of(v) {
                    for a in tets[s as usize] {
                        for &s2 in stars.of(a) {
                            for b in tets[s2 as usize] {
                                locked[b as usize] = stamp;
                            }
                        }
                    }
                }
                moves.push((v, points[v as usize]));
                points[v as usize] = self.perturbed(points[v as usize], v, MAX_STEP * self.h);
            }
            if moves.is_empty() {
                break;
            }
            self.moves_tried += moves.len();
            let new_tets = triangulate(points)?;
            let new_quality = min_angles(points, &new_tets);
            let new_stars = Stars::new(n, &new_tets);
            // A move onto another point exactly would leave a vertex out: undo the round.
            if (0..n as u32).any(|v| new_stars.of(v).is_empty()) {
                for &(v, old) in &moves {
                    points[v as usize] = old;
                }
                continue;
            }
            old_seen.resize(tets.len(), 0);
            new_seen.resize(new_tets.len(), 0);
            let mut undone = false;
            for &(v, old) in &moves {
                // The neighbourhood: v and its neighbours before and after the move; compared
                // over every tet touching it in either triangulation.
                stamp += 1;
                region.clear();
                for (s, list) in [(stars.of(v), &*tets), (new_stars.of(v), &new_tets)] {
                    for &t in s {
                        for a in list[t as usize] {
                            if in_region[a as usize] != stamp {
                                in_region[a as usize] = stamp;
                                region.push(a);
                            }
                        }
                    }
                }
                old_q.clear();
                new_q.clear();
                for &a in &region {
                    for &t in stars.of(a) {
                        if old_seen[t as usize] != stamp {
                            old_seen[t as usize] = stamp;
                            old_q.push(quality[t as usize]);
                        }
                    }
                    for &t in new_stars.of(a) {
                        if new_seen[t as usize] != stamp {
                            new_seen[t as usize] = stamp;
                            new_q.push(new_quality[t as usize]);
                        }
                    }
                }
                old_q.sort_by(f64::total_cmp);
                new_q.sort_by(f64::total_cmp);
                if better(&new_q, &old_q) {
                    self.moves_kept += 1;
                } else {
                    points[v as usize] = old;
                    undone = true;
                }
            }
            if undone {
                *tets = triangulate(points)?;
                quality = min_angles(points, tets);
            } else {
                *tets = new_tets;
                quality = new_quality;
            }
            let worst = worst_of(&quality);
            if worst > best_min {
                best_min = worst;
                best.0.clone_from(points);
                best.1.clone_from(tets);
            }
        }
        if worst_of(&quality) < best_min {
            (*points, *tets) = best;
        }
        Ok(rounds)
    }

    /// Smoothing with `tets` fixed (see the module docs). Returns the sweeps run.
    fn smooth(&mut self, points: &mut [[f64; 3]], tets: &[[u32; 4]]) -> usize {
        let n = points.len();
        let stars = Stars::new(n, tets);
        let mut quality = min_angles(points, tets);
        let mut seen = vec![0u32; n];
        // A vertex that found nothing better is skipped until a vertex of its star moves:
        // `clock` counts moves, `touched` is the clock of the last move in a vertex's star,
        // `failed` the clock when the vertex last found nothing better (0: never).
        let mut clock = 1u32;
        let mut touched = vec![0u32; n];
        let mut failed = vec![0u32; n];
        let mut sweeps = 0;
        for sweep in 1..=SWEEPS as u32 {
            let worst = quality.iter().copied().fold(f64::INFINITY, f64::min);
            let limit = SMOOTH_TARGET_DEG.min(worst + SMOOTH_WINDOW_DEG);
            let mut bad: Vec<u32> = (0..tets.len() as u32)
                .filter(|&t| quality[t as usize] < limit)
                .collect();
            if bad.is_empty() {
                break;
            }
            sweeps += 1;
            bad.sort_by(|&a, &b| quality[a as usize].total_cmp(&quality[b as usize]));
            let mut improved = false;
            for &t in &bad {
                for v in tets[t as usize] {
                    if self.placement[v as usize] == Placement::Corner
                        || seen[v as usize] == sweep
                        || (failed[v as usize] != 0 && touched[v as usize] <= failed[v as usize])
                    {
                        continue;
                    }
                    seen[v as usize] = sweep;
                    let star = stars.of(v);
                    // The largest cosine of a dihedral angle in the star: smaller is better.
                    let mut best_cos = star
                        .iter()
                        .map(|&s| quality[s as usize].to_radians().cos())
                        .fold(f64::NEG_INFINITY, f64::max);
                    let origin = points[v as usize];
                    let mut best_at = origin;
                    for k in 0..SMOOTH_TRIES {
                        let radius = MAX_STEP * self.h * (1.0 - k as f64 / SMOOTH_TRIES as f64);
                        let q = self.perturbed(best_at, v, radius);
                        points[v as usize] = q;
                        let mut worst_cos = f64::NEG_INFINITY;
                        for &s in star {
                            let p = tets[s as usize].map(|w| points[w as usize]);
                            let c = max_cos(p);
                            if c >= best_cos || orient(p[0], p[1], p[2], p[3]) <= 0.0 {
                                worst_cos = f64::INFINITY;
                                break;
                            }
                            worst_cos = worst_cos.max(c);
                        }
                        if worst_cos < best_cos {
                            best_cos = worst_cos;
                            best_at = q;
                        }
                    }
                    points[v as usize] = best_at;
                    if best_at != origin {
                        improved = true;
                        clock += 1;
                        for &s in star {
                            quality[s as usize] = tet_min_angle(points, tets[s as usize]);
                            for w in tets[s as usize] {
                                touched[w as usize] = clock;
                            }
                        }
                    } else {
                        failed[v as usize] = clock;
                    }
                }
            }
            if !improved {
                break;
            }
        }
        sweeps
    }

    /// `p` (the position of vertex `v`) moved at random by up to `radius` (length) without
    /// leaving its place on the box, keeping [`MOVE_MARGIN`]` * h` from the box faces it does
    /// not lie on (or where it already was, if closer).
    fn perturbed(&mut self, p: [f64; 3], v: u32, radius: f64) -> [f64; 3] {
        let step = radius * self.rng.uniform();
        // A uniform direction, then zeroed along the axes the vertex may not move on.
        let z = 2.0 * self.rng.uniform() - 1.0;
        let phi = std::f64::consts::TAU * self.rng.uniform();
        let s = (1.0 - z * z).sqrt();
        let d = [s * phi.cos(), s * phi.sin(), z];
        let free = match self.placement[v as usize] {
            Placement::Corner => [false; 3],
            Placement::Edge { axis } => [0, 1, 2].map(|k| k == axis),
            Placement::Face { axis } => [0, 1, 2].map(|k| k != axis),
            Placement::Interior => [true; 3],
        };
        let norm = (0..3)
            .filter(|&k| free[k])
            .map(|k| d[k] * d[k])
            .sum::<f64>()
            .sqrt();
        if norm == 0.0 {
            return p;
        }
        let margin = MOVE_MARGIN * self.h;
        let mut q = p;
        for k in (0..3).filter(|&k| free[k]) {
            let lo = (self.min[k] + margin).min(p[k]);
            let hi = (self.max[k] - margin).max(p[k]);
            q[k] = (p[k] + step * d[k] / norm).clamp(lo, hi);
        }
        q
    }
}
