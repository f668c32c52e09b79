//! Explicit velocity Verlet (kick, drift, kick) with loads, a stable-step choice and a blow-up
//! guard.
//!
//! Velocity Verlet costs one force evaluation per step like semi-implicit Euler, but it is
//! second order and time-reversible, and positions and velocities are known at the same instant,
//! so the kinetic plus elastic energy it reports is conserved to O(dt^2) without drift. Both have
//! the same stability limit `dt < 2 / omega_max`.

use super::simulation::{check_lengths, restore_dt, Integrator, Simulation};
use crate::environment::{Environment, External, ForcesOnly};
use crate::error::PhysicsError;
use crate::loads::Loads;
use crate::material::ForceModel;
use crate::math::{dot, norm, sub, Vec3};
use crate::stable_step::{stable_frequency, FrequencyEstimate};
use crate::state::State;
use perifrac_checkpoint::{Reader, Writer};
use rayon::prelude::*;

/// How the step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStep {
    /// A fixed step (s).
    Fixed(f64),
    /// `safety * 2 / omega_max` from Lanczos at the rest shape ([`crate::stable_frequency`]:
    /// one force evaluation per iteration, stopping at a 1e-6 relative change); the
    /// Silling-Askari bound times `safety` if the iteration fails. The estimate converges from
    /// below, so keep `safety` under 1 (0.9 is measured stable, see tests/dynamics.rs).
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

/// Velocity Verlet: owns the per-step buffers (forces, inverse masses, broken bonds).
pub struct VelocityVerlet {
    pub(super) f: Vec<Vec3>,
    inv_mass: Vec<f64>,
    pub(super) dt: f64,
    guard: f64,
    broken: Vec<(u32, u32)>,
    estimate: Option<FrequencyEstimate>,
}

/// The explicit solver: a force model stepped by velocity Verlet.
pub type Explicit<M> = Simulation<M, VelocityVerlet>;

impl<M: ForceModel> Simulation<M, VelocityVerlet> {
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
        check_lengths(n, rest, &loads)?;
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
        let state = State::at_rest(rest);
        let mut f = vec![[0.0; 3]; n];
        if !model.forces_vanish_at(&state.positions) {
            model.update_forces(&state.positions, &mut f);
        }
        Ok(Simulation {
            model,
            state,
            loads,
            integrator: VelocityVerlet {
                f,
                inv_mass,
                dt,
                guard: config.guard_fraction * horizon,
                broken: Vec::new(),
                estimate,
            },
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
    pub fn step_with<F>(&mut self, external: F) -> Result<&[(u32, u32)], PhysicsError>
    where
        F: FnMut(External<'_>),
    {
        self.step_in(&mut ForcesOnly(external))
    }

    /// The stable-step estimate, when `dt` was `Auto`.
    pub fn estimate(&self) -> Option<FrequencyEstimate> {
        self.integrator.estimate
    }

    /// Sets positions (m) and recomputes forces (history advances as in a step).
    pub fn set_positions(&mut self, y: &[Vec3]) {
        self.state.positions.copy_from_slice(y);
        self.model
            .update_forces(&self.state.positions, &mut self.integrator.f);
    }

    /// Internal forces at the current positions (N).
    pub fn forces(&self) -> &[Vec3] {
        &self.integrator.f
    }
}

impl<M: ForceModel> Integrator<M> for VelocityVerlet {
    fn advance(
        &mut self,
        model: &mut M,
        state: &mut State,
        loads: &Loads,
        env: &mut dyn Environment,
    ) -> Result<(), PhysicsError> {
        let t = state.time;
        self.kick(state, loads, t);
        if loads.has_rotation() {
            self.drift::<true>(state, loads)?;
        } else {
            self.drift::<false>(state, loads)?;
        }
        self.broken.clear();
        model.break_bonds_and_update_forces(&state.positions, &mut self.broken, &mut self.f);
        env.add_forces(External {
            dt: self.dt,
            positions: &state.positions,
            velocities: &state.velocities,
            masses: model.masses(),
            forces: &mut self.f,
        });
        self.kick(state, loads, t + self.dt);
        state.time += self.dt;
        state.steps += 1;
        Ok(())
    }

    fn broken(&self) -> &[(u32, u32)] {
        &self.broken
    }

    fn dt(&self) -> f64 {
        self.dt
    }

    fn kind(&self) -> crate::integrate::IntegratorKind {
        crate::integrate::IntegratorKind::Explicit
    }

    fn save_state(&self, w: &mut Writer) {
        w.tag("velocity verlet");
        w.f64(self.dt);
        w.array(&self.f);
    }

    fn restore_state(&mut self, r: &mut Reader, _: &M, _: &Loads) -> Result<(), PhysicsError> {
        r.tag("velocity verlet")?;
        restore_dt(r, self.dt)?;
        r.array_into("forces", &mut self.f)?;
        Ok(())
    }
}

impl VelocityVerlet {
    /// Half-step velocity update with forces, gravity, damping and anchors (their velocity at
    /// time `t`).
    fn kick(&self, state: &mut State, loads: &Loads, t: f64) {
        let half = 0.5 * self.dt;
        let decay = (-loads.damping * half).exp();
        let (f, inv_mass) = (&self.f, &self.inv_mass);
        let g = loads.gravity;
        let y = &state.positions;
        state
            .velocities
            .par_chunks_mut(crate::par::GRAIN)
            .enumerate()
            .for_each(|(c, chunk)| {
                for (o, v) in chunk.iter_mut().enumerate() {
                    let i = c * crate::par::GRAIN + o;
                    if let Some(motion) = loads.motion(i) {
                        *v = motion.velocity_at(y[i], t);
                        continue;
                    }
                    for d in 0..3 {
                        v[d] = (v[d] + half * (f[i][d] * inv_mass[i] + g[d])) * decay;
                    }
                }
            });
    }

    /// Position update with the blow-up guard; with `ROTATION`, anchored particles of a turning
    /// motion move along their exact circle instead of the tangent.
    fn drift<const ROTATION: bool>(
        &self,
        state: &mut State,
        loads: &Loads,
    ) -> Result<(), PhysicsError> {
        let dt = self.dt;
        let t = state.time;
        let v = &state.velocities;
        let (worst, at) = state
            .positions
            .par_chunks_mut(crate::par::GRAIN)
            .enumerate()
            .map(|(c, chunk)| {
                let mut worst = (0.0f64, usize::MAX);
                for (o, y) in chunk.iter_mut().enumerate() {
                    let i = c * crate::par::GRAIN + o;
                    let vi = v[i];
                    if ROTATION {
                        if let Some(m) = loads.motion(i).filter(|m| m.rotates()) {
                            let next = m.advance(*y, t, dt);
                            let s = norm(sub(next, *y));
                            *y = next;
                            if s > worst.0 || !s.is_finite() {
                                worst = (if s.is_finite() { s } else { f64::INFINITY }, i);
                            }
                            continue;
                        }
                    }
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
                step: state.steps,
                particle: at,
                displacement: worst,
                limit: self.guard,
            });
        }
        Ok(())
    }
}
