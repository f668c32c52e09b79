//! Tet mesh topology for perifrac.
//!
//! The tetrahedral mesh that the peridynamic particles are embedded in (one particle per tet,
//! tet index == particle index): rest mesh and face adjacency, the crack face set, multi-way
//! vertex splitting, vertex advection from particle velocities, extraction of the surface of every
//! piece with a crack flag, pieces, quality measures and built-in primitive meshes.
//! See docs/model.md section 3 for the model.

#![warn(missing_docs)]

mod advect;
pub mod boundary_planes;
mod build;
mod crack;
mod error;
pub mod faces;
mod fit;
mod mesh;
pub mod mesher;
mod persist;
mod pieces;
pub mod primitives;
mod quality;
mod rigid;
mod shading;
mod smooth;
pub mod spec;
mod split;
mod surface;

pub use boundary_planes::BoundaryPlanes;
pub use build::VOLUME_TOLERANCE;
pub use error::TopologyError;
pub use mesh::{BuildReport, TetMesh, NO_TET};
pub use mesher::point_bounds;
pub use pieces::Pieces;
pub use quality::{dihedral_angles_deg, radius_ratio, Quality};
pub use rigid::RIGID_PIECE_TETS;
pub use shading::{ShadedSurface, ShadingOptions, SHARP_ANGLE};
pub use smooth::{CrackSmoothing, SmoothReport};
pub use split::SplitReport;
pub use surface::Surface;
