//! A simulation: one force model, its state, its loads and the integrator that advances them.
//! [`Solver`] is the object-safe face the scene driver holds, whatever the model and integrator.

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use crate::energy;
use crate::environment::Environment;
use crate::error::PhysicsError;
use crate::loads::Loads;
use crate::material::ForceModel;
use crate::math::Vec3;
use crate::state::State;

/// Counters an integrator reports; zero where they do not apply.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolverStats {
    /// Nonlinear iterations over all steps (implicit).
    pub iterations: u64,
    /// Steps that stopped at the iteration cap before the tolerance (implicit).
    pub capped_steps: u64,
    /// Evaluations of the objective and its gradient, line-search trials included (implicit).
    pub evaluations: u64,
    /// Factorisations of the step matrix (implicit), the first one included.
    pub factorizations: u64,
    /// Wall time in factorisations (s).
    pub factor_seconds: f64,
    /// Triangular solves with the factor, one per search direction (implicit).
    pub solves: u64,
    /// Wall time in the triangular solves (s).
    pub solve_seconds: f64,
    /// Heap bytes of the factor (implicit).
    pub factor_bytes: usize,
    /// Accepted sub-steps (explicit with event search).
    pub substeps: u64,
    /// Trial sub-steps rejected and undone (explicit with event search).
    pub rejected: u64,
}

/// The integrators a [`Solver`] can step with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Velocity Verlet under the stable step.
    Explicit,
    /// Velocity Verlet sub-stepped by the event search.
    EventSearch,
    /// The quasi-Newton implicit step.
    Implicit,
}

impl IntegratorKind {
    /// Its name in reports and checkpoints.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Explicit => "explicit",
            IntegratorKind::EventSearch => "event_search",
            IntegratorKind::Implicit => "implicit",
        }
    }
}

impl std::fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// An integrator: a stage that advances a [`State`] under a force model, loads and an
/// environment by one step of its own length.
pub trait Integrator<M: ForceModel>: Send {
    /// Advances `state` by one step; the bonds broken in it are then in
    /// [`Integrator::broken`]. After an error the state is that of the failed step.
    fn advance(
        &mut self,
        model: &mut M,
        state: &mut State,
        loads: &Loads,
        env: &mut dyn Environment,
    ) -> Result<(), PhysicsError>;

    /// Bonds broken in the last step, `(i, j)` with `i < j`.
    fn broken(&self) -> &[(u32, u32)];

    /// The step (s).
    fn dt(&self) -> f64;

    /// Which integrator this is.
    fn kind(&self) -> IntegratorKind;

    /// Counters so far.
    fn stats(&self) -> SolverStats {
        SolverStats::default()
    }

    /// Writes what carries from one step to the next (the explicit step's forces, the implicit
    /// step's factored matrix inputs and counters) for a checkpoint or a snapshot.
    fn save_state(&self, w: &mut Writer);

    /// Reads what [`Integrator::save_state`] wrote, for `model` and `loads` already restored
    /// (the implicit step refactors its matrix from what was factored then).
    fn restore_state(
        &mut self,
        r: &mut Reader,
        model: &M,
        loads: &Loads,
    ) -> Result<(), PhysicsError>;
}

/// Reads a saved step length and refuses one that is not `dt` (s) to the bit.
pub(crate) fn restore_dt(r: &mut Reader, dt: f64) -> Result<(), PhysicsError> {
    let saved = r.f64("time step")?;
    if saved.to_bits() == dt.to_bits() {
        return Ok(());
    }
    Err(CheckpointError::Invalid {
        what: "time step".into(),
        message: format!("{saved:e} s in the checkpoint, {dt:e} s in this run"),
    }
    .into())
}

/// Refuses rest positions or loads that are not one per particle of `n`.
pub(crate) fn check_lengths(n: usize, rest: &[Vec3], loads: &Loads) -> Result<(), PhysicsError> {
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
    Ok(())
}

/// A force model with its state and loads, advanced by an integrator `I`.
pub struct Simulation<M: ForceModel, I: Integrator<M>> {
    pub(crate) model: M,
    pub(crate) state: State,
    pub(crate) loads: Loads,
    pub(crate) integrator: I,
}

impl<M: ForceModel, I: Integrator<M>> Simulation<M, I> {
    /// Advances one step in `env`; returns the bonds broken in it as `(i, j)`, `i < j`.
    pub fn step_in(&mut self, env: &mut dyn Environment) -> Result<&[(u32, u32)], PhysicsError> {
        let Simulation {
            model,
            state,
            loads,
            integrator,
        } = self;
        integrator.advance(model, state, loads, env)?;
        Ok(integrator.broken())
    }

    /// The state (positions, velocities, time, steps).
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The time step (s).
    pub fn dt(&self) -> f64 {
        self.integrator.dt()
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.state.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.state.steps
    }

    /// Current positions (m).
    pub fn positions(&self) -> &[Vec3] {
        &self.state.positions
    }

    /// Current velocities (m/s).
    pub fn velocities(&self) -> &[Vec3] {
        &self.state.velocities
    }

    /// Velocities to set initial conditions (m/s).
    pub fn velocities_mut(&mut self) -> &mut [Vec3] {
        &mut self.state.velocities
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
        energy::kinetic_energy(self.model.masses(), &self.state.velocities)
    }

    /// Elastic energy at the current positions (J).
    pub fn elastic_energy(&mut self) -> f64 {
        self.model.elastic_energy(&self.state.positions)
    }

    /// Writes everything a step changes (state, anchors, model history, integrator buffers
    /// that carry over) so that [`Simulation::restore`] on the same setup continues bit for
    /// bit.
    pub fn save(&self, w: &mut Writer) {
        w.tag("simulation");
        w.str(self.integrator.kind().name());
        self.state.save(w);
        self.loads.save(w);
        self.model.save_state(w);
        self.integrator.save_state(w);
    }

    /// Reads what [`Simulation::save`] wrote; refuses one of another integrator or size.
    pub fn restore(&mut self, r: &mut Reader) -> Result<(), PhysicsError> {
        r.tag("simulation")?;
        let name = r.str("integrator")?;
        if name != self.integrator.kind().name() {
            return Err(CheckpointError::Invalid {
                what: "integrator".into(),
                message: format!(
                    "the checkpoint was stepped {name}, this run {}",
                    self.integrator.kind().name()
                ),
            }
            .into());
        }
        self.state.restore(r)?;
        self.loads.restore(r)?;
        self.model.restore_state(r)?;
        self.integrator.restore_state(r, &self.model, &self.loads)
    }
}

/// Any simulation as one object: what the scene driver holds, so that it names neither the
/// model nor the integrator. One virtual call per step; the loops inside stay monomorphised.
pub trait Solver: Send {
    /// Advances one step in `env`; returns the bonds broken in it as `(i, j)`, `i < j`.
    fn step(&mut self, env: &mut dyn Environment) -> Result<&[(u32, u32)], PhysicsError>;
    /// The state (positions, velocities, time, steps).
    fn state(&self) -> &State;
    /// Velocities to set initial conditions (m/s).
    fn velocities_mut(&mut self) -> &mut [Vec3];
    /// The loads (anchors are released through it).
    fn loads_mut(&mut self) -> &mut Loads;
    /// The force model.
    fn model(&self) -> &dyn ForceModel;
    /// The force model, to probe it outside a step (energies, the damage check at chosen
    /// positions); what it changes, the next step sees.
    fn model_mut(&mut self) -> &mut dyn ForceModel;
    /// The time step (s).
    fn dt(&self) -> f64;
    /// Kinetic energy (J).
    fn kinetic_energy(&self) -> f64;
    /// Elastic energy at the current positions (J).
    fn elastic_energy(&mut self) -> f64;
    /// Which integrator steps it.
    fn integrator(&self) -> IntegratorKind;
    /// The integrator's counters.
    fn stats(&self) -> SolverStats;
    /// Writes the state for a checkpoint or a snapshot ([`Simulation::save`]).
    fn save(&self, w: &mut Writer);
    /// Restores what [`Solver::save`] wrote ([`Simulation::restore`]).
    fn restore(&mut self, r: &mut Reader) -> Result<(), PhysicsError>;

    /// Current positions (m).
    fn positions(&self) -> &[Vec3] {
        &self.state().positions
    }
    /// Current velocities (m/s).
    fn velocities(&self) -> &[Vec3] {
        &self.state().velocities
    }
    /// Simulated time (s).
    fn time(&self) -> f64 {
        self.state().time
    }
    /// Steps taken.
    fn steps(&self) -> u64 {
        self.state().steps
    }
}

impl<M: ForceModel, I: Integrator<M>> Solver for Simulation<M, I> {
    fn step(&mut self, env: &mut dyn Environment) -> Result<&[(u32, u32)], PhysicsError> {
        self.step_in(env)
    }
    fn state(&self) -> &State {
        &self.state
    }
    fn velocities_mut(&mut self) -> &mut [Vec3] {
        &mut self.state.velocities
    }
    fn loads_mut(&mut self) -> &mut Loads {
        &mut self.loads
    }
    fn model(&self) -> &dyn ForceModel {
        &self.model
    }
    fn model_mut(&mut self) -> &mut dyn ForceModel {
        &mut self.model
    }
    fn dt(&self) -> f64 {
        self.integrator.dt()
    }
    fn kinetic_energy(&self) -> f64 {
        Simulation::kinetic_energy(self)
    }
    fn elastic_energy(&mut self) -> f64 {
        Simulation::elastic_energy(self)
    }
    fn integrator(&self) -> IntegratorKind {
        self.integrator.kind()
    }
    fn stats(&self) -> SolverStats {
        self.integrator.stats()
    }
    fn save(&self, w: &mut Writer) {
        Simulation::save(self, w)
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), PhysicsError> {
        Simulation::restore(self, r)
    }
}
