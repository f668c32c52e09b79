//! Newton's method with load stepping for the neo-Hookean statics of [`crate::nonlinear`]:
//! per load step a predictor, then Newton iterations with a backtracking line search on the
//! total potential energy, and halving of the step when it fails.

use crate::assembly::CONSTRAINED;
use crate::basis::Basis;
use crate::error::FemError;
use crate::hyperelastic_system::{Energies, System};
use crate::math::Vec3;
use crate::nonlinear::{NewtonOptions, NonlinearSolution, StepReport};
use crate::problem::Problem;
use crate::shifted_cholesky::ShiftedCholesky;

/// Halvings tried by the line search before it gives up.
const BACKTRACKS: usize = 40;
/// Sufficient-decrease constant of the Armijo condition.
const ARMIJO: f64 = 1e-4;
/// Energy changes below this fraction of the energy's terms are rounding (about 5e4 eps).
const ENERGY_NOISE: f64 = 1e-11;

/// What one attempted (sub-)step reports.
struct Attempt {
    iterations: usize,
    shifted: usize,
    initial_residual: f64,
    residual: f64,
}

pub(crate) struct Newton<'p, const N: usize, B: Basis<N>> {
    problem: &'p Problem,
    t_final: f64,
    options: NewtonOptions,
    system: System<'p, N, B>,
    cholesky: ShiftedCholesky,
    values: Vec<f64>,
    /// Displacements (m) of every node: the current state.
    u: Vec<Vec3>,
    /// `dPi/du` (N) at `u`.
    grad: Vec<Vec3>,
    energies: Energies,
    trial: Vec<Vec3>,
    trial_grad: Vec<Vec3>,
    /// Free-DOF work vector.
    rhs: Vec<f64>,
}

impl<'p, const N: usize, B: Basis<N>> Newton<'p, N, B> {
    pub fn new(
        problem: &'p Problem,
        t_final: f64,
        options: &NewtonOptions,
    ) -> Result<Self, FemError> {
        let system = System::<N, B>::new(problem, options.quadrature)?;
        let cholesky = ShiftedCholesky::new(&system.pattern)?;
        let n = problem.mesh().node_count();
        let n_free = system.free.count;
        Ok(Self {
            problem,
            t_final,
            options: *options,
            values: vec![0.0; system.pattern.len()],
            system,
            cholesky,
            u: vec![[0.0; 3]; n],
            grad: vec![[0.0; 3]; n],
            energies: Energies {
                strain: 0.0,
                potential: 0.0,
                scale: 0.0,
            },
            trial: vec![[0.0; 3]; n],
            trial_grad: vec![[0.0; 3]; n],
            rhs: vec![0.0; n_free],
        })
    }

    pub fn run(mut self) -> Result<NonlinearSolution, FemError> {
        let steps = self.options.load_steps;
        let mut reports = Vec::with_capacity(steps);
        let mut s_done = 0.0;
        for step in 0..steps {
            let s_target = (step + 1) as f64 / steps as f64;
            let mut report = StepReport {
                load: s_target,
                iterations: 0,
                substeps: 0,
                shifted: 0,
                initial_residual: f64::NAN,
                residual: f64::NAN,
            };
            let mut cuts = 0;
            let mut ends = vec![s_target];
            while let Some(&s_next) = ends.last() {
                let saved = self.u.clone();
                let mut counters = (0, 0);
                match self.attempt(step, s_next, &mut counters) {
                    Ok(a) => {
                        report.iterations += a.iterations;
                        report.shifted += a.shifted;
                        if report.substeps == 0 {
                            report.initial_residual = a.initial_residual;
                        }
                        report.substeps += 1;
                        report.residual = a.residual;
                        s_done = s_next;
                        ends.pop();
                    }
                    Err(e) => {
                        report.iterations += counters.0;
                        report.shifted += counters.1;
                        let recoverable = matches!(
                            e,
                            FemError::ElementInverted { .. }
                                | FemError::NotConverged { .. }
                                | FemError::LineSearchFailed { .. }
                        );
                        if !recoverable || cuts >= self.options.max_cuts {
                            return Err(e);
                        }
                        cuts += 1;
                        self.u = saved;
                        ends.push(0.5 * (s_done + s_next));
                    }
                }
            }
            reports.push(report);
        }
        let free = &self.system.free.index;
        let reactions = self
            .grad
            .iter()
            .enumerate()
            .map(|(node, g)| {
                if free[3 * node] == CONSTRAINED {
                    *g
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        Ok(NonlinearSolution {
            residual: free_norm(&self.grad, free),
            displacements: self.u,
            reactions,
            steps: reports,
            strain_energy: self.energies.strain,
            potential_energy: self.energies.potential,
            free_dofs: self.system.free.count,
        })
    }

    /// One (sub-)step from the current equilibrium to load `s`; `counters` counts iterations
    /// and shifted factorisations as they happen, for the report of a failed attempt.
    fn attempt(
        &mut self,
        step: usize,
        s: f64,
        counters: &mut (usize, usize),
    ) -> Result<Attempt, FemError> {
        let time = s * self.t_final;
        let inverted = |element| FemError::ElementInverted {
            element,
            time: Some(time),
        };
        let mesh = self.problem.mesh();
        // Increment of the held nodes' displacements.
        let mut held_step = vec![[0.0; 3]; mesh.node_count()];
        for (node, du) in held_step.iter_mut().enumerate() {
            if let Some(p) = self.problem.held_position(node, time) {
                let x = mesh.nodes()[node];
                *du = std::array::from_fn(|d| p[d] - x[d] - self.u[node][d]);
            }
        }
        if held_step.iter().flatten().any(|v| !v.is_finite()) {
            return Err(FemError::Solver(format!(
                "a prescribed motion is not finite at time {time} s"
            )));
        }
        // Predictor: tangent at the last equilibrium with the held nodes' increment.
        self.system
            .evaluate(&self.u, s, &mut self.grad)
            .map_err(inverted)?;
        let free = self.system.free.index.clone();
        for (k, &r) in free.iter().enumerate() {
            if r != CONSTRAINED {
                self.rhs[r as usize] = -self.grad[k / 3][k % 3];
            }
        }
        let rhs = &mut self.rhs;
        self.system
            .tangent(&self.u, &mut self.values, |r, node, d, kv| {
                rhs[r] -= kv * held_step[node][d];
            })
            .map_err(inverted)?;
        let reference = norm(&self.rhs);
        let mut shifted = 0;
        if reference > 0.0 {
            shifted += usize::from(self.solve()?);
        }
        for (k, &r) in free.iter().enumerate() {
            let (node, d) = (k / 3, k % 3);
            self.trial[node][d] = self.u[node][d]
                + if r == CONSTRAINED {
                    held_step[node][d]
                } else if reference > 0.0 {
                    self.rhs[r as usize]
                } else {
                    0.0
                };
        }
        self.energies = self
            .system
            .evaluate(&self.trial, s, &mut self.grad)
            .map_err(inverted)?;
        std::mem::swap(&mut self.u, &mut self.trial);
        let mut iterations = 1;
        *counters = (iterations, shifted);
        let target = self.options.tolerance * reference;
        loop {
            let residual = free_norm(&self.grad, &free);
            if !residual.is_finite() {
                return Err(FemError::Solver("the residual is not finite".into()));
            }
            // Below the rounding floor the residual only jitters: measured at 0.28 to 0.36 of
            // `rounding_floor` on the bent bar, so reaching the floor itself is convergence.
            if residual <= target.max(self.rounding_floor(&free)) {
                return Ok(Attempt {
                    iterations,
                    shifted,
                    initial_residual: reference,
                    residual,
                });
            }
            if iterations >= self.options.max_iterations {
                return Err(FemError::NotConverged {
                    step,
                    load: s,
                    iterations,
                    residual,
                    tolerance: target.max(self.rounding_floor(&free)),
                });
            }
            for (k, &r) in free.iter().enumerate() {
                if r != CONSTRAINED {
                    self.rhs[r as usize] = -self.grad[k / 3][k % 3];
                }
            }
            self.system
                .tangent(&self.u, &mut self.values, |_, _, _, _| {})
                .map_err(inverted)?;
            shifted += usize::from(self.solve()?);
            iterations += 1;
            *counters = (iterations, shifted);
            if !self.line_search(s, residual, &free) {
                return Err(FemError::LineSearchFailed {
                    step,
                    load: s,
                    iteration: iterations,
                    residual,
                });
            }
        }
    }

    /// Solves the assembled tangent for `self.rhs` in place; returns whether it was shifted.
    fn solve(&mut self) -> Result<bool, FemError> {
        self.cholesky
            .solve_in_place(&self.system.pattern, &self.values, &mut self.rhs)
    }

    /// Size (N) of the residual that rounding alone leaves: eps times the norm over the free
    /// DOFs of the tangent's diagonal times the displacement (a change of one unit in the last
    /// place of a displacement moves the residual by about that much).
    fn rounding_floor(&self, free: &[u32]) -> f64 {
        let pattern = &self.system.pattern;
        free.iter()
            .enumerate()
            .filter(|(_, &r)| r != CONSTRAINED)
            .map(|(k, &r)| {
                (self.values[pattern.diagonal(r as usize)] * self.u[k / 3][k % 3]).powi(2)
            })
            .sum::<f64>()
            .sqrt()
            * f64::EPSILON
    }

    /// Backtracks along the direction in `self.rhs` from `self.u` until `Pi` decreases enough
    /// (Armijo), or, at rounding level, until the residual drops; moves `self.u` there.
    fn line_search(&mut self, s: f64, residual: f64, free: &[u32]) -> bool {
        let dir = &self.rhs;
        let slope: f64 = free
            .iter()
            .enumerate()
            .filter(|(_, &r)| r != CONSTRAINED)
            .map(|(k, &r)| self.grad[k / 3][k % 3] * dir[r as usize])
            .sum();
        let start = self.energies;
        let mut alpha = 1.0;
        for _ in 0..BACKTRACKS {
            for (k, &r) in free.iter().enumerate() {
                let (node, d) = (k / 3, k % 3);
                self.trial[node][d] = self.u[node][d]
                    + if r == CONSTRAINED {
                        0.0
                    } else {
                        alpha * dir[r as usize]
                    };
            }
            match self.system.evaluate(&self.trial, s, &mut self.trial_grad) {
                // J <= 0 somewhere: a rejected step.
                Err(_) => alpha *= 0.5,
                Ok(e) => {
                    let change = e.potential - start.potential;
                    let armijo = change <= ARMIJO * alpha * slope;
                    let noise = ENERGY_NOISE * start.scale.max(e.scale);
                    let rounding =
                        change.abs() <= noise && free_norm(&self.trial_grad, free) < residual;
                    if armijo || rounding {
                        std::mem::swap(&mut self.u, &mut self.trial);
                        std::mem::swap(&mut self.grad, &mut self.trial_grad);
                        self.energies = e;
                        return true;
                    }
                    // Minimiser of the quadratic through Pi(0), Pi'(0) and Pi(alpha), kept
                    // within [alpha / 10, alpha / 2].
                    let curvature = change - slope * alpha;
                    let fit = if curvature > 0.0 {
                        -slope * alpha * alpha / (2.0 * curvature)
                    } else {
                        0.5 * alpha
                    };
                    alpha = fit.clamp(0.1 * alpha, 0.5 * alpha);
                }
            }
        }
        false
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Euclidean norm of a nodal field over the free DOFs.
fn free_norm(field: &[Vec3], free: &[u32]) -> f64 {
    free.iter()
        .enumerate()
        .filter(|(_, &r)| r != CONSTRAINED)
        .map(|(k, _)| field[k / 3][k % 3].powi(2))
        .sum::<f64>()
        .sqrt()
}
