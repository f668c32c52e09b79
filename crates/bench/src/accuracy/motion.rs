//! Large motion against corotated FEM: the swinging bar and the twisting bar of Chen et al.
//! 2018, Figures 11 and 12, with the paper's metric, the position deviation over the diagonal
//! of the bounding box.
//!
//! Both are a 1 x 0.1 x 0.1 m bar clamped at x = 0 (for peridynamics a clamp layer one horizon
//! thick behind it, held). The swinging bar (Table 1: kappa = 5e3 kPa, mu = 5e3 kPa,
//! rho = 1000 kg/m^3) starts straight and falls under gravity, swinging down and back; the
//! twisting bar (kappa = 1e3 kPa, mu = 6e2 kPa) starts with an angular velocity about its axis
//! growing linearly from the clamp to 40 rad/s at the free end, and twists about a radian and
//! back. The reference is quadratic tets with corotated kinematics, integrated explicitly; its
//! error is bounded by running it on a mesh half as fine and, there, with half the step.
//!
//! Chen's model (the paper's) runs over the resolution and horizon sweep; Xu's runs beside it
//! on two resolutions at k = 1.5, explicitly and implicitly at 1, 4 and 16 steps per frame
//! ([`super::motion_runs`]), and a second table sets their wall times against their errors.

use std::time::Instant;

use perifrac_fem::{critical_time_step, Dynamic, Kinematics, Problem, Sampler};
use perifrac_physics::{ChenMaterial, Vec3};

use super::motion_runs::{implicit_steps, Method};
use super::{
    clamped_fem_bar, table_and_plot, CaseReport, Run, DENSITY, HORIZON_FACTORS, LENGTH, SIDE,
};
use crate::bar::cells_across;
use crate::table::Table;
use crate::{BenchError, Effort};

/// Steps per 1/24 s frame of the implicit runs.
const PER_FRAME: [u32; 3] = [1, 4, 16];
/// The runs of Xu's model, explicit and implicit.
const XU_METHODS: [Method; 4] = [
    Method::XuExplicit,
    Method::XuImplicit(PER_FRAME[0]),
    Method::XuImplicit(PER_FRAME[1]),
    Method::XuImplicit(PER_FRAME[2]),
];
/// Cells along of Xu's runs and of the speed-against-error table.
const XU_LEVELS: [usize; 2] = [30, 60];
/// Horizon factor of Xu's runs.
const XU_FACTOR: f64 = 1.5;
/// Horizon factor of the runs with the fitted dilatation and of those on unstructured tets.
const FITTED_FACTOR: f64 = 1.5;

/// Diagonal of the bar's bounding box (m): the paper's length scale for the deviation.
pub(super) fn diagonal() -> f64 {
    (LENGTH * LENGTH + 2.0 * SIDE * SIDE).sqrt()
}

/// Which motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Motion {
    /// Figure 11.
    Swing,
    /// Figure 12.
    Twist,
}

impl Motion {
    /// Bulk and shear modulus (Pa), Table 1.
    fn moduli(self) -> (f64, f64) {
        match self {
            Motion::Swing => (5e6, 5e6),
            Motion::Twist => (1e6, 6e5),
        }
    }

    /// The material of Table 1.
    pub(super) fn material(self) -> ChenMaterial {
        let (kappa, mu) = self.moduli();
        ChenMaterial::elastic(kappa, mu, DENSITY)
    }

    /// Young's modulus (Pa) and Poisson's ratio of [`Motion::material`].
    pub(super) fn young_poisson(self) -> (f64, f64) {
        let m = self.material();
        (m.young(), m.poisson())
    }

    /// Gravity (m/s^2).
    pub(super) fn gravity(self) -> Vec3 {
        match self {
            Motion::Swing => [0.0, 0.0, -9.81],
            Motion::Twist => [0.0; 3],
        }
    }

    /// Simulated time (s): about one swing period, two twist periods.
    pub(super) fn duration(self) -> f64 {
        match self {
            Motion::Swing => 0.6,
            Motion::Twist => 0.3,
        }
    }

    /// Initial velocity at rest position `x` (m/s).
    pub(super) fn velocity(self, x: Vec3) -> Vec3 {
        match self {
            Motion::Swing => [0.0; 3],
            Motion::Twist => {
                let w = 40.0 * (x[0] / LENGTH).max(0.0);
                [0.0, -w * x[2], w * x[1]]
            }
        }
    }

    /// Name for progress lines and errors.
    pub(super) fn name(self) -> &'static str {
        match self {
            Motion::Swing => "swinging bar",
            Motion::Twist => "twisting bar",
        }
    }
}

/// Sample times (evenly spaced over the duration) at which positions are compared.
pub(super) const SAMPLES: usize = 30;

/// A trajectory: positions of the compared points at each sample time.
pub(super) type Trajectory = Vec<Vec<Vec3>>;

/// The corotated P2 reference: its problem and the nodal displacements at each sample time.
pub(super) struct Reference {
    problem: Problem,
    displacements: Vec<Vec<Vec3>>,
    /// Wall time of the run (s).
    pub wall_s: f64,
    steps: u64,
}

impl Reference {
    /// Runs the reference on `nx` cells along at `dt_fraction` of its stable estimate.
    pub(super) fn run(
        motion: Motion,
        nx: usize,
        dt_fraction: f64,
    ) -> Result<Reference, BenchError> {
        let started = Instant::now();
        let case = format!("{} FEM P2 {nx} cells", motion.name());
        let fem = |cause| BenchError::Fem {
            case: case.clone(),
            cause,
        };
        let (e, nu) = motion.young_poisson();
        let problem = clamped_fem_bar(nx, true, e, nu, motion.gravity()).map_err(fem)?;
        // The largest step under the fraction that divides the interval between samples, so
        // each sample is at its time (as the peridynamic runs' are).
        let interval = motion.duration() / SAMPLES as f64;
        let dt = dt_fraction * critical_time_step(&problem, 60);
        let dt = interval / (interval / dt).ceil();
        let nodes = problem.mesh().nodes().to_vec();
        let mut displacements = Vec::with_capacity(SAMPLES);
        let mut steps = 0;
        {
            let mut sim = Dynamic::new(&problem, Kinematics::Corotated, dt).map_err(fem)?;
            for (v, x) in sim.velocities_mut().iter_mut().zip(&nodes) {
                *v = motion.velocity(*x);
            }
            for k in 1..=SAMPLES {
                steps += sim
                    .advance_to(motion.duration() * k as f64 / SAMPLES as f64)
                    .map_err(fem)?;
                displacements.push(
                    sim.positions()
                        .iter()
                        .zip(&nodes)
                        .map(|(y, x)| [y[0] - x[0], y[1] - x[1], y[2] - x[2]])
                        .collect(),
                );
            }
        }
        Ok(Reference {
            problem,
            displacements,
            wall_s: started.elapsed().as_secs_f64(),
            steps,
        })
    }

    /// Positions of the rest points `points` (inside the bar) at each sample time.
    pub(super) fn at(&self, points: &[Vec3]) -> Result<Trajectory, BenchError> {
        let sampler =
            Sampler::new(self.problem.mesh(), points).map_err(|cause| BenchError::Fem {
                case: "sampling the reference".into(),
                cause,
            })?;
        Ok(self
            .displacements
            .iter()
            .map(|u| {
                points
                    .iter()
                    .zip(sampler.interpolate(u))
                    .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
                    .collect()
            })
            .collect())
    }
}

/// Largest distance between two trajectories over points and samples, over the diagonal.
pub(super) fn deviation(a: &Trajectory, b: &Trajectory) -> f64 {
    a.iter()
        .zip(b)
        .map(|(pa, pb)| deviation_at(pa, pb))
        .fold(0.0, f64::max)
}

/// Largest distance between corresponding points of `a` and `b` (m), over the diagonal.
pub(super) fn deviation_at(a: &[Vec3], b: &[Vec3]) -> f64 {
    let mut worst: f64 = 0.0;
    for (x, y) in a.iter().zip(b) {
        let d = ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt();
        worst = worst.max(d);
    }
    worst / diagonal()
}

fn motion_case(
    motion: Motion,
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    // Torsion needs a finer reference than bending: the twisting bar's P2 answer moved by 0.69%
    // of the diagonal from 40 to 80 cells along.
    let (levels, factors, fem_nx): (&[usize], &[f64], usize) = match (effort, motion) {
        (Effort::Tiny, _) => (&[20], &[1.5], 10),
        (Effort::Full, Motion::Swing) => (&[20, 30, 40, 60], &HORIZON_FACTORS, 20),
        (Effort::Full, Motion::Twist) => (&[20, 30, 40, 60], &HORIZON_FACTORS, 40),
    };
    let xu_levels: &[usize] = match effort {
        Effort::Tiny => &[20],
        Effort::Full => &XU_LEVELS,
    };
    // The reference is the finer of two meshes; the coarser one, and a run of it at half the
    // step, bound its error.
    progress(&format!(
        "{}: corotated P2 at {fem_nx} cells along",
        motion.name()
    ));
    let coarse = Reference::run(motion, fem_nx, 0.5)?;
    progress(&format!("{}: the same at half the step", motion.name()));
    let half = Reference::run(motion, fem_nx, 0.25)?;
    let fine_nx = 2 * fem_nx;
    progress(&format!(
        "{}: the reference, at {fine_nx} cells along",
        motion.name()
    ));
    let reference = Reference::run(motion, fine_nx, 0.5)?;
    // Chen's model over the whole sweep, then Xu's explicitly and implicitly at k = 1.5 on the
    // resolutions of the speed-against-error table.
    let mut plan: Vec<(Method, usize, f64)> = Vec::new();
    for &k in factors {
        for &nx in levels {
            plan.push((Method::ChenExplicit, nx, k));
        }
    }
    for method in [
        Method::ChenFitted,
        Method::ChenUnstructured(false),
        Method::ChenUnstructured(true),
    ] {
        for &nx in levels {
            plan.push((method, nx, FITTED_FACTOR));
        }
    }
    for &nx in xu_levels {
        for m in XU_METHODS {
            plan.push((m, nx, XU_FACTOR));
        }
    }
    let mut runs = Vec::new();
    let (mut by_mesh, mut by_step): (f64, f64) = (0.0, 0.0);
    for (method, nx, k) in plan {
        progress(&format!(
            "{}: {} at {nx} cells along, k = {k}",
            motion.name(),
            method.label()
        ));
        let (mut run, points, pd) = method.run(motion, nx, k)?;
        let fem = reference.at(&points)?;
        let coarse_at = coarse.at(&points)?;
        by_mesh = by_mesh.max(deviation(&fem, &coarse_at));
        by_step = by_step.max(deviation(&coarse_at, &half.at(&points)?));
        let dev = deviation(&pd, &fem);
        run.value = dev;
        run.error = dev;
        runs.push(run);
    }
    let ref_cost = (reference.wall_s, reference.steps);
    // Quadratic elements converge at least at second order, so the finer mesh's own error is
    // at most a third of its distance to the coarser one.
    let ref_error = by_mesh / 3.0 + by_step;
    let resolved = runs.iter().filter(|r| ref_error < 0.1 * r.error).count();
    let (table, plot) = table_and_plot(
        &format!("{} against corotated FEM", motion.name()),
        "deviation / diagonal",
        &runs,
    );
    let (e, nu) = motion.young_poisson();
    let (kappa, mu) = motion.moduli();
    let text = format!(
        "A 1 x 0.1 x 0.1 m bar is clamped at x = 0. Its moduli are kappa = {kappa:e} Pa and \
         mu = {mu:e} Pa, so E = {e:.4e} Pa and nu = {nu:.3}. Its density is rho = 1000 kg/m^3. \
         The bar is {}. The run covers {} s of motion. The error is the paper's. It is the \
         largest distance between a particle and the reference at the same rest point. The \
         largest is taken over the bar's particles and {SAMPLES} sample times. It is divided \
         by the diagonal of the bounding box ({:.4} m). The paper reports under 10%. The \
         reference is corotated quadratic tets at {fine_nx} cells along. Its run took {:.1} s \
         and {} steps at half its stable step. At {fem_nx} cells along, the answer differs \
         from it by {:.3}% of the diagonal. Halving the step there moves it by {:.4}%. For \
         second-order elements, the reference's own error is then at most {:.3}%. This is \
         under a tenth of {resolved} of the {} peridynamic deviations, those above {:.2}%. \
         Chen's model is the paper's. It is stepped explicitly on the Kuhn lattice with the \
         scalar calibration, `correction = \"calibrated\"`. The \"fitted\" rows use the \
         fitted dilatation of `correction = \"fitted\"`, the default, at k = 1.5. The \
         \"unstructured\" rows are on the scenes' default box. It is Delaunay tets of \
         well-spaced random points, seed 1. Besides Chen's model, Xu's neo-Hookean-like model \
         runs with the same E and nu (consistent moduli). It runs explicitly. It also runs \
         implicitly at {}, {} and {} steps per 1/24 s frame. That is {}, {} and {} steps over \
         the {} s. The implicit runs use the scene's implicit defaults: tolerance 1e-4 and at \
         most 100 iterations a step. They have no damping but the step's own.",
        match motion {
            Motion::Swing => "released straight under gravity",
            Motion::Twist => "started with an angular velocity about x growing from 0 at the clamp to 40 rad/s at the free end",
        },
        motion.duration(),
        diagonal(),
        ref_cost.0,
        ref_cost.1,
        100.0 * by_mesh,
        100.0 * by_step,
        100.0 * ref_error,
        runs.len(),
        1000.0 * ref_error,
        PER_FRAME[0],
        PER_FRAME[1],
        PER_FRAME[2],
        implicit_steps(motion.duration(), PER_FRAME[0]),
        implicit_steps(motion.duration(), PER_FRAME[1]),
        implicit_steps(motion.duration(), PER_FRAME[2]),
        motion.duration(),
    );
    let tables = vec![(
        "Wall time to simulate the same seconds, against the error".to_string(),
        speed_table(&runs, xu_levels),
    )];
    Ok(CaseReport {
        name: match motion {
            Motion::Swing => "swing".into(),
            Motion::Twist => "twist".into(),
        },
        title: format!(
            "The {} (Figure {})",
            motion.name(),
            match motion {
                Motion::Swing => 11,
                Motion::Twist => 12,
            }
        ),
        text,
        table,
        plot,
        runs,
        tables,
    })
}

/// The runs on the resolutions of `levels` cells along, one row each: method, cells, `k`, wall
/// time, steps, iterations per step (implicit), error.
fn speed_table(runs: &[Run], levels: &[usize]) -> Table {
    let mut t = Table::new(&[
        "method",
        "cells",
        "k",
        "wall time (s)",
        "steps",
        "iterations / step",
        "capped steps",
        "error (deviation / diagonal)",
    ]);
    for &nx in levels {
        let n = cells_across(nx);
        let cells = format!("{nx}x{n}x{n}");
        for r in runs.iter().filter(|r| r.resolution == cells) {
            let (per_step, capped) = match r.implicit {
                Some(st) => (
                    format!("{:.1}", st.iterations as f64 / r.steps.max(1) as f64),
                    st.capped_steps.to_string(),
                ),
                None => ("-".into(), "-".into()),
            };
            t.push(vec![
                r.method.clone(),
                r.resolution.clone(),
                r.horizon_factor.map_or("-".into(), |k| format!("{k:.1}")),
                format!("{:.2}", r.wall_s),
                r.steps.to_string(),
                per_step,
                capped,
                format!("{:.2}%", 100.0 * r.error),
            ]);
        }
    }
    t
}

/// The swinging bar of Figure 11 against corotated FEM.
pub fn swing(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<CaseReport, BenchError> {
    motion_case(Motion::Swing, effort, progress)
}

/// The twisting bar of Figure 12 against corotated FEM.
pub fn twist(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<CaseReport, BenchError> {
    motion_case(Motion::Twist, effort, progress)
}
