//! Explicit dynamics: velocity Verlet (central difference) with a lumped mass.

use crate::error::FemError;
use crate::forces::{ElasticForces, Kinematics, Parallelism};
use crate::math::{dot, Vec3};
use crate::mesh::{Mesh, Order};
use crate::problem::Problem;

/// Lumped (diagonal) mass (kg) of every node. P1: a quarter of each tet's mass per corner. P2:
/// HRZ lumping (the diagonal of the consistent mass, scaled to the element's mass), which gives
/// each tet's corners `rho V / 36` and its edge nodes `4 rho V / 27`, all positive (row sums
/// would give the corners negative mass).
pub fn lumped_masses(mesh: &Mesh, density: f64) -> Vec<f64> {
    let mut m = vec![0.0; mesh.node_count()];
    let (corner, edge) = match mesh.order() {
        Order::Linear => (0.25, 0.0),
        Order::Quadratic => (1.0 / 36.0, 4.0 / 27.0),
    };
    for e in 0..mesh.element_count() {
        let mass = density * mesh.volumes()[e];
        for (a, &n) in mesh.element(e).iter().enumerate() {
            m[n as usize] += mass * if a < 4 { corner } else { edge };
        }
    }
    m
}

/// Estimate of the critical time step (s) of central difference on `problem`'s mesh with the
/// lumped mass: `2 / sqrt(lambda_max)`, `lambda_max` of `M^-1 K` (linear stiffness, every node
/// free, which bounds the constrained system's) by `iterations` power iterations. Power
/// iteration approaches `lambda_max` from below, so the estimate is a little above the true
/// limit: use a safety factor (0.5 to 0.9).
pub fn critical_time_step(problem: &Problem, iterations: usize) -> f64 {
    let mesh = problem.mesh();
    let mass = lumped_masses(mesh, problem.material().density);
    let mut kernel = ElasticForces::new(mesh, problem.material(), Kinematics::Linear);
    let rest = mesh.nodes();
    let n = mesh.node_count();
    // Deterministic, rough start vector.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut v: Vec<Vec3> = (0..n)
        .map(|_| {
            std::array::from_fn(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
        })
        .collect();
    let mut x = vec![[0.0; 3]; n];
    let mut f = vec![[0.0; 3]; n];
    let mut lambda = 0.0;
    for _ in 0..iterations.max(1) {
        // M-normalise v.
        let norm: f64 = v
            .iter()
            .zip(&mass)
            .map(|(vi, m)| m * dot(*vi, *vi))
            .sum::<f64>()
            .sqrt();
        for vi in &mut v {
            *vi = vi.map(|c| c / norm);
        }
        for i in 0..n {
            x[i] = std::array::from_fn(|d| rest[i][d] + v[i][d]);
        }
        kernel
            .compute(&x, &mut f)
            .expect("linear kinematics never fails");
        // f = -K v; Rayleigh quotient v^T K v / v^T M v with v^T M v = 1.
        lambda = -v.iter().zip(&f).map(|(vi, fi)| dot(*vi, *fi)).sum::<f64>();
        for i in 0..n {
            v[i] = f[i].map(|c| -c / mass[i]);
        }
    }
    2.0 / lambda.sqrt()
}

/// Explicit dynamics of a [`Problem`]: velocity Verlet (kick, drift, constrain, force, kick),
/// which is central difference with synchronised velocities. Second order, symplectic (energy
/// error bounded, no drift, for the conservative forces here), stable for `dt` below
/// [`critical_time_step`]. Gravity acts as `m_i g` on each lumped node mass, so a free body
/// falls with exactly `g`. No allocation per step.
#[derive(Debug)]
pub struct Dynamic<'p> {
    problem: &'p Problem,
    forces: ElasticForces<'p>,
    dt: f64,
    steps: u64,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    f: Vec<Vec3>,
    mass: Vec<f64>,
    free_nodes: Vec<u32>,
    held_nodes: Vec<u32>,
    forces_stale: bool,
}

impl<'p> Dynamic<'p> {
    /// At rest at time 0 (constrained nodes at their held positions for time 0), zero
    /// velocity; `dt` (s) must be positive and finite.
    pub fn new(problem: &'p Problem, kinematics: Kinematics, dt: f64) -> Result<Self, FemError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(FemError::BadTimeStep { dt });
        }
        let mesh = problem.mesh();
        let n = mesh.node_count();
        let (mut free_nodes, mut held_nodes) = (Vec::new(), Vec::new());
        let mut x = mesh.nodes().to_vec();
        for (i, xi) in x.iter_mut().enumerate() {
            match problem.held_position(i, 0.0) {
                Some(p) => {
                    *xi = p;
                    held_nodes.push(i as u32);
                }
                None => free_nodes.push(i as u32),
            }
        }
        Ok(Self {
            problem,
            forces: ElasticForces::new(mesh, problem.material(), kinematics),
            dt,
            steps: 0,
            x,
            v: vec![[0.0; 3]; n],
            f: vec![[0.0; 3]; n],
            mass: lumped_masses(mesh, problem.material().density),
            free_nodes,
            held_nodes,
            forces_stale: true,
        })
    }

    /// The same integrator with its force kernel on the given parallelism.
    pub fn with_parallelism(mut self, parallelism: Parallelism) -> Self {
        self.forces = self.forces.with_parallelism(parallelism);
        self
    }

    /// Advances one step of `dt`. Fails if a corotated element inverts (the state is then that
    /// of the end of the drift, with the forces unusable).
    pub fn step(&mut self) -> Result<(), FemError> {
        if self.forces_stale {
            self.update_forces()?;
        }
        let (dt, g) = (self.dt, self.problem.gravity());
        self.kick(0.5 * dt, g);
        for &i in &self.free_nodes {
            let i = i as usize;
            for d in 0..3 {
                self.x[i][d] += dt * self.v[i][d];
            }
        }
        self.steps += 1;
        let t = self.time();
        for &i in &self.held_nodes {
            let i = i as usize;
            let p = self.problem.held_position(i, t).expect("held node");
            self.v[i] = std::array::from_fn(|d| (p[d] - self.x[i][d]) / dt);
            self.x[i] = p;
        }
        self.update_forces()?;
        self.kick(0.5 * dt, g);
        Ok(())
    }

    /// Steps until `time() >= end` (s) (to within a hundredth of a step); returns the number of
    /// steps taken.
    pub fn advance_to(&mut self, end: f64) -> Result<u64, FemError> {
        let start = self.steps;
        while self.time() < end - 0.01 * self.dt {
            self.step()?;
        }
        Ok(self.steps - start)
    }

    fn kick(&mut self, h: f64, g: Vec3) {
        for &i in &self.free_nodes {
            let i = i as usize;
            let inv_m = 1.0 / self.mass[i];
            let (v, f) = (&mut self.v[i], self.f[i]);
            for (d, gd) in g.iter().enumerate() {
                v[d] += h * (f[d] * inv_m + gd);
            }
        }
    }

    fn update_forces(&mut self) -> Result<(), FemError> {
        let time = self.time();
        self.forces
            .compute(&self.x, &mut self.f)
            .map_err(|e| match e {
                FemError::ElementInverted { element, .. } => FemError::ElementInverted {
                    element,
                    time: Some(time),
                },
                other => other,
            })?;
        self.forces_stale = false;
        Ok(())
    }

    /// Simulated time (s): steps taken times `dt`.
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.dt
    }

    /// Time step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Steps taken.
    pub fn step_count(&self) -> u64 {
        self.steps
    }

    /// The problem.
    pub fn problem(&self) -> &'p Problem {
        self.problem
    }

    /// Current node positions (m).
    pub fn positions(&self) -> &[Vec3] {
        &self.x
    }

    /// Node positions (m), to set an initial deformation; forces are recomputed before the
    /// next step. Constrained nodes are moved back to their held positions by the next step.
    pub fn positions_mut(&mut self) -> &mut [Vec3] {
        self.forces_stale = true;
        &mut self.x
    }

    /// Node velocities (m/s).
    pub fn velocities(&self) -> &[Vec3] {
        &self.v
    }

    /// Node velocities (m/s), to set initial velocities.
    pub fn velocities_mut(&mut self) -> &mut [Vec3] {
        &mut self.v
    }

    /// Lumped node masses (kg).
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Kinetic energy (J) `sum m v^2 / 2` over all nodes.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self
            .v
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| m * dot(*v, *v))
            .sum::<f64>()
    }

    /// Elastic strain energy (J) at the current positions, with this integrator's kinematics.
    pub fn elastic_energy(&self) -> Result<f64, FemError> {
        self.forces.energy(&self.x)
    }

    /// Gravitational potential energy (J) `-sum m g . (x - X)`, zero at rest.
    pub fn gravity_energy(&self) -> f64 {
        let g = self.problem.gravity();
        let rest = self.problem.mesh().nodes();
        -self
            .x
            .iter()
            .zip(rest)
            .zip(&self.mass)
            .map(|((x, r), m)| {
                m * (g[0] * (x[0] - r[0]) + g[1] * (x[1] - r[1]) + g[2] * (x[2] - r[2]))
            })
            .sum::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lumped_masses_add_up_to_the_body_mass() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        for mesh in [
            Mesh::linear(v.clone(), vec![[0, 1, 2, 3]]).unwrap(),
            Mesh::quadratic(v, vec![[0, 1, 2, 3]]).unwrap(),
        ] {
            let m = lumped_masses(&mesh, 600.0);
            assert!((m.iter().sum::<f64>() - 100.0).abs() < 1e-12);
            assert!(m.iter().all(|&mi| mi > 0.0));
        }
    }
}
