//! Static compressible neo-Hookean elasticity with load stepping: at each load parameter `s`
//! the total potential energy `Pi(u) = W(u) - s f . u` (`f` the consistent load of the body
//! force) is minimised over the free DOFs with the held nodes at `held_position(node, s
//! t_final)`, by Newton's method with a backtracking line search on `Pi`.
//!
//! Each load step starts with a predictor: the tangent at the last equilibrium, with the
//! increment of the held nodes' motion as its boundary data (`K_ff du_f = -(r_f + K_fc du_c)`),
//! so a prescribed rotation moves the whole body along instead of shearing the first layer of
//! elements. Its right-hand side, the linearised out-of-balance force of the step, is the
//! reference the step's residual is measured against.
//!
//! The tangent is indefinite where the body is unstable or strongly stretched: the solver
//! then factors `K + tau I` instead (see `shifted_cholesky.rs`), so every direction goes
//! downhill in `Pi`. A trial point where `J <= 0` somewhere is rejected by the line search; a
//! load step that fails (an inverted predictor, no convergence, no decrease) is halved, up to
//! [`NewtonOptions::max_cuts`] times.
//!
//! Iteration order, chunking and sums are fixed, so the result does not depend on the number
//! of threads.

use crate::basis::{P1, P2};
use crate::error::FemError;
use crate::hyperelastic_element::Quadrature;
use crate::math::{add, Vec3};
use crate::mesh::{Mesh, Order};
use crate::newton::Newton;
use crate::problem::Problem;

/// Settings of [`static_neo_hookean`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonOptions {
    /// Number of equal load steps from 0 to 1 (at least 1).
    pub load_steps: usize,
    /// Newton iterations allowed per load step, the predictor included (at least 1).
    pub max_iterations: usize,
    /// A step has converged when the residual norm (N) on the free DOFs is at most
    /// `tolerance` times the step's initial out-of-balance force, or is down to rounding
    /// (eps times the norm of the tangent's diagonal times the displacements, the residual
    /// that one unit in the last place of every displacement makes); in (0, 1).
    pub tolerance: f64,
    /// How many times one load step may be halved after a failure (inverted element,
    /// no convergence, failed line search) before the failure is returned.
    pub max_cuts: usize,
    /// Quadrature of the energy over P2 elements.
    pub quadrature: Quadrature,
}

impl Default for NewtonOptions {
    /// 10 load steps, 30 iterations, tolerance 1e-10, 6 cuts, the degree-5 rule.
    fn default() -> Self {
        Self {
            load_steps: 10,
            max_iterations: 30,
            tolerance: 1e-10,
            max_cuts: 6,
            quadrature: Quadrature::Degree5,
        }
    }
}

impl NewtonOptions {
    fn validate(&self) -> Result<(), FemError> {
        let bad = |name, value: usize, range| {
            Err(FemError::BadOption {
                name,
                value: value as f64,
                range,
            })
        };
        if self.load_steps == 0 {
            return bad("load_steps", 0, "at least 1");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", 0, "at least 1");
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(FemError::BadOption {
                name: "tolerance",
                value: self.tolerance,
                range: "0 < tolerance < 1",
            });
        }
        Ok(())
    }
}

/// How one load step went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Load parameter reached, in (0, 1].
    pub load: f64,
    /// Newton iterations spent (predictors included), failed attempts included.
    pub iterations: usize,
    /// Sub-steps it was done in: 1 unless it had to be cut.
    pub substeps: usize,
    /// Factorisations that needed a diagonal shift (an indefinite tangent).
    pub shifted: usize,
    /// Out-of-balance force (N) at the start of its first sub-step: the reference of the
    /// relative tolerance.
    pub initial_residual: f64,
    /// Residual norm (N) on the free DOFs at the end.
    pub residual: f64,
}

/// A static neo-Hookean solution.
#[derive(Debug, Clone)]
pub struct NonlinearSolution {
    /// Displacement (m) of every node.
    pub displacements: Vec<Vec3>,
    /// Force (N) the supports exert on each held node (zero on free nodes).
    pub reactions: Vec<Vec3>,
    /// One report per load step.
    pub steps: Vec<StepReport>,
    /// Final residual norm (N) on the free DOFs.
    pub residual: f64,
    /// Strain energy (J) at the solution.
    pub strain_energy: f64,
    /// Total potential energy (J) `W - f . u` at the solution.
    pub potential_energy: f64,
    /// Number of free degrees of freedom.
    pub free_dofs: usize,
}

impl NonlinearSolution {
    /// Current positions (m): rest positions of `mesh` plus displacements.
    pub fn positions(&self, mesh: &Mesh) -> Vec<Vec3> {
        mesh.nodes()
            .iter()
            .zip(&self.displacements)
            .map(|(&x, &u)| add(x, u))
            .collect()
    }

    /// Newton iterations over all load steps.
    pub fn total_iterations(&self) -> usize {
        self.steps.iter().map(|s| s.iterations).sum()
    }
}

/// Static compressible neo-Hookean solution of `problem` ([`crate::NeoHookean`] with the
/// problem's material) under its gravity, with prescribed nodes at `held_position(node,
/// t_final)` (s), reached in `options.load_steps` equal steps of the load parameter `s`:
/// gravity `s g`, prescribed nodes at `held_position(node, s t_final)`. Starts from the rest
/// state.
///
/// Errors: [`FemError::BadOption`]; [`FemError::NotPositiveDefinite`] when the constraints
/// leave a rigid motion free; [`FemError::ElementInverted`] (with `time` = `s t_final`),
/// [`FemError::NotConverged`] or [`FemError::LineSearchFailed`] when a load step fails even
/// after `options.max_cuts` halvings. Never returns non-finite displacements.
pub fn static_neo_hookean(
    problem: &Problem,
    t_final: f64,
    options: &NewtonOptions,
) -> Result<NonlinearSolution, FemError> {
    options.validate()?;
    if !t_final.is_finite() {
        return Err(FemError::BadOption {
            name: "t_final",
            value: t_final,
            range: "finite, s",
        });
    }
    match problem.mesh().order() {
        Order::Linear => Newton::<4, P1>::new(problem, t_final, options)?.run(),
        Order::Quadratic => Newton::<10, P2>::new(problem, t_final, options)?.run(),
    }
}
