//! What acts on the particles from outside the material (contact, say), as the integrators see
//! it. The physics crate names no collider: the caller implements [`Environment`].

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use crate::math::Vec3;

/// What an explicit step shows its environment, after the drift and the internal forces.
pub struct External<'a> {
    /// The step (s).
    pub dt: f64,
    /// Positions at the end of the step (m).
    pub positions: &'a [Vec3],
    /// Half-step velocities (m/s).
    pub velocities: &'a [Vec3],
    /// Particle masses (kg).
    pub masses: &'a [f64],
    /// Internal forces at `positions` (N); add external forces here.
    pub forces: &'a mut [Vec3],
}

/// Forces from outside the material. An explicit integrator calls [`Environment::add_forces`]
/// once per step, on the calling thread; an implicit one asks for
/// [`Environment::implicit`] and fails with a clear error when it is `None`.
pub trait Environment {
    /// Adds external forces (N) into [`External::forces`] at the end-of-drift positions.
    fn add_forces(&mut self, ext: External<'_>);

    /// The same environment as a potential energy for an implicit step, when it can be one.
    fn implicit(&mut self) -> Option<&mut dyn crate::ImplicitEnvironment> {
        None
    }

    /// Writes the environment's own state (colliders' motion), so that a trial step can be
    /// undone by [`Environment::restore`]; stateless environments write nothing.
    fn save(&self, _w: &mut Writer) {}

    /// Reads what [`Environment::save`] wrote.
    fn restore(&mut self, _r: &mut Reader) -> Result<(), CheckpointError> {
        Ok(())
    }
}

/// Nothing outside the material.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoEnvironment;

impl Environment for NoEnvironment {
    fn add_forces(&mut self, _ext: External<'_>) {}

    fn implicit(&mut self) -> Option<&mut dyn crate::ImplicitEnvironment> {
        Some(self)
    }
}

/// An environment made of a closure that adds explicit forces (see
/// [`crate::Explicit::step_with`]).
pub(crate) struct ForcesOnly<F>(pub F);

impl<F: FnMut(External<'_>)> Environment for ForcesOnly<F> {
    fn add_forces(&mut self, ext: External<'_>) {
        (self.0)(ext)
    }
}

/// An environment seen by an implicit step as a potential energy over the particles' end
/// positions `q` and, optionally, extra point bodies of its own (dynamic colliders) whose end
/// positions `c` the step solves for too. The potential includes the bodies' own inertia
/// (`M / (2 dt^2) |c - c*|^2`) and any dissipation written as a potential (damping, friction),
/// so the step minimises one function.
pub trait ImplicitEnvironment {
    /// Starts a step of `dt` (s) from positions `y0` (m) and velocities `v0` (m/s) of
    /// particles of mass `masses` (kg).
    fn begin(
        &mut self,
        dt: f64,
        y0: &[Vec3],
        v0: &[Vec3],
        masses: &[f64],
    ) -> Result<(), crate::PhysicsError>;

    /// Number of extra bodies solved for.
    fn bodies(&self) -> usize;

    /// A starting guess for the bodies' end positions (m), one per body.
    fn body_guess(&self, out: &mut [Vec3]);

    /// A positive diagonal curvature per body (N/m) for the step's preconditioner (its mass
    /// over `dt^2`, say).
    fn body_curvature(&self, out: &mut [f64]);

    /// The potential (J) at particle end positions `q` (m) and body end positions `c` (m);
    /// with `grad`, adds `dP/dq` and `dP/dc` (N) into the two slices.
    fn potential(
        &mut self,
        q: &[Vec3],
        c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64;

    /// The step was accepted at `q`, `c`, with particle end velocities `v` (m/s).
    fn end(&mut self, q: &[Vec3], c: &[Vec3], v: &[Vec3]);

    /// Writes into `out` an upper bound of the curvature (N/m) the environment adds to each
    /// particle at the step's start positions `y0` (m) (its contact stiffness), for the step
    /// matrix; zeros by default.
    fn particle_curvature(&mut self, _y0: &[Vec3], out: &mut [f64]) {
        out.fill(0.0);
    }
}

impl ImplicitEnvironment for NoEnvironment {
    fn begin(
        &mut self,
        _dt: f64,
        _y0: &[Vec3],
        _v0: &[Vec3],
        _masses: &[f64],
    ) -> Result<(), crate::PhysicsError> {
        Ok(())
    }
    fn bodies(&self) -> usize {
        0
    }
    fn body_guess(&self, _out: &mut [Vec3]) {}
    fn body_curvature(&self, _out: &mut [f64]) {}
    fn potential(
        &mut self,
        _q: &[Vec3],
        _c: &[Vec3],
        _grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        0.0
    }
    fn end(&mut self, _q: &[Vec3], _c: &[Vec3], _v: &[Vec3]) {}
}
