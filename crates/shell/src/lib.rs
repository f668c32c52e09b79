//! Thin shells on triangle meshes after Gingold et al. 2004 (`docs/model.md` section 8):
//! membrane strain from the changes of squared edge lengths, bending strain from the changes
//! of `phi(theta) = 2 tan(theta / 2)` of the dihedral angles, both constant per triangle, and
//! Koiter's energy of the two; forces as its exact negative gradient, lumped masses, explicit
//! stepping.
//!
//! ```
//! use perifrac_shell::*;
//! // a 10 cm square steel sheet, 1 mm thick, 4 x 4 quads
//! let s = generate::sheet(0.1, 0.1, 4, 4)?;
//! let mesh = ShellMesh::new(s.vertices, s.triangles)?;
//! let steel = ShellMaterial::new(200e9, 0.3, 7800.0, 1e-3)?;
//! let mut shell = ShellDynamics::new(ShellModel::new(mesh, steel)?)?;
//! shell.velocities_mut()[12] = [0.0, 0.0, 1.0];
//! let dt = 0.5 * shell.stable_step()?;
//! shell.step(dt)?;
//! assert!(shell.elastic_energy() > 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod block_matrix;
mod broad_phase;
pub mod dynamics;
pub mod error;
pub mod fracture;
pub mod generate;
pub mod material;
pub mod mesh;
pub mod model;
pub mod output;
pub mod plastic;
pub mod proximity;
pub mod search;
pub mod self_contact;

pub use dynamics::{max_frequency, NewmarkConfig, NewmarkStats, ShellDynamics, ShellLoad};
pub use error::ShellError;
pub use fracture::{FractureEvent, FractureReport, ShellFracture};
pub use material::ShellMaterial;
pub use mesh::{Edge, Role, ShellMesh, NONE};
pub use model::{dihedral, dihedral_half_tan, phi, phi_of_half_tan, FaceStrain, ShellModel};
pub use output::{enclosed_volume, pieces, FrameMesh};
pub use perifrac_physics::Vec3;
pub use plastic::ShellYield;
pub use search::{SearchStats, SearchedShell, ShellSearch};
pub use self_contact::{SelfContact, SelfContactStats, ShellSelfContact};
