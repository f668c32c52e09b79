//! Reference finite elements for perifrac's accuracy benchmark: linear (P1) and quadratic (P2)
//! straight-sided tets, isotropic linear elasticity with linear or corotated kinematics, static
//! (sparse Cholesky) and explicit dynamic (velocity Verlet, lumped mass) solves, static
//! compressible neo-Hookean elasticity (Newton with load stepping, [`static_neo_hookean`]) with
//! two large-deformation reference cases, and sampling of nodal fields at arbitrary rest
//! points.
//!
//! Plain arrays in (`[f64; 3]` vertices, `[u32; 4]` tets), SI units throughout (m, s, kg, Pa,
//! N, J). Independent of the peridynamic crates, so the two can be compared.
//!
//! ```
//! use perifrac_fem::{static_linear, Material, Mesh, Problem, Sampler};
//! // The benchmark's cantilever: 1 x 0.1 x 0.1 m, clamped at x = 0, under gravity.
//! let (v, t) = perifrac_topology::primitives::bar_data(1.0, [0.1, 0.1], 20);
//! let mesh = Mesh::quadratic(v, t)?;
//! let mut problem = Problem::new(mesh, Material::new(1e8, 0.3, 1000.0)?)?
//!     .with_gravity([0.0, 0.0, -9.81]);
//! problem.fix_where(|x| x[0] <= 1e-12);
//! let solution = static_linear(&problem)?;
//! let tip = Sampler::new(problem.mesh(), &[[1.0, 0.0, 0.0]])?.interpolate(&solution.displacements);
//! assert!((-tip[0][2] - 0.014652).abs() < 1e-6); // 20x2x2 cells; converged 3D: 0.014728 m
//! # Ok::<(), perifrac_fem::FemError>(())
//! ```

mod assembly;
mod basis;
mod dynamics;
mod element;
mod error;
mod forces;
mod hyperelastic;
mod hyperelastic_element;
mod hyperelastic_system;
mod material;
mod math;
mod mesh;
mod newton;
mod nonlinear;
mod problem;
mod references;
mod sampler;
mod shifted_cholesky;
mod statics;

pub use basis::EDGES;
pub use dynamics::{critical_time_step, lumped_masses, Dynamic};
pub use error::FemError;
pub use forces::{ElasticForces, Kinematics, Parallelism, SERIAL_BELOW};
pub use hyperelastic::{NeoHookean, PiolaTangent};
pub use hyperelastic_element::{
    neo_hookean_energy, neo_hookean_gradient, neo_hookean_tangent, Quadrature,
};
pub use material::Material;
pub use math::{Mat3, Real, Vec3};
pub use mesh::{Mesh, Order};
pub use nonlinear::{static_neo_hookean, NewtonOptions, NonlinearSolution, StepReport};
pub use problem::{Constraint, Motion, Problem};
pub use references::{
    large_bending, large_bending_problem, twist, twist_problem, Reference, BENDING_YOUNG,
    REFERENCE_DENSITY, REFERENCE_GRAVITY, REFERENCE_POISSON, TWIST_YOUNG,
};
pub use sampler::Sampler;
pub use statics::{static_linear, static_linear_at, Solution};
