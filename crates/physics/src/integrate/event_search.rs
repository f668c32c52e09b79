//! Explicit steps with an event search (docs/model.md section 6, after the thin-shell paper's time
//! stepping): each step of length `dt` is covered by sub-steps of `dt 2^-k`; a trial sub-step
//! is undone whole (state, model history, forces and the environment's bodies, from an
//! in-memory snapshot) and retried at `k + 1` when the largest force grew by more than a
//! factor or a bond it broke went past its threshold by more than a tolerance; after an
//! accepted sub-step `k` falls by one. At `k = levels` a sub-step is always accepted.
//!
//! The outer step keeps its length, so frames, step counts and checkpoints are those of the
//! plain explicit step; the sub-steps are counted in [`SolverStats::substeps`] and
//! [`SolverStats::rejected`].

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use super::explicit::{ExplicitConfig, VelocityVerlet};
use super::simulation::{Integrator, Simulation, SolverStats};
use crate::environment::Environment;
use crate::error::PhysicsError;
use crate::loads::Loads;
use crate::material::ForceModel;
use crate::math::Vec3;
use crate::state::State;

/// The event search's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventSearchConfig {
    /// Finest level `k_max`: sub-steps go down to `dt 2^-levels` (at most 20).
    pub levels: u32,
    /// A trial sub-step is rejected when the largest force (N) after it exceeds this factor
    /// times the largest before it (> 1; the paper uses 1.1).
    pub force_growth: f64,
    /// ... or when a bond it broke was stretched past its threshold by more than this share
    /// (>= 0; infinity: bonds never reject a sub-step).
    pub overshoot: f64,
    /// Forces below this share of the largest force seen so far are too small to reject a
    /// sub-step for growing (in [0, 1)).
    pub force_floor: f64,
}

impl Default for EventSearchConfig {
    fn default() -> Self {
        EventSearchConfig {
            levels: 4,
            force_growth: 1.1,
            overshoot: 0.1,
            force_floor: 1e-3,
        }
    }
}

impl EventSearchConfig {
    /// Refuses settings out of range.
    pub fn check(&self) -> Result<(), PhysicsError> {
        let bad = |m: String| Err(PhysicsError::BadSetting(m));
        if self.levels > MAX_LEVELS {
            return bad(format!(
                "event search levels {} must be at most {MAX_LEVELS}",
                self.levels
            ));
        }
        if self.force_growth.is_nan() || self.force_growth <= 1.0 {
            return bad(format!(
                "event search force growth {} must be above 1",
                self.force_growth
            ));
        }
        if self.overshoot.is_nan() || self.overshoot < 0.0 {
            return bad(format!(
                "event search overshoot {} must be >= 0",
                self.overshoot
            ));
        }
        if !(0.0..1.0).contains(&self.force_floor) {
            return bad(format!(
                "event search force floor {} must be in [0, 1)",
                self.force_floor
            ));
        }
        Ok(())
    }
}

/// Finest level allowed: a step of `2^20` sub-steps is already a million force evaluations.
pub const MAX_LEVELS: u32 = 20;

/// Velocity Verlet under the event search.
pub struct EventSearch {
    inner: VelocityVerlet,
    config: EventSearchConfig,
    /// The outer step (s).
    dt: f64,
    /// The level of the next trial sub-step.
    k: u32,
    /// Largest force seen in an accepted sub-step so far (N).
    peak: f64,
    /// The snapshot a rejected trial returns to, and the environment's; reused every step.
    snapshot: Writer,
    env_snapshot: Writer,
    broken: Vec<(u32, u32)>,
    stats: SolverStats,
}

/// The explicit solver with the event search: a force model stepped by [`EventSearch`].
pub type Searched<M> = Simulation<M, EventSearch>;

impl<M: ForceModel> Simulation<M, EventSearch> {
    /// As [`crate::Explicit::new`] (the step from `explicit`), with the event search `search`.
    pub fn new(
        model: M,
        rest: &[Vec3],
        horizon: f64,
        loads: Loads,
        explicit: ExplicitConfig,
        search: EventSearchConfig,
    ) -> Result<Self, PhysicsError> {
        search.check()?;
        let Simulation {
            model,
            state,
            loads,
            integrator,
        } = crate::Explicit::new(model, rest, horizon, loads, explicit)?;
        let dt = integrator.dt;
        Ok(Simulation {
            model,
            state,
            loads,
            integrator: EventSearch {
                inner: integrator,
                config: search,
                dt,
                k: 0,
                peak: 0.0,
                snapshot: Writer::new(),
                env_snapshot: Writer::new(),
                broken: Vec::new(),
                stats: SolverStats::default(),
            },
        })
    }
}

/// Largest force magnitude (N).
fn largest(f: &[Vec3]) -> f64 {
    f.iter()
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .fold(0.0, f64::max)
}

impl EventSearch {
    /// The level of the next trial sub-step.
    pub fn level(&self) -> u32 {
        self.k
    }
}

impl<M: ForceModel> Integrator<M> for EventSearch {
    fn advance(
        &mut self,
        model: &mut M,
        state: &mut State,
        loads: &Loads,
        env: &mut dyn Environment,
    ) -> Result<(), PhysicsError> {
        let levels = self.config.levels;
        let (t0, steps0) = (state.time, state.steps);
        // time in units of the finest sub-step, so that sub-steps add up to dt exactly
        let full = 1u64 << levels;
        let mut done = 0u64;
        self.broken.clear();
        // the largest force at the start of the next trial: an undone trial restores the forces
        // it started from, an accepted one leaves its own
        let mut before = largest(&self.inner.f);
        while done < full {
            let units = (full >> self.k).min(full - done);
            let trial = self.k < levels;
            if trial {
                self.snapshot.clear();
                state.save(&mut self.snapshot);
                model.save_state(&mut self.snapshot);
                self.snapshot.array(&self.inner.f);
                self.env_snapshot.clear();
                env.save(&mut self.env_snapshot);
            }
            self.inner.dt = self.dt * units as f64 / full as f64;
            state.time = t0 + self.dt * done as f64 / full as f64;
            let stepped = self.inner.advance(model, state, loads, env);
            self.inner.dt = self.dt;
            stepped?;
            let after = largest(&self.inner.f);
            let grew = after > self.config.force_growth * before
                && after > self.config.force_floor * self.peak;
            let late = model.break_overshoot() > self.config.overshoot;
            if trial && (grew || late) {
                let mut r = Reader::new(self.snapshot.bytes());
                state.restore(&mut r)?;
                model.restore_state(&mut r)?;
                r.array_into("forces", &mut self.inner.f)?;
                env.restore(&mut Reader::new(self.env_snapshot.bytes()))?;
                self.k += 1;
                self.stats.rejected += 1;
                continue;
            }
            self.broken
                .extend_from_slice(Integrator::<M>::broken(&self.inner));
            self.peak = self.peak.max(after);
            before = after;
            done += units;
            self.stats.substeps += 1;
            self.k = self.k.saturating_sub(1);
        }
        state.time = t0 + self.dt;
        state.steps = steps0 + 1;
        Ok(())
    }

    fn broken(&self) -> &[(u32, u32)] {
        &self.broken
    }

    fn dt(&self) -> f64 {
        self.dt
    }

    fn kind(&self) -> crate::integrate::IntegratorKind {
        crate::integrate::IntegratorKind::EventSearch
    }

    fn stats(&self) -> SolverStats {
        self.stats
    }

    fn save_state(&self, w: &mut Writer) {
        w.tag("event search");
        Integrator::<M>::save_state(&self.inner, w);
        w.u64(u64::from(self.k));
        w.f64(self.peak);
        w.u64(self.stats.substeps);
        w.u64(self.stats.rejected);
    }

    fn restore_state(
        &mut self,
        r: &mut Reader,
        model: &M,
        loads: &Loads,
    ) -> Result<(), PhysicsError> {
        r.tag("event search")?;
        self.inner.restore_state(r, model, loads)?;
        let k = r.u64("search level")?;
        if k > u64::from(self.config.levels) {
            return Err(CheckpointError::Invalid {
                what: "search level".into(),
                message: format!("{k} beyond the {} levels", self.config.levels),
            }
            .into());
        }
        self.k = k as u32;
        self.peak = r.f64("largest force")?;
        self.stats.substeps = r.u64("sub-steps")?;
        self.stats.rejected = r.u64("rejected sub-steps")?;
        Ok(())
    }
}
