//! The mesher's entry point: options, report, errors and the pipeline.

use thiserror::Error;

use super::fragments::{drop_small_fragments, FragmentReport};
use super::lattice::BccLattice;
use super::manifold::{make_boundary_manifold, ManifoldReport};
use super::snap::{snap_to_surface, SnapReport};
use super::surface_check::{capped_volume, check_surface, SurfaceProblems};
use super::winding::Winding;
use crate::faces::signed_volume;
use crate::quality::dihedral_angles_deg;

/// Tets aimed for when neither an edge length nor a resolution is given.
pub const DEFAULT_TARGET_TETS: f64 = 50_000.0;

/// Most lattice points the mesher will allocate (about 1.2 GB of work arrays at most).
const MAX_LATTICE_POINTS: usize = 40_000_000;

/// A surface enclosing less than this fraction of its bounding box is taken as flat.
const FLAT_FRACTION: f64 = 1e-3;

/// How fine to mesh; at most one of the two may be set.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MesherOptions {
    /// Lattice spacing (the length of the axis-aligned lattice edges).
    pub edge_length: Option<f64>,
    /// Lattice cells across the longest side of the bounding box.
    pub resolution: Option<usize>,
}

/// What the mesher found and did.
#[derive(Debug, Clone, PartialEq)]
pub struct MesherReport {
    /// Problems found in the input surface (after merging duplicate vertices).
    pub problems: SurfaceProblems,
    /// Whether the input faces were all reversed because they enclosed a negative volume.
    pub reoriented: bool,
    /// The winding number decided inside on a surface that is not watertight.
    pub used_winding_on_open_surface: bool,
    /// Volume enclosed by the surface, holes capped by fans from their boundary loops' centroids.
    pub surface_volume: f64,
    /// Volume of the tet mesh.
    pub mesh_volume: f64,
    /// Lattice spacing used.
    pub edge_length: f64,
    /// Loose fragments dropped after clipping.
    pub fragments: FragmentReport,
    /// Tets removed where the clipped boundary pinched at a lattice vertex or edge.
    pub manifold: ManifoldReport,
    /// What snapping did.
    pub snap: SnapReport,
    /// Number of tets.
    pub tets: usize,
    /// Smallest dihedral angle, in degrees.
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle, in degrees.
    pub max_dihedral_deg: f64,
}

/// A tet mesh, every tet positively oriented.
#[derive(Debug, Clone)]
pub struct MesherOutput {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Tets as vertex indices, positively oriented.
    pub tets: Vec<[u32; 4]>,
    /// What was found and done.
    pub report: MesherReport,
}

/// Why a surface cannot be meshed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MesherError {
    /// No faces at all.
    #[error("the surface has no faces")]
    Empty,
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {vertex}, but there are only {num_vertices} vertices")]
    VertexOutOfRange {
        /// Index of the face.
        face: usize,
        /// The offending index.
        vertex: u32,
        /// Number of vertices given.
        num_vertices: usize,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate {coords:?}")]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: usize,
        /// Its coordinates.
        coords: [f64; 3],
    },
    /// Both or neither sizing options are unusable.
    #[error("invalid sizing: {0}")]
    BadSizing(String),
    /// The surface is flat or otherwise encloses (almost) nothing.
    #[error(
        "the surface encloses no volume ({volume:.3e} against a bounding box of {box_volume:.3e}): \
         it is flat or a sheet, not a solid, so there is nothing to fill with tets"
    )]
    EnclosesNoVolume {
        /// Enclosed (or winding-number) volume.
        volume: f64,
        /// Bounding-box volume.
        box_volume: f64,
    },
    /// The requested spacing would need too large a lattice.
    #[error("edge length {edge_length:.3e} needs {points} lattice points, more than {MAX_LATTICE_POINTS}; use a larger edge length")]
    TooFine {
        /// Requested spacing.
        edge_length: f64,
        /// Lattice points it would need.
        points: usize,
    },
}

/// An upper estimate of the tets [`mesh_surface`] makes of a surface with these vertices, made
/// before anything is allocated: a BCC lattice of spacing `h` has 12 tets per `h^3`, and the
/// solid fills at most its bounding box (each side taken as at least `h`); a sphere fills about
/// half of it, so the estimate is up to about twice the count for round shapes. About
/// [`DEFAULT_TARGET_TETS`] when neither option is given, and 0 for options `mesh_surface`
/// refuses anyway.
pub fn estimated_tets(vertices: &[[f64; 3]], opts: &MesherOptions) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in vertices.iter().filter(|p| p.iter().all(|x| x.is_finite())) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let extent = [0, 1, 2].map(|k| (hi[k] - lo[k]).max(0.0));
    let h = match (opts.edge_length, opts.resolution) {
        (None, None) => return DEFAULT_TARGET_TETS,
        (Some(l), None) => l,
        (None, Some(n)) if n > 0 => extent.iter().cloned().fold(0.0, f64::max) / n as f64,
        _ => return 0.0,
    };
    if !(h.is_finite() && h > 0.0) {
        return 0.0;
    }
    12.0 * extent.iter().map(|&e| e.max(h) / h).product::<f64>()
}

/// Meshes the solid bounded by the triangle surface `faces` on `vertices`.
pub fn mesh_surface(
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    opts: &MesherOptions,
) -> Result<MesherOutput, MesherError> {
    validate(vertices, faces)?;
    let clean = check_surface(vertices, faces);
    let mut tri = clean.faces;
    let mut volume = capped_volume(&clean.vertices, &tri);
    let reoriented = volume < 0.0;
    if reoriented {
        for f in &mut tri {
            f.swap(1, 2);
        }
        volume = -volume;
    }
    let (lo, hi) = bounds(&clean.vertices, &tri);
    let extent = [0, 1, 2].map(|k| hi[k] - lo[k]);
    let box_volume = extent[0] * extent[1] * extent[2];
    let solid = volume > FLAT_FRACTION * box_volume && box_volume > 0.0;
    if !solid {
        return Err(MesherError::EnclosesNoVolume { volume, box_volume });
    }
    let h = spacing(opts, extent, volume)?;
    let lattice = BccLattice::covering(lo, hi, h);
    let points = lattice.num_points();
    if points > MAX_LATTICE_POINTS {
        return Err(MesherError::TooFine {
            edge_length: h,
            points,
        });
    }
    let winding = Winding::new(&clean.vertices, &tri);
    let inside: Vec<bool> = (0..points as u32)
        .map(|p| winding.inside(lattice.point(p)))
        .collect();
    let mut tets = Vec::new();
    let mut all = Vec::new();
    lattice.for_each_tet(|t| {
        all.push(t);
        let n = t.iter().filter(|&&v| inside[v as usize]).count();
        let keep = match n {
            0 => false,
            4 => true,
            _ => {
                let p = t.map(|v| lattice.point(v));
                let c = [0, 1, 2].map(|k| 0.25 * (p[0][k] + p[1][k] + p[2][k] + p[3][k]));
                winding.inside(c)
            }
        };
        if keep {
            tets.push(t);
        }
    });
    let mut fragments = drop_small_fragments(&mut tets);
    let manifold = make_boundary_manifold(&mut tets, &all);
    drop(all);
    if manifold.removed_tets > 0 {
        // Removing tets at a pinch can leave a loose bit behind.
        let again = drop_small_fragments(&mut tets);
        fragments.dropped_pieces += again.dropped_pieces;
        fragments.dropped_tets += again.dropped_tets;
    }
    // Compact the used lattice points and orient every tet positively.
    let mut new_index = vec![u32::MAX; points];
    let mut out_vertices = Vec::new();
    for t in &mut tets {
        for v in t.iter_mut() {
            if new_index[*v as usize] == u32::MAX {
                new_index[*v as usize] = out_vertices.len() as u32;
                out_vertices.push(lattice.point(*v));
            }
            *v = new_index[*v as usize];
        }
        let p = t.map(|v| out_vertices[v as usize]);
        if signed_volume(p[0], p[1], p[2], p[3]) < 0.0 {
            t.swap(2, 3);
        }
    }
    if tets.is_empty() {
        return Err(MesherError::EnclosesNoVolume {
            volume: 0.0,
            box_volume,
        });
    }
    let snap = snap_to_surface(&mut out_vertices, &tets, winding.bvh(), h);
    let (mut min_d, mut max_d, mut mesh_volume) = (f64::INFINITY, 0.0f64, 0.0);
    for t in &tets {
        let p = t.map(|v| out_vertices[v as usize]);
        mesh_volume += signed_volume(p[0], p[1], p[2], p[3]);
        for a in dihedral_angles_deg(p) {
            min_d = min_d.min(a);
            max_d = max_d.max(a);
        }
    }
    let report = MesherReport {
        used_winding_on_open_surface: !clean.problems.is_watertight(),
        problems: clean.problems,
        reoriented,
        surface_volume: volume,
        mesh_volume,
        edge_length: h,
        fragments,
        manifold,
        snap,
        tets: tets.len(),
        min_dihedral_deg: min_d,
        max_dihedral_deg: max_d,
    };
    Ok(MesherOutput {
        vertices: out_vertices,
        tets,
        report,
    })
}

fn validate(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<(), MesherError> {
    if faces.is_empty() {
        return Err(MesherError::Empty);
    }
    for (face, f) in faces.iter().enumerate() {
        for &vertex in f {
            if vertex as usize >= vertices.len() {
                return Err(MesherError::VertexOutOfRange {
                    face,
                    vertex,
                    num_vertices: vertices.len(),
                });
            }
        }
    }
    for (vertex, p) in vertices.iter().enumerate() {
        if p.iter().any(|x| !x.is_finite()) {
            return Err(MesherError::NonFiniteVertex { vertex, coords: *p });
        }
    }
    Ok(())
}

/// Bounding box of the vertices used by faces.
fn bounds(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> ([f64; 3], [f64; 3]) {
    super::point_bounds(faces.iter().flatten().map(|&v| vertices[v as usize]))
}

/// Lattice spacing from the options, or for about [`DEFAULT_TARGET_TETS`] tets (a BCC cell of
/// side `h` holds 12 tets of volume `h^3 / 12`).
fn spacing(opts: &MesherOptions, extent: [f64; 3], volume: f64) -> Result<f64, MesherError> {
    let h = match (opts.edge_length, opts.resolution) {
        (Some(_), Some(_)) => {
            return Err(MesherError::BadSizing(
                "give an edge length or a resolution, not both".into(),
            ))
        }
        (Some(l), None) => l,
        (None, Some(0)) => {
            return Err(MesherError::BadSizing(
                "the resolution must be at least 1".into(),
            ))
        }
        (None, Some(n)) => extent.iter().cloned().fold(0.0, f64::max) / n as f64,
        (None, None) => (12.0 * volume / DEFAULT_TARGET_TETS).cbrt(),
    };
    if !(h.is_finite() && h > 0.0) {
        return Err(MesherError::BadSizing(format!(
            "the edge length must be positive and finite, found {h}"
        )));
    }
    Ok(h)
}
