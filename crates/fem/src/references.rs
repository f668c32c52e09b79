//! Large-deformation reference cases for the peridynamics benchmark, on a bar along x meshed
//! by the caller (the benchmark's `perifrac_topology::primitives::bar_data(1.0, [0.1, 0.1],
//! nx)`: x in [0, 1], y and z in [-0.05, 0.05]): a soft cantilever bent tens of degrees by
//! its own weight, and a bar twisted through a full turn. Both are P2, compressible
//! neo-Hookean, solved by [`static_neo_hookean`].
//!
//! Measured on that bar with `nx` = 10, 20, 40 cells along (1, 2, 4 across), default options
//! (10 load steps, degree-5 rule) for bending and 16 load steps for the twist:
//!
//! | case | quantity | nx 10 | nx 20 | nx 40 |
//! |---|---|---|---|---|
//! | bending | free-end centre x (m) | 0.814017 | 0.809757 | 0.808766 |
//! | bending | free-end centre z (m) | -0.544086 | -0.550726 | -0.552285 |
//! | bending | free-end slope (deg) | 44.193 | 44.540 | 44.627 |
//! | twist | mid-span corner (0.5, 0.05, 0.05) y (m) | -0.048608 | -0.049865 | -0.049701 |
//! | twist | same corner, z (m) | -0.052115 | -0.049691 | -0.049600 |
//!
//! The bending tip converges at second order (successive changes in z shrink 4.26 times), so
//! nx = 40 is within about 5e-4 m (0.1 %) of the converged tip; the twist's corners move
//! 2.7e-3 m from 10 to 20 cells and 1.6e-4 m from 20 to 40.

use std::f64::consts::TAU;

use crate::error::FemError;
use crate::material::Material;
use crate::math::Vec3;
use crate::mesh::Mesh;
use crate::nonlinear::{static_neo_hookean, NewtonOptions, NonlinearSolution};
use crate::problem::Problem;
use crate::sampler::Sampler;

/// Young's modulus (Pa) of the large-bending case: with nu = 0.3, rho = 1000 kg/m^3 and
/// g = 9.81 m/s^2 the free end of the 1 x 0.1 x 0.1 m bar turns 44.6 degrees (linear theory,
/// `q L^3 / (6 E I)`, would say 56), its centre dropping 0.55 m.
pub const BENDING_YOUNG: f64 = 2.0e6;
/// Young's modulus (Pa) of the twist case (without gravity the deformed shape does not depend
/// on it; the reactions scale with it).
pub const TWIST_YOUNG: f64 = 1.0e6;
/// Poisson's ratio of both cases.
pub const REFERENCE_POISSON: f64 = 0.3;
/// Density (kg/m^3) of both cases.
pub const REFERENCE_DENSITY: f64 = 1000.0;
/// Gravity (m/s^2) of the bending case.
pub const REFERENCE_GRAVITY: Vec3 = [0.0, 0.0, -9.81];

/// A solved reference case.
#[derive(Debug, Clone)]
pub struct Reference {
    /// The problem solved (its mesh, material, gravity and constraints).
    pub problem: Problem,
    /// The solution.
    pub solution: NonlinearSolution,
}

impl Reference {
    /// Current positions (m) of material points given by their rest positions (m), by P2
    /// interpolation of the nodal displacements.
    pub fn positions_at(&self, rest: &[Vec3]) -> Result<Vec<Vec3>, FemError> {
        let sampler = Sampler::new(self.problem.mesh(), rest)?;
        let u = sampler.interpolate(&self.solution.displacements);
        Ok(rest
            .iter()
            .zip(u)
            .map(|(x, d)| std::array::from_fn(|i| x[i] + d[i]))
            .collect())
    }
}

/// Extent of the vertices: (min, max) per axis (m).
fn bounds(vertices: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in vertices {
        for d in 0..3 {
            lo[d] = lo[d].min(v[d]);
            hi[d] = hi[d].max(v[d]);
        }
    }
    (lo, hi)
}

/// The large-bending problem on the bar meshed by `vertices` and `tets`: P2,
/// [`BENDING_YOUNG`], [`REFERENCE_POISSON`], [`REFERENCE_DENSITY`], gravity
/// [`REFERENCE_GRAVITY`], clamped (all nodes fixed) at its smallest x.
pub fn large_bending_problem(
    vertices: Vec<Vec3>,
    tets: Vec<[u32; 4]>,
) -> Result<Problem, FemError> {
    let (lo, hi) = bounds(&vertices);
    let mesh = Mesh::quadratic(vertices, tets)?;
    let material = Material::new(BENDING_YOUNG, REFERENCE_POISSON, REFERENCE_DENSITY)?;
    let mut problem = Problem::new(mesh, material)?.with_gravity(REFERENCE_GRAVITY);
    let tol = 1e-9 * (hi[0] - lo[0]);
    problem.fix_where(|x| x[0] <= lo[0] + tol);
    Ok(problem)
}

/// [`large_bending_problem`] solved with `options` (time plays no part).
pub fn large_bending(
    vertices: Vec<Vec3>,
    tets: Vec<[u32; 4]>,
    options: &NewtonOptions,
) -> Result<Reference, FemError> {
    let problem = large_bending_problem(vertices, tets)?;
    let solution = static_neo_hookean(&problem, 0.0, options)?;
    Ok(Reference { problem, solution })
}

/// The twist problem on the bar meshed by `vertices` and `tets`: P2, [`TWIST_YOUNG`],
/// [`REFERENCE_POISSON`], [`REFERENCE_DENSITY`], no gravity, clamped at its smallest x, its
/// end at the largest x turned rigidly by `turns * 360 degrees * t` at time `t` (s) about the
/// line along x through the centre of its cross-section's bounding box (the right-hand sense:
/// +y towards +z), so that the solve to `t_final = 1` s turns it `turns` times.
pub fn twist_problem(
    vertices: Vec<Vec3>,
    tets: Vec<[u32; 4]>,
    turns: f64,
) -> Result<Problem, FemError> {
    if !turns.is_finite() {
        return Err(FemError::BadOption {
            name: "turns",
            value: turns,
            range: "finite",
        });
    }
    let (lo, hi) = bounds(&vertices);
    let (cy, cz) = (0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    let mesh = Mesh::quadratic(vertices, tets)?;
    let material = Material::new(TWIST_YOUNG, REFERENCE_POISSON, REFERENCE_DENSITY)?;
    let mut problem = Problem::new(mesh, material)?;
    let tol = 1e-9 * (hi[0] - lo[0]);
    problem.fix_where(|x| x[0] <= lo[0] + tol);
    problem.prescribe_where(
        |x| x[0] >= hi[0] - tol,
        move |x, t| {
            let (s, c) = (turns * TAU * t).sin_cos();
            let (y, z) = (x[1] - cy, x[2] - cz);
            [x[0], cy + c * y - s * z, cz + s * y + c * z]
        },
    );
    Ok(problem)
}

/// [`twist_problem`] solved to `t_final = 1` s with `options`.
pub fn twist(
    vertices: Vec<Vec3>,
    tets: Vec<[u32; 4]>,
    turns: f64,
    options: &NewtonOptions,
) -> Result<Reference, FemError> {
    let problem = twist_problem(vertices, tets, turns)?;
    let solution = static_neo_hookean(&problem, 1.0, options)?;
    Ok(Reference { problem, solution })
}
