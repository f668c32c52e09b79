//! Built-in tetrahedral mesher: a closed (or slightly open) triangle surface to a tet mesh.
//!
//! The surface is cleaned ([`surface_check`]), a body-centred cubic lattice ([`lattice`]) covers
//! it, lattice tets are kept by generalised winding number ([`winding`]) at their corners and,
//! where those disagree, their centroid, loose fragments are dropped ([`fragments`]), and the
//! boundary of what is kept is snapped onto the
//! surface under a dihedral-angle guard ([`snap`]).
//!
//! Separately, [`unstructured`] meshes an axis-aligned box without a lattice: well-spaced points
//! ([`scatter`]), their Delaunay tetrahedralisation ([`delaunay`]) and sliver removal.

pub(crate) mod bvh;
pub mod delaunay;
pub mod fragments;
pub mod lattice;
pub mod manifold;
mod mesh_surface;
pub mod scatter;
pub mod shapes;
pub mod snap;
pub mod surface_check;
pub mod unstructured;
pub mod winding;

pub use fragments::FragmentReport;
pub use manifold::ManifoldReport;
pub use mesh_surface::{
    estimated_tets, mesh_surface, MesherError, MesherOptions, MesherOutput, MesherReport,
    DEFAULT_TARGET_TETS,
};
pub use shapes::{cube_surface, cylinder_surface, sphere_surface};
pub use snap::SnapReport;
pub use surface_check::{
    capped_volume, check_surface, enclosed_volume, CleanSurface, SurfaceProblems,
};
pub use unstructured::{unstructured_box_data, UnstructuredError};
pub use winding::Winding;

/// How a box is cut into tets: a lattice of six tets a cell, or the unstructured mesher's tets
/// from points of a seed (about as many).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoxCut {
    /// [`crate::primitives::lattice_box_data`].
    Lattice(crate::primitives::Lattice),
    /// [`unstructured_box_data`] with this seed.
    Unstructured(u64),
}

/// Vertices and tets of the box `min..max` (m) of `cells` cuboids, cut as `cut` says; an error
/// only from the unstructured mesher. The counts are not checked here (see
/// [`crate::primitives::check_box`]).
#[allow(clippy::type_complexity)]
pub fn box_cut_data(
    min: [f64; 3],
    max: [f64; 3],
    cells: [usize; 3],
    cut: BoxCut,
) -> Result<(Vec<[f64; 3]>, Vec<[u32; 4]>), UnstructuredError> {
    match cut {
        BoxCut::Lattice(l) => Ok(crate::primitives::lattice_box_data(min, max, cells, l)),
        BoxCut::Unstructured(seed) => unstructured_box_data(min, max, cells, seed),
    }
}

/// Smallest and largest coordinates (m) of `points`; infinities of the wrong sign when empty.
pub fn point_bounds(points: impl IntoIterator<Item = [f64; 3]>) -> ([f64; 3], [f64; 3]) {
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
