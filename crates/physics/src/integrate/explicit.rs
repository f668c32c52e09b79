//! Explicit velocity Verlet (kick, drift, kick) with loads, a stable-step choice and a blow-up
//! guard.
//!
//! Velocity Verlet costs one force evaluation per step like semi-implicit Euler, but it is
//! second order and time-reversible, and positions and velocities are known at the same instant,
//! so the kinetic plus elastic energy it reports is conserved to O(dt^2) without drift. Both have
//! the same stability limit `dt < 2 / omega_max`.

use crate::energy;
use crate::error::PhysicsError;
use crate::loads::Loads;
use crate::material::ForceModel;
use crate::math::{dot, Vec3};
use crate::stable_step::{stable_frequency, FrequencyEstimate};
use rayon::prelude::*;

/// How the step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStep {
    /// A fixed step (s).
    Fixed(f64),
    /// `safety * 2 / omega_max` from power iteration at the rest shape (at most 100 iterations,
    /// two force evaluations each, stopping at a 1e-5 relative change); the Silling-Askari bound
    /// times `safety` if the iteration fails. The estimate converges from below, so keep
    /// `safety` under 1 (0.9 is measured stable, see tests/dynamics.rs).
    Auto {
        /// Fraction of the estimated limit, e.g. 0.8.
        safety: f64,
    },
}

/// Integrator settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplicitConfig {
    /// Step choice.
    pub dt: TimeStep,
    /// A step that moves any particle further than this fraction of the horizon (or a
    /// non-finite position) is an error, [`PhysicsError::Unstable`]; > 0, infinity disables
    /// the distance test (non-finite values are still caught).
    pub guard_fraction: f64,
}

impl Default for ExplicitConfig {
    fn default() -> Self {
        ExplicitConfig {
            dt: TimeStep::Auto { safety: 0.8 },
            guard_fraction: 0.5,
        }
    }
}

/// What an external-force callback of [`Explicit::step_with`] sees.
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

/// The explicit solver: owns the model, the particle state and every per-step buffer.
pub struct Explicit<M: ForceModel> {
    model: M,
    y: Vec<Vec3>,
    v: Vec<Vec3>,
    f: Vec<Vec3>,
    inv_mass: Vec<f64>,
    loads: Loads,
    dt: f64,
    guard: f64,
    time: f64,
    steps: u64,
    broken: Vec<(u32, u32)>,
    estimate: Option<FrequencyEstimate>,
}

impl<M: ForceModel> Explicit<M> {
    /// Starts at rest at `rest` (m). `horizon` (m) scales the blow-up guard and the probe of the
    /// stable-step estimate.
    pub fn new(
        mut model: M,
        rest: &[Vec3],
        horizon: f64,
        loads: Loads,
        config: ExplicitConfig,
    ) -> Result<Self, PhysicsError> {
        let n = model.num_particles();
        if rest.len() != n || loads.len() != n {
            return Err(PhysicsError::LengthMismatch {
                what: "rest positions / loads",
                expected: n,
                got: if rest.len() != n {
                    rest.len()
                } else {
                    loads.len()
                },
            });
        }
        if config.guard_fraction.is_nan() || config.guard_fraction <= 0.0 {
            return Err(PhysicsError::BadSetting(format!(
                "guard fraction {} must be positive (infinity disables the guard)",
                config.guard_fraction
            )));
        }
        let (dt, estimate) = match config.dt {
            TimeStep::Fixed(dt) => (dt, None),
            TimeStep::Auto { safety } => {
                let (omega, est) = stable_frequency(&mut model, rest, horizon);
                (safety * (2.0 / omega), Some(est))
            }
        };
        if !(dt.is_finite() && dt > 0.0) {
            return Err(PhysicsError::BadTimeStep(dt));
        }
        let inv_mass = model.masses().iter().map(|m| 1.0 / m).collect();
        let y = rest.to_vec();
        let mut f = vec![[0.0; 3]; n];
        model.update_forces(&y, &mut f);
        Ok(Explicit {
            model,
            y,
            v: vec![[0.0; 3]; n],
            f,
            inv_mass,
            loads,
            dt,
            guard: config.guard_fraction * horizon,
            time: 0.0,
            steps: 0,
            broken: Vec::new(),
            estimate,
        })
    }

    /// Advances one step of `dt`; returns the bonds broken in it as `(i, j)`, `i < j`. After an
    /// error the state is that of the failed step (restore a checkpoint to go on).
    pub fn step(&mut self) -> Result<&[(u32, u32)], PhysicsError> {
        self.step_with(|_| {})
    }

    /// Advances one step like [`Explicit::step`], with external forces: after the drift to
    /// `y(t + dt)` and the internal forces there, `external` may add forces (N) into
    /// [`External::forces`] (contact, say); they act in the closing half kick and the opening
    /// half kick of the next step, as internal forces do. Velocities seen are the half-step
    /// ones. The closure runs once per step, on the calling thread.
    pub fn step_with<F>(&mut self, mut external: F) -> Result<&[(u32, u32)], PhysicsError>
    where
        F: FnMut(External<'_>),
    {
        self.kick();
        self.drift()?;
        self.broken.clear();
        self.model.break_bonds(&self.y, &mut self.broken);
        self.model.update_forces(&self.y, &mut self.f);
        external(External {
            dt: self.dt,
            positions: &self.y,
            velocities: &self.v,
            masses: self.model.masses(),
            forces: &mut self.f,
        });
        self.kick();
        self.time += self.dt;
        self.steps += 1;
        Ok(&self.broken)
    }

    /// Half-step velocity update with forces, gravity, damping and anchors.
    fn kick(&mut self) {
        let half = 0.5 * self.dt;
        let decay = (-self.loads.damping * half).exp();
        let (f, inv_mass, loads) = (&self.f, &self.inv_mass, &self.loads);
        let g = loads.gravity;
        self.v
            .par_chunks_mut(crate::par::GRAIN)
            .enumerate()
            .for_each(|(c, chunk)| {
                for (o, v) in chunk.iter_mut().enumerate() {
                    let i = c * crate::par::GRAIN + o;
                    if let Some(prescribed) = loads.anchored(i) {
                        *v = prescribed;
                        continue;
                    }
                    for d in 0..3 {
                        v[d] = (v[d] + half * (f[i][d] * inv_mass[i] + g[d])) * decay;
                    }
                }
            });
    }

    /// Position update with the blow-up guard.
    fn drift(&mut self) -> Result<(), PhysicsError> {
        let dt = self.dt;
        let v = &self.v;
        let (worst, at) = self
            .y
            .par_chunks_mut(crate::par::GRAIN)
            .enumerate()
            .map(|(c, chunk)| {
                let mut worst = (0.0f64, usize::MAX);
                for (o, y) in chunk.iter_mut().enumerate() {
                    let i = c * crate::par::GRAIN + o;
                    let vi = v[i];
                    for d in 0..3 {
                        y[d] += dt * vi[d];
                    }
                    let s = dt * dot(vi, vi).sqrt();
                    let s = if s.is_finite() { s } else { f64::INFINITY };
                    if s > worst.0 {
                        worst = (s, i);
                    }
                }
                worst
            })
            .reduce(
                || (0.0, usize::MAX),
                |a, b| {
                    if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) {
                        b
                    } else {
                        a
                    }
                },
            );
        if worst.is_infinite() || worst > self.guard {
            return Err(PhysicsError::Unstable {
                step: self.steps,
                particle: at,
                displacement: worst,
                limit: self.guard,
            });
        }
        Ok(())
    }

    /// The time step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The power-iteration estimate, when `dt` was `Auto`.
    pub fn estimate(&self) -> Option<FrequencyEstimate> {
        self.estimate
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Current positions (m).
    pub fn positions(&self) -> &[Vec3] {
        &self.y
    }

    /// Current velocities (m/s).
    pub fn velocities(&self) -> &[Vec3] {
        &self.v
    }

    /// Velocities to set initial conditions (m/s).
    pub fn velocities_mut(&mut self) -> &mut [Vec3] {
        &mut self.v
    }

    /// Sets positions (m) and recomputes forces (history advances as in a step).
    pub fn set_positions(&mut self, y: &[Vec3]) {
        self.y.copy_from_slice(y);
        self.model.update_forces(&self.y, &mut self.f);
    }

    /// Internal forces at the current positions (N).
    pub fn forces(&self) -> &[Vec3] {
        &self.f
    }

    /// The loads (e.g. to change damping between phases).
    pub fn loads_mut(&mut self) -> &mut Loads {
        &mut self.loads
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The model, mutably.
    pub fn model_mut(&mut self) -> &mut M {
        &mut self.model
    }

    /// Kinetic energy (J).
    pub fn kinetic_energy(&self) -> f64 {
        energy::kinetic_energy(self.model.masses(), &self.v)
    }

    /// Elastic energy at the current positions (J).
    pub fn elastic_energy(&mut self) -> f64 {
        self.model.elastic_energy(&self.y)
    }
}
