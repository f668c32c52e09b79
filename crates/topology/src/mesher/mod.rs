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

mod bvh;
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
