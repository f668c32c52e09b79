//! The implicit quasi-Newton step (docs/model.md section 5; Liu, Bouaziz and Kavan's quasi-Newton
//! method, as Xu et al. use it): each step minimises
//! `Phi(q) = |q - q*|^2_M / (2 dt^2) + c |q - q_n|^2_M / (2 dt) + E(q) + P_env(q, c)`,
//! `q* = q_n + dt v_n + dt^2 g`, over the free particles' end positions `q` (anchored ones sit
//! on their prescribed motion, eliminated from the unknowns) and the environment's own bodies
//! `c` (dynamic balls). The search direction is L-BFGS with the constant matrix
//! `S = M / dt^2 + c M / dt + L` as its initial inverse Hessian (with no history it is plain
//! `-S^-1 grad`); a backtracking line search halves the step until `Phi` decreases (Armijo);
//! the iteration stops when the decrease still to come (estimated from the next direction's
//! prediction and the rate at which the decreases shrink) is below `tolerance` of the whole
//! decrease of the step, or at the iteration cap, which is counted. `v_{n+1} = (q_{n+1}
//! - q_n) / dt`. The environment's stiffness at the start of the step (contact: `k`, damping
//! and friction curvature of each touching pair, isotropic, an upper bound of the pair's own
//! Hessian) joins `S`'s diagonal; `S` is refactored when it changed by more than a factor of
//! two for some particle. Bonds break after the step; `S` is kept (a stiffer `S` still gives descent
//! directions) until the share of bonds broken since it was factored passes `refactor_share`.

use std::time::Instant;

use perifrac_checkpoint::{Reader, Writer};

use super::simulation::{check_lengths, restore_dt, Integrator, Simulation, SolverStats};
use super::step_matrix::{StepMatrix, HELD};
use crate::environment::{Environment, ImplicitEnvironment};
use crate::error::PhysicsError;
use crate::loads::Loads;
use crate::material::QuasiNewtonModel;
use crate::math::{norm, sub, Vec3};
use crate::state::State;

/// Settings of the implicit step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImplicitConfig {
    /// The step (s).
    pub dt: f64,
    /// Iterations per step at most; a step that reaches it is accepted and counted in
    /// [`SolverStats::capped_steps`].
    pub max_iterations: usize,
    /// Stop when the decrease of `Phi` still to come is below this share of the step's whole
    /// decrease (the paper's relative error; 1e-4 is its working value).
    pub tolerance: f64,
    /// L-BFGS pairs kept (Liu et al. use 5); 0 is the plain constant-matrix iteration.
    pub history: usize,
    /// Refactor `S` when bonds broken since the last factorisation exceed this share of the
    /// bonds intact then.
    pub refactor_share: f64,
    /// A step that moves a particle further than this (m), or to a non-finite position, is an
    /// error; infinity disables the distance test.
    pub guard_distance: f64,
}

impl ImplicitConfig {
    /// The defaults with step `dt` (s): 100 iterations, tolerance 1e-4, 10 pairs, refactor past
    /// 2% broken, no distance guard.
    pub fn with_dt(dt: f64) -> Self {
        ImplicitConfig {
            dt,
            max_iterations: 100,
            tolerance: 1e-4,
            history: 10,
            refactor_share: 0.02,
            guard_distance: f64::INFINITY,
        }
    }

    fn check(&self) -> Result<(), PhysicsError> {
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return Err(PhysicsError::BadTimeStep(self.dt));
        }
        if self.max_iterations == 0 {
            return Err(PhysicsError::BadSetting(
                "max_iterations must be at least 1".into(),
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(PhysicsError::BadSetting(format!(
                "implicit tolerance {} must be in (0, 1)",
                self.tolerance
            )));
        }
        if self.refactor_share.is_nan() || self.refactor_share < 0.0 {
            return Err(PhysicsError::BadSetting(format!(
                "refactor share {} must be >= 0",
                self.refactor_share
            )));
        }
        if self.guard_distance.is_nan() || self.guard_distance <= 0.0 {
            return Err(PhysicsError::BadSetting(format!(
                "guard distance {} m must be positive (infinity: off)",
                self.guard_distance
            )));
        }
        Ok(())
    }
}

/// What the last step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepInfo {
    /// Iterations taken.
    pub iterations: usize,
    /// `Phi` at the start and at the end of the step (J).
    pub phi_start: f64,
    /// `Phi` at the end (J).
    pub phi_end: f64,
    /// Whether the iteration cap ended it.
    pub capped: bool,
}

/// The unknowns: particle end positions and the environment's body positions.
#[derive(Debug, Clone, Default)]
struct Dofs {
    q: Vec<Vec3>,
    c: Vec<Vec3>,
}

impl Dofs {
    fn zeros(n: usize, nb: usize) -> Self {
        Dofs {
            q: vec![[0.0; 3]; n],
            c: vec![[0.0; 3]; nb],
        }
    }
    fn resize(&mut self, n: usize, nb: usize) {
        self.q.resize(n, [0.0; 3]);
        self.c.resize(nb, [0.0; 3]);
    }
    fn flat(&self) -> impl Iterator<Item = &f64> {
        self.q.as_flattened().iter().chain(self.c.as_flattened())
    }
    fn flat_mut(&mut self) -> impl Iterator<Item = &mut f64> {
        self.q
            .as_flattened_mut()
            .iter_mut()
            .chain(self.c.as_flattened_mut())
    }
    fn dot(&self, o: &Dofs) -> f64 {
        self.flat().zip(o.flat()).map(|(a, b)| a * b).sum()
    }
    /// `self += s o`.
    fn axpy(&mut self, s: f64, o: &Dofs) {
        for (a, b) in self.flat_mut().zip(o.flat()) {
            *a += s * b;
        }
    }
    fn copy_from(&mut self, o: &Dofs) {
        self.q.copy_from_slice(&o.q);
        self.c.copy_from_slice(&o.c);
    }
    fn scale(&mut self, s: f64) {
        for a in self.flat_mut() {
            *a *= s;
        }
    }
}

/// The quasi-Newton integrator: the factored step matrix, the L-BFGS history and every buffer.
pub struct QuasiNewton {
    config: ImplicitConfig,
    matrix: StepMatrix,
    /// `k_ij` per directed bond (N/m) and `k_ij + k_ji` as assembled into `S`.
    bond_k: Vec<f64>,
    pair: Vec<f64>,
    reverse: Vec<u32>,
    /// Intact directed bonds when `S` was last factored.
    intact_at_factor: usize,
    /// The environment's curvature per particle (N/m) at this step's start, and as factored
    /// into `S`.
    env_curvature: Vec<f64>,
    factored_curvature: Vec<f64>,
    held: Vec<bool>,
    // per-step buffers
    start: Vec<Vec3>,
    target: Vec<Vec3>,
    end_held: Vec<Vec3>,
    forces: Vec<Vec3>,
    x: Dofs,
    g: Dofs,
    d: Dofs,
    trial: Dofs,
    g_trial: Dofs,
    body_diag: Vec<f64>,
    s_hist: Vec<Dofs>,
    y_hist: Vec<Dofs>,
    rho: Vec<f64>,
    alpha: Vec<f64>,
    broken: Vec<(u32, u32)>,
    stats: SolverStats,
    last: StepInfo,
    /// `Phi` after each iteration of the last step, the start first.
    trace: Vec<f64>,
}

/// The implicit solver: a force model stepped by [`QuasiNewton`].
pub type Implicit<M> = Simulation<M, QuasiNewton>;

impl<M: QuasiNewtonModel> Simulation<M, QuasiNewton> {
    /// Starts at rest at `rest` (m) with `loads`; factors the step matrix once.
    pub fn new(
        mut model: M,
        rest: &[Vec3],
        loads: Loads,
        config: ImplicitConfig,
    ) -> Result<Self, PhysicsError> {
        config.check()?;
        let n = model.num_particles();
        check_lengths(n, rest, &loads)?;
        let family = model.discretization().family();
        let nb = family.num_bonds();
        let held: Vec<bool> = (0..n).map(|i| loads.motion(i).is_some()).collect();
        let matrix = StepMatrix::new(family, &held)?;
        let reverse = family.reverse_index();
        let state = State::at_rest(rest);
        let mut forces = vec![[0.0; 3]; n];
        model.update_forces(&state.positions, &mut forces);
        let mut integrator = QuasiNewton {
            config,
            matrix,
            bond_k: vec![0.0; nb],
            pair: vec![0.0; nb],
            reverse,
            intact_at_factor: 0,
            env_curvature: vec![0.0; n],
            factored_curvature: vec![0.0; n],
            held,
            start: vec![[0.0; 3]; n],
            target: vec![[0.0; 3]; n],
            end_held: vec![[0.0; 3]; n],
            forces,
            x: Dofs::zeros(n, 0),
            g: Dofs::zeros(n, 0),
            d: Dofs::zeros(n, 0),
            trial: Dofs::zeros(n, 0),
            g_trial: Dofs::zeros(n, 0),
            body_diag: Vec::new(),
            s_hist: vec![Dofs::zeros(n, 0); config.history],
            y_hist: vec![Dofs::zeros(n, 0); config.history],
            rho: vec![0.0; config.history],
            alpha: vec![0.0; config.history],
            broken: Vec::new(),
            stats: SolverStats::default(),
            last: StepInfo::default(),
            trace: Vec::with_capacity(config.max_iterations + 1),
        };
        integrator.refactor(&model, &loads)?;
        Ok(Simulation {
            model,
            state,
            loads,
            integrator,
        })
    }

    /// What the last step did.
    pub fn last_step(&self) -> StepInfo {
        self.integrator.last
    }

    /// `Phi` (J) at the start of the last step and after each of its iterations.
    pub fn last_trace(&self) -> &[f64] {
        &self.integrator.trace
    }

    /// Advances one step with no environment.
    pub fn step(&mut self) -> Result<&[(u32, u32)], PhysicsError> {
        self.step_in(&mut crate::environment::NoEnvironment)
    }
}

impl QuasiNewton {
    /// Rebuilds the free set if the anchors changed, reassembles `S` from the model's current
    /// bond stiffness and factors it.
    fn refactor<M: QuasiNewtonModel>(
        &mut self,
        model: &M,
        loads: &Loads,
    ) -> Result<(), PhysicsError> {
        model.bond_stiffness(&mut self.bond_k);
        self.intact_at_factor = self.bond_k.iter().filter(|&&k| k != 0.0).count();
        self.factored_curvature.copy_from_slice(&self.env_curvature);
        let seconds = self.factor(model, loads)?;
        self.stats.factorizations += 1;
        self.stats.factor_seconds += seconds;
        self.stats.factor_bytes = self.matrix.bytes();
        Ok(())
    }

    /// Assembles `S` from `bond_k` and `factored_curvature` for the free set `held` and
    /// factors it; returns the seconds it took.
    fn factor<M: QuasiNewtonModel>(
        &mut self,
        model: &M,
        loads: &Loads,
    ) -> Result<f64, PhysicsError> {
        let family = model.discretization().family();
        if !self.matrix.matches(&self.held) {
            self.matrix = StepMatrix::new(family, &self.held)?;
        }
        for k in 0..self.bond_k.len() {
            self.pair[k] = self.bond_k[k] + self.bond_k[self.reverse[k] as usize];
        }
        let dt = self.config.dt;
        let masses = model.masses();
        let damping = loads.damping;
        let env = &self.factored_curvature;
        self.matrix.factor(
            family,
            |i| masses[i] / (dt * dt) + damping * masses[i] / dt + env[i],
            &self.pair,
        )
    }

    /// `Phi` at `x` with its gradient in `g` (free and body components; zero on held ones).
    #[allow(clippy::needless_range_loop)]
    fn phi<M: QuasiNewtonModel>(
        &mut self,
        model: &mut M,
        env: &mut dyn ImplicitEnvironment,
        loads: &Loads,
        which: Which,
    ) -> f64 {
        self.stats.evaluations += 1;
        let (x, g) = match which {
            Which::Current => (&self.x, &mut self.g),
            Which::Trial => (&self.trial, &mut self.g_trial),
        };
        let dt = self.config.dt;
        let elastic = model.energy_and_forces(&x.q, &mut self.forces);
        let masses = model.masses();
        let (inertia, damp) = (1.0 / (dt * dt), loads.damping / dt);
        let mut kinetic = 0.0;
        for i in 0..x.q.len() {
            if self.held[i] {
                g.q[i] = [0.0; 3];
                continue;
            }
            let m = masses[i];
            let (a, b) = (sub(x.q[i], self.target[i]), sub(x.q[i], self.start[i]));
            kinetic += 0.5
                * m
                * (inertia * (a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
                    + damp * (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]));
            for d in 0..3 {
                g.q[i][d] = m * (inertia * a[d] + damp * b[d]) - self.forces[i][d];
            }
        }
        g.c.iter_mut().for_each(|v| *v = [0.0; 3]);
        let outside = env.potential(&x.q, &x.c, Some((&mut g.q, &mut g.c)));
        for (i, gq) in g.q.iter_mut().enumerate() {
            if self.held[i] {
                *gq = [0.0; 3];
            }
        }
        kinetic + elastic + outside
    }

    /// `d = -H g` by the L-BFGS two-loop recursion with `S^-1` (and the bodies' diagonal) as
    /// the initial inverse Hessian over the `count` newest pairs ending at `head`.
    fn direction(&mut self, count: usize, head: usize) {
        let m = self.config.history;
        self.d.copy_from(&self.g);
        for t in 0..count {
            let k = (head + m - t) % m;
            let a = self.rho[k] * self.s_hist[k].dot(&self.d);
            self.alpha[k] = a;
            self.d.axpy(-a, &self.y_hist[k]);
        }
        self.precondition();
        for t in (0..count).rev() {
            let k = (head + m - t) % m;
            let b = self.rho[k] * self.y_hist[k].dot(&self.d);
            self.d.axpy(self.alpha[k] - b, &self.s_hist[k]);
        }
        self.d.scale(-1.0);
    }

    /// `d <- P^-1 d`: `S_1^-1` on the three coordinates of the free particles, the bodies'
    /// diagonal on theirs.
    fn precondition(&mut self) {
        let nf = self.matrix.len();
        for (fi, &p) in self.matrix.particles.iter().enumerate() {
            let v = self.d.q[p as usize];
            for (c, vc) in v.iter().enumerate() {
                self.matrix.rhs[c * nf + fi] = *vc;
            }
        }
        let t = Instant::now();
        self.matrix.solve();
        self.stats.solves += 1;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        for (i, q) in self.d.q.iter_mut().enumerate() {
            let fi = self.matrix.free[i];
            *q = if fi == HELD {
                [0.0; 3]
            } else {
                let f = fi as usize;
                [
                    self.matrix.rhs[f],
                    self.matrix.rhs[nf + f],
                    self.matrix.rhs[2 * nf + f],
                ]
            };
        }
        for (c, &w) in self.d.c.iter_mut().zip(&self.body_diag) {
            *c = [c[0] / w, c[1] / w, c[2] / w];
        }
    }
}

/// Which iterate [`QuasiNewton::phi`] evaluates.
#[derive(Clone, Copy)]
enum Which {
    Current,
    Trial,
}

/// An estimate of how much `Phi` can still fall in this step (J): the quadratic model's
/// prediction `predicted` for the next direction, or, when the last decreases shrink at a rate
/// `r` (the geometric mean of the ratios over the last three, `(d_k / d_(k-3))^(1/3)`, at most
/// 0.99), the tail `d_k r / (1 - r)` of that series if larger; when they do not shrink, the
/// last decrease itself. The prediction alone underestimates the remaining decrease by `1 - r`
/// when the iteration converges slowly (bending a long bar with a matrix that resists
/// rotation), and would stop it early; one ratio alone is too noisy for L-BFGS's uneven steps.
fn remaining_decrease(predicted: f64, decreases: &[f64; 4]) -> f64 {
    let [older, _, _, last] = *decreases;
    let rate = (last / older).cbrt();
    if !rate.is_finite() || rate <= 0.0 {
        return predicted;
    }
    let tail = if rate < 1.0 {
        let r = rate.min(0.99);
        last * r / (1.0 - r)
    } else {
        last
    };
    predicted.max(tail)
}

/// Line-search halvings before a step is declared stalled.
const MAX_HALVINGS: usize = 40;

impl<M: QuasiNewtonModel> Integrator<M> for QuasiNewton {
    fn advance(
        &mut self,
        model: &mut M,
        state: &mut State,
        loads: &Loads,
        env: &mut dyn Environment,
    ) -> Result<(), PhysicsError> {
        let Some(env) = env.implicit() else {
            return Err(PhysicsError::Unsupported(
                "the environment cannot act as a potential: the implicit step needs one".into(),
            ));
        };
        let dt = self.config.dt;
        let n = state.len();
        let t = state.time;
        // anchors: the free set follows releases
        for i in 0..n {
            self.held[i] = loads.motion(i).is_some();
        }
        if !self.matrix.matches(&self.held) {
            self.refactor(model, loads)?;
        }
        env.begin(dt, &state.positions, &state.velocities, model.masses())?;
        // the environment's stiffness (contact) joins S's diagonal; refactor when it changed
        // by more than a factor of two somewhere (a contact made or lost, say)
        env.particle_curvature(&state.positions, &mut self.env_curvature);
        let changed = self
            .env_curvature
            .iter()
            .zip(&self.factored_curvature)
            .any(|(&now, &then)| now > 2.0 * then || then > 2.0 * now);
        if changed {
            self.refactor(model, loads)?;
        }
        let nb = env.bodies();
        for v in [
            &mut self.x,
            &mut self.g,
            &mut self.d,
            &mut self.trial,
            &mut self.g_trial,
        ] {
            v.resize(n, nb);
        }
        for h in self.s_hist.iter_mut().chain(self.y_hist.iter_mut()) {
            h.resize(n, nb);
        }
        self.body_diag.resize(nb, 0.0);
        env.body_curvature(&mut self.body_diag);
        env.body_guess(&mut self.x.c);
        let g = loads.gravity;
        for i in 0..n {
            let (y, v) = (state.positions[i], state.velocities[i]);
            self.start[i] = y;
            match loads.motion(i) {
                Some(m) => {
                    self.end_held[i] = m.advance(y, t, dt);
                    self.x.q[i] = self.end_held[i];
                    self.target[i] = self.end_held[i];
                }
                None => {
                    for d in 0..3 {
                        self.target[i][d] = y[d] + dt * v[d] + dt * dt * g[d];
                        self.x.q[i][d] = y[d] + dt * v[d];
                    }
                }
            }
        }
        // start from the better of the constant-velocity guess and the inertial target
        // `q*`: under gravity with a long step `q*` is a free fall of `g dt^2` (2.5 m at
        // 0.5 s), whose enormous `Phi` would make any relative tolerance meaningless
        let mut phi = self.phi(model, env, loads, Which::Current);
        self.trial.copy_from(&self.x);
        for i in 0..n {
            if loads.motion(i).is_none() {
                self.trial.q[i] = self.target[i];
            }
        }
        let at_target = self.phi(model, env, loads, Which::Trial);
        if at_target < phi {
            std::mem::swap(&mut self.x, &mut self.trial);
            std::mem::swap(&mut self.g, &mut self.g_trial);
            phi = at_target;
        }
        if !phi.is_finite() || !self.g.flat().all(|v| v.is_finite()) {
            return Err(PhysicsError::NotFinite {
                step: state.steps,
                phi,
            });
        }
        let phi_start = phi;
        let kinetic: f64 = model
            .masses()
            .iter()
            .zip(&state.velocities)
            .map(|(&m, v)| 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
            .sum();
        self.trace.clear();
        self.trace.push(phi);
        let (mut count, mut head) = (0usize, 0usize);
        let mut iterations = 0;
        let mut capped = true;
        // the last four decreases of Phi, oldest first, for the rate of convergence
        let mut decreases = [f64::NAN; 4];
        while iterations < self.config.max_iterations {
            self.direction(count, head);
            let mut slope = self.g.dot(&self.d);
            if slope.is_nan() || slope >= 0.0 {
                // not a descent direction (a pair with bad curvature): restart from S alone
                count = 0;
                self.direction(0, head);
                slope = self.g.dot(&self.d);
            }
            let predicted = -0.5 * slope;
            let remaining = remaining_decrease(predicted, &decreases);
            if remaining <= self.config.tolerance * (phi_start - phi + remaining) {
                capped = false;
                break;
            }
            iterations += 1;
            let mut step = 1.0;
            let mut accepted = None;
            for _ in 0..MAX_HALVINGS {
                self.trial.copy_from(&self.x);
                self.trial.axpy(step, &self.d);
                let value = self.phi(model, env, loads, Which::Trial);
                if value.is_finite() && value <= phi + 1e-4 * step * slope {
                    accepted = Some(value);
                    break;
                }
                step *= 0.5;
            }
            let Some(value) = accepted else {
                // at the rounding floor of Phi the decrease cannot be seen: converged. The
                // floor is relative to the energies Phi is made of, the kinetic one included:
                // a body coasting without forces starts at Phi ~ 0 (its inertial target),
                // where nothing is left to decrease but rounding
                let floor = phi.abs().max(phi_start.abs()).max(kinetic);
                if predicted <= 1e-12 * floor {
                    capped = false;
                    break;
                }
                return Err(PhysicsError::Stalled {
                    step: state.steps,
                    iteration: iterations,
                    halvings: MAX_HALVINGS,
                    predicted,
                    phi,
                });
            };
            // L-BFGS pair s = x_new - x, y = g_new - g
            if self.config.history > 0 {
                let m = self.config.history;
                let k = if count == 0 { head } else { (head + 1) % m };
                let (s, y) = (&mut self.s_hist[k], &mut self.y_hist[k]);
                s.copy_from(&self.trial);
                s.axpy(-1.0, &self.x);
                y.copy_from(&self.g_trial);
                y.axpy(-1.0, &self.g);
                let sy = s.dot(y);
                if sy > 1e-12 * s.dot(s).sqrt() * y.dot(y).sqrt() {
                    self.rho[k] = 1.0 / sy;
                    head = k;
                    count = (count + 1).min(m);
                } else if count == m {
                    // the slot written was the oldest pair still in use
                    count = m - 1;
                }
            }
            std::mem::swap(&mut self.x, &mut self.trial);
            std::mem::swap(&mut self.g, &mut self.g_trial);
            decreases.rotate_left(1);
            decreases[3] = phi - value;
            phi = value;
            self.trace.push(phi);
        }
        self.stats.iterations += iterations as u64;
        if capped {
            self.stats.capped_steps += 1;
        }
        self.last = StepInfo {
            iterations,
            phi_start,
            phi_end: phi,
            capped,
        };
        // accept: velocities, the guard, the state
        let mut worst = (0.0f64, 0usize);
        for i in 0..n {
            let u = sub(self.x.q[i], self.start[i]);
            let dist = norm(u);
            if !dist.is_finite() || dist > worst.0 {
                worst = (
                    if dist.is_finite() {
                        dist
                    } else {
                        f64::INFINITY
                    },
                    i,
                );
            }
        }
        if worst.0.is_infinite() || worst.0 > self.config.guard_distance {
            return Err(PhysicsError::Unstable {
                step: state.steps,
                particle: worst.1,
                displacement: worst.0,
                limit: self.config.guard_distance,
            });
        }
        for i in 0..n {
            let u = sub(self.x.q[i], self.start[i]);
            state.velocities[i] = [u[0] / dt, u[1] / dt, u[2] / dt];
        }
        state.positions.copy_from_slice(&self.x.q);
        env.end(&self.x.q, &self.x.c, &state.velocities);
        self.broken.clear();
        model.break_bonds(&state.positions, &mut self.broken);
        model.update_forces(&state.positions, &mut self.forces);
        if !self.broken.is_empty() {
            let intact = model
                .damage()
                .map_or(self.intact_at_factor, |d| d.intact_bonds());
            let lost = self.intact_at_factor.saturating_sub(intact);
            if lost as f64 > self.config.refactor_share * self.intact_at_factor as f64 {
                self.refactor(model, loads)?;
            }
        }
        state.time += dt;
        state.steps += 1;
        Ok(())
    }

    fn broken(&self) -> &[(u32, u32)] {
        &self.broken
    }

    fn dt(&self) -> f64 {
        self.config.dt
    }

    fn kind(&self) -> crate::integrate::IntegratorKind {
        crate::integrate::IntegratorKind::Implicit
    }

    fn stats(&self) -> SolverStats {
        self.stats
    }

    fn save_state(&self, w: &mut Writer) {
        w.tag("quasi-newton");
        w.f64(self.config.dt);
        // what S was assembled from when last factored, to factor the same matrix again
        w.array(&self.bond_k);
        w.array(&self.factored_curvature);
        w.array(&self.env_curvature);
        w.usize(self.intact_at_factor);
        let s = &self.stats;
        for v in [
            s.iterations,
            s.capped_steps,
            s.evaluations,
            s.factorizations,
            s.solves,
        ] {
            w.u64(v);
        }
        w.f64(s.factor_seconds);
        w.f64(s.solve_seconds);
        w.usize(s.factor_bytes);
        let l = &self.last;
        w.usize(l.iterations);
        w.f64(l.phi_start);
        w.f64(l.phi_end);
        w.bool(l.capped);
        w.array(&self.trace);
    }

    fn restore_state(
        &mut self,
        r: &mut Reader,
        model: &M,
        loads: &Loads,
    ) -> Result<(), PhysicsError> {
        r.tag("quasi-newton")?;
        restore_dt(r, self.config.dt)?;
        r.array_into("bond stiffness", &mut self.bond_k)?;
        r.array_into("factored curvature", &mut self.factored_curvature)?;
        r.array_into("contact curvature", &mut self.env_curvature)?;
        self.intact_at_factor = r.usize("intact bonds when factored")?;
        let mut s = SolverStats::default();
        for v in [
            &mut s.iterations,
            &mut s.capped_steps,
            &mut s.evaluations,
            &mut s.factorizations,
            &mut s.solves,
        ] {
            *v = r.u64("counters")?;
        }
        s.factor_seconds = r.f64("factor seconds")?;
        s.solve_seconds = r.f64("solve seconds")?;
        s.factor_bytes = r.usize("factor bytes")?;
        self.last = StepInfo {
            iterations: r.usize("last iterations")?,
            phi_start: r.f64("last phi")?,
            phi_end: r.f64("last phi")?,
            capped: r.bool("last capped")?,
        };
        r.array_vec("trace", &mut self.trace)?;
        for (i, h) in self.held.iter_mut().enumerate() {
            *h = loads.motion(i).is_some();
        }
        // the factorisation redone here is the one the checkpoint's run held, not a new one
        self.factor(model, loads)?;
        self.stats = s;
        Ok(())
    }
}

#[cfg(test)]
#[path = "implicit_tests.rs"]
mod tests;
