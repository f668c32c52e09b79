//! Implicit Newmark stepping of a shell, the integrator the paper uses for its production runs
//! (`beta = 1/4`, `gamma = 1/2`: the average-acceleration rule, unconditionally stable and
//! without numerical damping for a linear system).
//!
//! With `a_n` the acceleration at the start, a step of `h` finds the end positions `q` of the
//! free vertices as the minimiser of the incremental potential
//!
//! `Phi(q, c) = sum_i m_i / (2 beta h^2) |q_i - x~_i|^2 + E(q) + E_self(q) + P(q, c)`,
//! `x~ = x_n + h v_n + h^2 (1/2 - beta) a_n + beta h^2 g`,
//!
//! whose stationarity is Newmark's position update with `a_{n+1} = M^-1 f(q) + g`; `E` is the
//! shell's elastic energy with the plastic state frozen over the solve, `E_self` the repulsion
//! between its own pieces and `P` the colliders' incremental contact potential
//! ([`perifrac_contact::Colliders::implicit_potential`]: penalty, lagged damping and friction,
//! and the dynamic balls `c`, which it steps by backward Euler). Held vertices move at their
//! velocity. The minimiser is L-BFGS whose initial inverse Hessian is the factored matrix
//! `M / (beta h^2) + K_gn + K_contact` (the shell's Gauss-Newton stand-in
//! ([`crate::ShellModel`]), the contact stiffness at the predictor) with a backtracking line
//! search; it stops when the largest residual force is below `tolerance` of the step's force
//! scale. Then the plastic state is return-mapped at `q` (as the explicit step does, once per
//! step), `a_{n+1}` is taken from the forces there and `v_{n+1} = v_n + h ((1 - gamma) a_n +
//! gamma a_{n+1})`.

use std::time::Instant;

use super::ShellDynamics;
use crate::block_matrix::BlockMatrix;
use crate::error::{bad_setting, ShellError};
use crate::mesh::ShellMesh;
use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_physics::math::{axpy, dot, scale, sub, Vec3};

/// Settings of the implicit Newmark step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewmarkConfig {
    /// Newmark's `beta` (in (0, 1/2]; the paper's 1/4).
    pub beta: f64,
    /// Newmark's `gamma` (in [1/2, 2 beta + 1/2]... at most 1; 1/2 has no numerical damping).
    pub gamma: f64,
    /// L-BFGS iterations per step at most; a step that reaches it is taken and counted (the
    /// event search caps its trials lower: [`crate::ShellSearch::trial_iterations`]).
    pub max_iterations: usize,
    /// Stop when the largest residual force on a free vertex is below this share of the step's
    /// force scale (the largest force at its start, or the model's force scale if larger).
    pub tolerance: f64,
    /// L-BFGS pairs kept.
    pub history: usize,
}

impl Default for NewmarkConfig {
    fn default() -> Self {
        NewmarkConfig {
            beta: 0.25,
            gamma: 0.5,
            max_iterations: 200,
            tolerance: 1e-6,
            history: 8,
        }
    }
}

impl NewmarkConfig {
    /// Refuses settings out of range (`2 beta >= gamma >= 1/2` is unconditionally stable).
    pub fn check(&self) -> Result<(), ShellError> {
        if !(self.beta > 0.0 && self.beta <= 0.5) {
            return bad_setting("Newmark beta", "in (0, 0.5]", self.beta);
        }
        if !(self.gamma >= 0.5 && self.gamma <= 2.0 * self.beta.max(0.25) && self.gamma <= 1.0) {
            return bad_setting(
                "Newmark gamma",
                "in [0.5, 2 beta] (unconditionally stable)",
                self.gamma,
            );
        }
        if self.max_iterations == 0 {
            return bad_setting("Newmark iterations", "at least 1", 0.0);
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad_setting("Newmark tolerance", "in (0, 1)", self.tolerance);
        }
        Ok(())
    }
}

/// What the implicit steps did so far.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NewmarkStats {
    /// Steps taken (trials the event search discarded included).
    pub steps: u64,
    /// L-BFGS iterations, all steps.
    pub iterations: u64,
    /// Steps that stopped at the iteration cap.
    pub capped: u64,
    /// Steps whose line search found no decrease before the tolerance was met (round-off: the
    /// step is taken as it stands).
    pub stalled: u64,
    /// Numeric factorisations of the step matrix.
    pub factorizations: u64,
    /// Wall time in the factorisations (s).
    pub factor_seconds: f64,
    /// Factorisations that fell back to the diagonal (mass and contact) because the
    /// Gauss-Newton stand-in would not factor.
    pub diagonal_only: u64,
}

/// The solver's state and buffers: grown to the vertex count, never shrunk.
#[derive(Debug, Default)]
pub(crate) struct Newmark {
    config: NewmarkConfig,
    pub(crate) stats: NewmarkStats,
    matrix: Option<BlockMatrix>,
    /// The topology count the pattern was made for.
    topology: Option<u64>,
    last_iterations: usize,
    /// Whether the last solve stopped at the iteration cap.
    pub(crate) last_capped: bool,
    /// A lower cap for the next solves, set by the event search for its trials.
    pub(crate) trial_cap: Option<usize>,
    /// Acceleration at the current state (m/s^2).
    pub(crate) acc: Vec<Vec3>,
    target: Vec<Vec3>,
    y: Vec<Vec3>,
    f: Vec<Vec3>,
    gq: Vec<Vec3>,
    bodies: Vec<Vec3>,
    gc: Vec<Vec3>,
    /// Unknowns, gradient, direction, trial point and gradient: free vertices' then bodies'.
    q: Vec<f64>,
    g: Vec<f64>,
    d: Vec<f64>,
    qt: Vec<f64>,
    gt: Vec<f64>,
    /// Bodies' diagonal preconditioner (N/m).
    body_diag: Vec<f64>,
    /// Vertex masses (kg) and contact stiffness hints (N/m), copied per step.
    masses: Vec<f64>,
    hint: Vec<f64>,
    /// L-BFGS history, a ring of `history` pairs.
    s_hist: Vec<Vec<f64>>,
    y_hist: Vec<Vec<f64>>,
    rho: Vec<f64>,
    alpha: Vec<f64>,
}

/// A copy keeps the settings, counts and accelerations; the matrix is rebuilt at its next step,
/// so a copy of a shell already stepped solves from another matrix and can differ from the
/// original in the last bits (a checkpoint keeps the matrices: [`Newmark::write_checkpoint`]).
impl Clone for Newmark {
    fn clone(&self) -> Self {
        Newmark {
            config: self.config,
            stats: self.stats,
            acc: self.acc.clone(),
            ..Newmark::default()
        }
    }
}

impl Newmark {
    pub(crate) fn new(config: NewmarkConfig) -> Result<Newmark, ShellError> {
        config.check()?;
        Ok(Newmark {
            config,
            ..Newmark::default()
        })
    }

    pub(crate) fn config(&self) -> NewmarkConfig {
        self.config
    }

    /// Writes for a checkpoint what later steps read: the counts and the factorisations' wall
    /// time, the last solve's iterations and cap, the search's trial cap, the
    /// accelerations, and the step matrix as each kept factor was made from it, when the matrix
    /// is the one the next step would use (made for the mesh changes `topology` and the held
    /// set `held`; a stale one is rebuilt at the next step whether or not the run was resumed).
    /// Each was assembled at the positions and contact state of some earlier step, so it is
    /// kept, not assembled again.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer, topology: u64, held: &[bool]) {
        w.tag("newmark");
        let st = &self.stats;
        for n in [
            st.steps,
            st.iterations,
            st.capped,
            st.stalled,
            st.factorizations,
            st.diagonal_only,
        ] {
            w.u64(n);
        }
        w.f64(st.factor_seconds);
        w.usize(self.last_iterations);
        w.bool(self.last_capped);
        w.bool(self.trial_cap.is_some());
        w.usize(self.trial_cap.unwrap_or(0));
        w.array(&self.acc);
        // The matrix the next step will use: one made for another mesh or held set is rebuilt
        // there, and after a long solve every kept factor is dropped.
        let current = self.matrix.as_ref().filter(|m| {
            self.topology == Some(topology)
                && m.matches(held)
                && self.last_iterations <= REFACTOR_ITERATIONS
        });
        w.bool(current.is_some());
        if let Some(m) = current {
            w.usize(m.kept().count());
            for (key, values) in m.kept() {
                w.f64(key);
                w.array(values);
            }
        }
    }

    /// Reads what [`Newmark::write_checkpoint`] wrote, the mesh, mesh changes and held set
    /// already read; the step matrix's pattern is rebuilt from them and each kept matrix
    /// factored again (the same values factor to the same bits).
    pub(crate) fn read_checkpoint(
        &mut self,
        r: &mut Reader,
        mesh: &ShellMesh,
        topology: u64,
        held: &[bool],
    ) -> Result<(), CheckpointError> {
        let invalid = |message: String| CheckpointError::Invalid {
            what: "Newmark stepping".into(),
            message,
        };
        r.tag("newmark")?;
        let mut st = NewmarkStats::default();
        for (c, what) in [
            (&mut st.steps, "implicit solves"),
            (&mut st.iterations, "L-BFGS iterations"),
            (&mut st.capped, "capped solves"),
            (&mut st.stalled, "stalled solves"),
            (&mut st.factorizations, "factorisations"),
            (&mut st.diagonal_only, "diagonal-only factorisations"),
        ] {
            *c = r.u64(what)?;
        }
        st.factor_seconds = r.f64("factorisation time")?;
        self.stats = st;
        self.last_iterations = r.usize("the last solve's iterations")?;
        self.last_capped = r.bool("whether the last solve was capped")?;
        let has_cap = r.bool("trial cap")?;
        let cap = r.usize("trial cap")?;
        self.trial_cap = has_cap.then_some(cap);
        r.array_vec("accelerations", &mut self.acc)?;
        if !self.acc.is_empty() && self.acc.len() != mesh.num_vertices() {
            return Err(invalid(format!(
                "{} accelerations for {} vertices",
                self.acc.len(),
                mesh.num_vertices()
            )));
        }
        self.matrix = None;
        self.topology = None;
        if r.bool("step matrix")? {
            let count = r.usize("kept factors")?;
            let mut kept = Vec::new();
            for _ in 0..count {
                let key = r.f64("factor's step")?;
                if !(key.is_finite() && key > 0.0) {
                    return Err(invalid(format!("a factor kept for a step of {key} s")));
                }
                let mut values = Vec::new();
                r.array_vec("step matrix", &mut values)?;
                kept.push((key, values));
            }
            let mut matrix = BlockMatrix::new(mesh, held).map_err(|e| invalid(e.to_string()))?;
            matrix
                .refactor_kept(&kept)
                .map_err(|e| invalid(e.to_string()))?;
            self.matrix = Some(matrix);
            self.topology = Some(topology);
        }
        Ok(())
    }

    /// Spreads the unknowns `q`, or the trial point `qt` (`trial`), over the positions `y` of
    /// the free vertices (held ones keep their place) and the bodies' centres.
    fn spread(&mut self, trial: bool) {
        let Some(matrix) = &self.matrix else {
            return;
        };
        let q = if trial { &self.qt } else { &self.q };
        for (k, &vi) in matrix.vertices.iter().enumerate() {
            self.y[vi as usize] = [q[3 * k], q[3 * k + 1], q[3 * k + 2]];
        }
        let nf = matrix.len();
        for (b, c) in self.bodies.iter_mut().enumerate() {
            let k = 3 * (nf + b);
            *c = [q[k], q[k + 1], q[k + 2]];
        }
    }

    /// The L-BFGS direction `-H g` into `d` from the newest `count` pairs of the ring (the next
    /// slot is `head`), with the factored matrix as `H_0`.
    fn direction(&mut self, count: usize, head: usize) {
        let hist = self.s_hist.len();
        self.d.copy_from_slice(&self.g);
        for j in 0..count {
            let slot = (head + hist - 1 - j) % hist;
            let a = self.rho[slot] * dot_flat(&self.s_hist[slot], &self.d);
            self.alpha[slot] = a;
            axpy_flat(&mut self.d, -a, &self.y_hist[slot]);
        }
        let matrix = self.matrix.as_mut().expect("built before the solve");
        let nf = matrix.len();
        matrix.solve(&mut self.d[..3 * nf]);
        for (b, &k) in self.body_diag.iter().enumerate() {
            for c in 0..3 {
                self.d[3 * (nf + b) + c] /= k;
            }
        }
        for j in (0..count).rev() {
            let slot = (head + hist - 1 - j) % hist;
            let b = self.rho[slot] * dot_flat(&self.y_hist[slot], &self.d);
            axpy_flat(&mut self.d, self.alpha[slot] - b, &self.s_hist[slot]);
        }
        self.d.iter_mut().for_each(|d| *d = -*d);
    }
}

impl ShellDynamics {
    /// One implicit Newmark step of `h` (s); see the module's text.
    pub(super) fn newmark_step(&mut self, h: f64) -> Result<(), ShellError> {
        let Some(mut nm) = self.newmark.take() else {
            return Ok(());
        };
        let mut masses = std::mem::take(&mut nm.masses);
        masses.clear();
        masses.extend_from_slice(self.model.masses());
        let out = self.newmark_solve(&mut nm, h, &masses);
        nm.masses = masses;
        self.newmark = Some(nm);
        out
    }

    fn newmark_solve(
        &mut self,
        nm: &mut Newmark,
        h: f64,
        masses: &[f64],
    ) -> Result<(), ShellError> {
        let cfg = nm.config;
        let n = self.x.len();
        let g = self.gravity;
        // Fracture gives a new vertex its sources' mean acceleration; should the count still
        // differ (a shell switched to Newmark mid-run), take them from the current forces.
        if nm.acc.len() != n {
            nm.acc.clear();
            nm.acc.extend(
                self.f
                    .iter()
                    .zip(masses)
                    .zip(&self.pinned)
                    .map(|((f, m), &p)| if p { [0.0; 3] } else { axpy(g, 1.0 / m, *f) }),
            );
        }
        let (beta, gamma) = (cfg.beta, cfg.gamma);
        let inertia = 1.0 / (beta * h * h);
        // Targets and the predictor; held vertices sit on their motion.
        nm.target.resize(n, [0.0; 3]);
        nm.y.resize(n, [0.0; 3]);
        nm.f.resize(n, [0.0; 3]);
        nm.gq.resize(n, [0.0; 3]);
        for i in 0..n {
            let (x, v, a) = (self.x[i], self.v[i], nm.acc[i]);
            let drift = axpy(x, h, v);
            if self.pinned[i] {
                nm.target[i] = drift;
                nm.y[i] = drift;
            } else {
                nm.target[i] = axpy(axpy(drift, h * h * (0.5 - beta), a), beta * h * h, g);
                nm.y[i] = axpy(drift, 0.5 * h * h, a);
            }
        }
        // Loads at the step's end enter as gravity does: the potential -F.x.
        self.loads.shift(
            self.time + h,
            beta * h * h,
            &mut nm.target,
            masses,
            &self.pinned,
        );
        // The colliders' lagged state for the step.
        let nb = match &mut self.colliders {
            Some(c) => {
                let started = Instant::now();
                c.begin_implicit(h, &self.x, &self.v, masses, &self.radii)
                    .map_err(|e| ShellError::Contact(e.to_string()))?;
                nm.bodies.clear();
                nm.bodies.extend_from_slice(c.implicit_body_targets());
                nm.body_diag.clear();
                nm.body_diag.extend_from_slice(c.implicit_body_diagonal());
                self.collider_seconds += started.elapsed().as_secs_f64();
                nm.bodies.len()
            }
            None => {
                nm.bodies.clear();
                0
            }
        };
        nm.gc.resize(nb, [0.0; 3]);
        self.newmark_matrix(nm, h, inertia, masses)?;
        let matrix = nm.matrix.as_ref().expect("built above");
        let nf = matrix.len();
        let dofs = 3 * (nf + nb);
        for v in [&mut nm.q, &mut nm.g, &mut nm.d, &mut nm.qt, &mut nm.gt] {
            v.resize(dofs, 0.0);
        }
        for (k, &vi) in matrix.vertices.iter().enumerate() {
            nm.q[3 * k..3 * k + 3].copy_from_slice(&nm.y[vi as usize]);
        }
        for (b, c) in nm.bodies.iter().enumerate() {
            nm.q[3 * (nf + b)..3 * (nf + b) + 3].copy_from_slice(c);
        }
        if nm.s_hist.len() != cfg.history || nm.s_hist.first().is_some_and(|s| s.len() != dofs) {
            nm.s_hist = vec![vec![0.0; dofs]; cfg.history];
            nm.y_hist = vec![vec![0.0; dofs]; cfg.history];
            nm.rho = vec![0.0; cfg.history];
            nm.alpha = vec![0.0; cfg.history];
        }
        // The force scale the residual is judged against.
        let reference = self
            .f
            .iter()
            .zip(&self.pinned)
            .filter(|(_, &p)| !p)
            .map(|(f, _)| dot(*f, *f).sqrt())
            .chain(masses.iter().map(|m| m * dot(g, g).sqrt()))
            .fold(self.model.force_scale(), f64::max)
            .max(self.loads.largest(self.time + h));
        // At short steps the inertia term's round-off (a few ulps of the positions, times
        // m / (beta h^2)) can pass the tolerance: no iteration gets below it.
        let floor = nm
            .target
            .iter()
            .zip(masses)
            .map(|(t, m)| m * inertia * t.iter().fold(0.0f64, |a, c| a.max(c.abs())))
            .fold(0.0, f64::max)
            * INERTIA_ULPS
            * f64::EPSILON;
        let goal = (cfg.tolerance * reference).max(floor);

        let mut phi = self.newmark_phi(nm, inertia, true)?;
        std::mem::swap(&mut nm.g, &mut nm.gt);
        let (mut count, mut head) = (0usize, 0usize);
        let mut iterations = 0;
        let mut capped = true;
        let cap = nm
            .trial_cap
            .map_or(cfg.max_iterations, |t| t.min(cfg.max_iterations));
        while iterations < cap {
            if largest(&nm.g) <= goal {
                capped = false;
                break;
            }
            iterations += 1;
            nm.direction(count, head);
            let slope: f64 = nm.g.iter().zip(&nm.d).map(|(a, b)| a * b).sum();
            if slope.is_nan() || slope >= 0.0 {
                // Not a descent direction (round-off at the bottom): start the history again
                // (the factored matrix alone is positive definite).
                count = 0;
                nm.direction(0, head);
            }
            let slope: f64 = nm.g.iter().zip(&nm.d).map(|(a, b)| a * b).sum();
            let mut step = 1.0;
            let mut accepted = None;
            // A decrease this small is below the round-off of `Phi` itself: the full step is
            // judged by the residual instead.
            if -slope < ROUND_OFF * phi.abs() {
                for ((t, q), d) in nm.qt.iter_mut().zip(&nm.q).zip(&nm.d) {
                    *t = q + d;
                }
                let trial = self.newmark_phi(nm, inertia, false)?;
                if trial.is_finite() && largest(&nm.gt) < largest(&nm.g) {
                    accepted = Some(trial);
                }
            }
            for _ in 0..if accepted.is_some() { 0 } else { 40 } {
                for ((t, q), d) in nm.qt.iter_mut().zip(&nm.q).zip(&nm.d) {
                    *t = q + step * d;
                }
                let trial = self.newmark_phi(nm, inertia, false)?;
                if trial.is_finite() && trial <= phi + 1e-4 * step * slope {
                    accepted = Some(trial);
                    break;
                }
                step *= 0.5;
            }
            let Some(trial) = accepted else {
                nm.stats.stalled += 1;
                capped = false;
                break;
            };
            // s = qt - q, y = gt - g into the ring, when curvature is positive along s (a
            // pair that is not would break the two-loop's positive definiteness; the slot,
            // the oldest pair once the ring is full, is then left as it was).
            let sy: f64 = (0..dofs)
                .map(|k| (nm.qt[k] - nm.q[k]) * (nm.gt[k] - nm.g[k]))
                .sum();
            if cfg.history > 0 && sy > 0.0 {
                let slot = head;
                for k in 0..dofs {
                    nm.s_hist[slot][k] = nm.qt[k] - nm.q[k];
                    nm.y_hist[slot][k] = nm.gt[k] - nm.g[k];
                }
                nm.rho[slot] = 1.0 / sy;
                head = (head + 1) % cfg.history;
                count = (count + 1).min(cfg.history);
            }
            std::mem::swap(&mut nm.q, &mut nm.qt);
            std::mem::swap(&mut nm.g, &mut nm.gt);
            phi = trial;
        }
        if capped && largest(&nm.g) <= goal {
            capped = false; // the last iteration got there
        }
        nm.stats.steps += 1;
        nm.stats.iterations += iterations as u64;
        nm.last_iterations = iterations;
        nm.last_capped = capped;
        if capped {
            nm.stats.capped += 1;
        }
        // Accept: positions, the forces there (with the plastic update), the contact state.
        nm.spread(false);
        self.x.copy_from_slice(&nm.y);
        self.elastic = self.model.forces(&self.x, &mut self.f)?;
        self.add_self_contact()?;
        if let Some(c) = &mut self.colliders {
            let started = Instant::now();
            nm.gq.fill([0.0; 3]);
            nm.gc.fill([0.0; 3]);
            c.implicit_potential(&self.x, &nm.bodies, Some((&mut nm.gq, &mut nm.gc)));
            for (f, gq) in self.f.iter_mut().zip(&nm.gq) {
                *f = sub(*f, *gq);
            }
            self.contact = c.end_implicit(&self.x, &nm.bodies, &self.v);
            self.collider_seconds += started.elapsed().as_secs_f64();
        }
        let keep = 1.0 / (1.0 + self.damping * h);
        for ((((v, acc), f), &m), &held) in self
            .v
            .iter_mut()
            .zip(&mut nm.acc)
            .zip(&self.f)
            .zip(masses)
            .zip(&self.pinned)
        {
            if held {
                *acc = [0.0; 3];
                continue;
            }
            let a = axpy(g, 1.0 / m, *f);
            *v = scale(axpy(axpy(*v, h * (1.0 - gamma), *acc), h * gamma, a), keep);
            *acc = a;
        }
        self.loads.finish(
            self.time + h,
            gamma * h * keep,
            &mut self.v,
            &mut nm.acc,
            masses,
            &self.pinned,
        );
        self.time += h;
        if !(self.elastic.is_finite() && self.self_energy.is_finite()) {
            return Err(ShellError::RanAway { time: self.time });
        }
        Ok(())
    }

    /// Builds the pattern when the mesh or the held set changed; factors for step `h` unless a
    /// factor for it is kept. Factors are kept per step length (the event search moves between
    /// a few) and all dropped when a solve needed many iterations (the positions they were made
    /// at have drifted).
    fn newmark_matrix(
        &mut self,
        nm: &mut Newmark,
        h: f64,
        inertia: f64,
        masses: &[f64],
    ) -> Result<(), ShellError> {
        let rebuilt = match &nm.matrix {
            Some(m) => !(nm.topology == Some(self.topology) && m.matches(&self.pinned)),
            None => true,
        };
        if rebuilt {
            nm.matrix = Some(BlockMatrix::new(self.model.mesh(), &self.pinned)?);
            nm.topology = Some(self.topology);
        }
        let matrix = nm.matrix.as_mut().expect("built above");
        if nm.last_iterations > REFACTOR_ITERATIONS {
            matrix.forget();
            nm.last_iterations = 0;
        }
        if matrix.use_factor(h) {
            return Ok(());
        }
        let started = Instant::now();
        matrix.clear();
        for (i, &m) in masses.iter().enumerate() {
            matrix.add_diagonal(i, m * inertia);
        }
        self.model
            .gauss_newton(&self.x, |i, j, b| matrix.add_block(i, j, b))?;
        nm.hint.clear();
        if let Some(c) = &self.colliders {
            nm.hint.resize(self.x.len(), 0.0);
            c.implicit_stiffness_hint(&nm.y, &nm.bodies, &mut nm.hint);
            for (i, &k) in nm.hint.iter().enumerate() {
                matrix.add_diagonal(i, k);
            }
        }
        if matrix.factor(h).is_err() {
            // A nearly folded hinge (phi' grows without bound towards a half turn) or a
            // sliver from fracture can leave the stand-in unfactorable in floating point: the
            // mass and contact diagonal alone is positive definite and still a preconditioner.
            matrix.clear();
            for (i, &m) in masses.iter().enumerate() {
                let k = nm.hint.get(i).copied().unwrap_or(0.0);
                matrix.add_diagonal(i, m * inertia + k);
            }
            matrix.factor(h)?;
            nm.stats.diagonal_only += 1;
        }
        nm.stats.factorizations += 1;
        nm.stats.factor_seconds += started.elapsed().as_secs_f64();
        Ok(())
    }

    /// `Phi` at `q` (`at_q`) or at the trial point `qt`, and its gradient into `gt`.
    fn newmark_phi(
        &mut self,
        nm: &mut Newmark,
        inertia: f64,
        at_q: bool,
    ) -> Result<f64, ShellError> {
        nm.spread(!at_q);
        if nm.y.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
            return Ok(f64::INFINITY);
        }
        let mut e = self.model.frozen_forces(&nm.y, &mut nm.f)?;
        if let Some(sc) = &mut self.self_contact {
            e += sc.add_forces(self.model.mesh(), &nm.y, &mut nm.f)?;
        }
        nm.gq.fill([0.0; 3]);
        nm.gc.fill([0.0; 3]);
        if let Some(c) = &mut self.colliders {
            let started = Instant::now();
            e += c.implicit_potential(&nm.y, &nm.bodies, Some((&mut nm.gq, &mut nm.gc)));
            self.collider_seconds += started.elapsed().as_secs_f64();
        }
        let matrix = nm.matrix.as_ref().expect("built before the solve");
        let masses = self.model.masses();
        for (k, &vi) in matrix.vertices.iter().enumerate() {
            let i = vi as usize;
            let dx = sub(nm.y[i], nm.target[i]);
            e += 0.5 * masses[i] * inertia * dot(dx, dx);
            let grad = sub(axpy(nm.gq[i], masses[i] * inertia, dx), nm.f[i]);
            nm.gt[3 * k..3 * k + 3].copy_from_slice(&grad);
        }
        let nf = matrix.len();
        for (b, gc) in nm.gc.iter().enumerate() {
            nm.gt[3 * (nf + b)..3 * (nf + b) + 3].copy_from_slice(gc);
        }
        Ok(e)
    }
}

/// A solve that took more L-BFGS iterations than this refactors the matrix at the next step's
/// start (positions drifted from the ones it was made at).
const REFACTOR_ITERATIONS: usize = 20;

/// Ulps of the positions the residual cannot get below, in units of the inertia term
/// (measured: solves at 1e-8 s on the egg stalled at about 4).
const INERTIA_ULPS: f64 = 8.0;

/// The relative round-off of `Phi` as evaluated (a sum over many triangles' energies): a
/// predicted decrease below this share of `|Phi|` cannot be told from noise.
const ROUND_OFF: f64 = 1e-12;

fn largest(g: &[f64]) -> f64 {
    g.iter().fold(0.0, |m, x| m.max(x.abs()))
}

fn dot_flat(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn axpy_flat(a: &mut [f64], s: f64, b: &[f64]) {
    a.iter_mut().zip(b).for_each(|(x, y)| *x += s * y);
}
