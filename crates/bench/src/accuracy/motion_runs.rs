//! The peridynamic runs of the swinging and twisting bars: Chen's model and Xu's stepped
//! explicitly (velocity Verlet at 0.8 of the stable step), and Xu's stepped implicitly at 1, 4
//! or 16 steps per 1/24 s frame, each on the same clamped bar and giving its trajectory at the
//! case's sample times.
//!
//! Xu's material is the case's (Table 1's kappa, mu as E, nu) with the neo-Hookean-like
//! curves and the consistent moduli: the reference is linear (corotated) elasticity, and at
//! these strains (under 1%) every curve with `f''(1) = 2` is the same material.

use std::time::Instant;

use perifrac_physics::{
    GhostFit, Implicit, ImplicitConfig, Loads, Solver, Vec3, XuMaterial, XuModel,
};

use super::cantilever::{bar_planes, Clamp};
use super::motion::{Motion, Trajectory, SAMPLES};
use super::{Run, DENSITY, LENGTH, SIDE};
use crate::bar::{
    cells_across, clamped_bar, rest_of, set_velocities, xu_neo_hookean, Cut, FittedChen,
    GhostedChen, PdMaterial, KUHN, UNSTRUCTURED_SEED,
};
use crate::BenchError;

/// Frames per second of the implicit runs' frame (the steps per frame count against it).
pub(super) const FRAME_RATE: f64 = 24.0;

/// How a run integrates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Method {
    /// Chen's model, velocity Verlet (the paper's method).
    ChenExplicit,
    /// Chen's model with the fitted dilatation (`correction = "fitted"`), velocity Verlet.
    ChenFitted,
    /// Chen's model on unstructured tets (the scenes' default box, seed 1), calibrated
    /// (`false`) or fitted (`true`), velocity Verlet.
    ChenUnstructured(bool),
    /// Chen's model with the fitted dilatation over families completed by ghosts across the
    /// bar's four side faces (`perifrac_physics::ghost`), on unstructured tets, velocity
    /// Verlet: the `ghosts` case's runs, not the motion cases'.
    ChenGhosts(GhostFit),
    /// Xu's model, velocity Verlet.
    XuExplicit,
    /// Xu's model, the implicit quasi-Newton step, this many steps per frame.
    XuImplicit(u32),
}

impl Method {
    /// The label in tables and plots.
    pub(super) fn label(self) -> String {
        match self {
            Method::ChenExplicit => "PD Chen explicit".into(),
            Method::ChenFitted => "PD Chen fitted explicit".into(),
            Method::ChenUnstructured(false) => "PD Chen explicit unstructured".into(),
            Method::ChenUnstructured(true) => "PD Chen fitted explicit unstructured".into(),
            Method::ChenGhosts(GhostFit::Affine) => "PD Chen affine ghosts explicit".into(),
            Method::ChenGhosts(GhostFit::Quadratic) => "PD Chen quadratic ghosts explicit".into(),
            Method::XuExplicit => "PD Xu explicit".into(),
            Method::XuImplicit(n) => format!("PD Xu implicit {n}/frame"),
        }
    }

    /// The run on `nx` cells along with horizon factor `k`: its cost, the rest positions of
    /// the compared particles (those of the bar proper, x > 0) and their trajectory.
    pub(super) fn run(
        self,
        motion: Motion,
        nx: usize,
        k: f64,
    ) -> Result<(Run, Vec<Vec3>, Trajectory), BenchError> {
        match self {
            Method::ChenExplicit => explicit(motion, nx, k, &motion.material(), self, KUHN),
            Method::ChenFitted => {
                explicit(motion, nx, k, &FittedChen(motion.material()), self, KUHN)
            }
            Method::ChenUnstructured(false) => {
                explicit(motion, nx, k, &motion.material(), self, UNSTRUCTURED)
            }
            Method::ChenUnstructured(true) => {
                let m = FittedChen(motion.material());
                explicit(motion, nx, k, &m, self, UNSTRUCTURED)
            }
            Method::ChenGhosts(fit) => {
                let m = GhostedChen {
                    material: motion.material(),
                    planes: bar_planes(Clamp::Held),
                    fit,
                };
                explicit(motion, nx, k, &m, self, UNSTRUCTURED)
            }
            Method::XuExplicit => explicit(motion, nx, k, &xu_material(motion)?, self, KUHN),
            Method::XuImplicit(per_frame) => implicit(motion, nx, k, per_frame),
        }
    }
}

/// Xu's neo-Hookean-like material with the case's E and nu (consistent moduli).
fn xu_material(motion: Motion) -> Result<XuMaterial, BenchError> {
    let (e, nu) = motion.young_poisson();
    xu_neo_hookean(&format!("{} Xu material", motion.name()), e, nu, DENSITY)
}

/// The case name of a run, for errors.
fn case_name(motion: Motion, method: Method, nx: usize, k: f64) -> String {
    let n = cells_across(nx);
    format!("{} {} {nx}x{n}x{n} k={k}", motion.name(), method.label())
}

/// Unstructured tets (the scenes' default box).
const UNSTRUCTURED: Cut = Cut::Unstructured(UNSTRUCTURED_SEED);

/// Velocity Verlet on `material` and the mesh `cut`, at the largest step under 0.8 of the
/// stable one that divides the interval between samples (so every sample is at its time).
fn explicit<T: PdMaterial>(
    motion: Motion,
    nx: usize,
    k: f64,
    material: &T,
    method: Method,
    cut: Cut,
) -> Result<(Run, Vec<Vec3>, Trajectory), BenchError> {
    let started = Instant::now();
    let n = cells_across(nx);
    let case = case_name(motion, method, nx, k);
    let physics = |cause| BenchError::Physics {
        case: case.clone(),
        cause,
    };
    let (b, held) = clamped_bar(&case, LENGTH, SIDE, nx, k, material, cut)?;
    let bonds = b.bonds();
    let tracked: Vec<u32> = b.select(|x| x[0] > 0.0);
    let mut loads = Loads::new(b.rest().len()).with_gravity(motion.gravity());
    loads.anchor(&held, [0.0; 3]).map_err(physics)?;
    let interval = motion.duration() / SAMPLES as f64;
    let mut s = b.solver_dividing(&case, loads, interval)?;
    // The clamp layer behind x = 0 starts, and stays, at rest.
    set_velocities(&mut s, |x| {
        if x[0] > 0.0 {
            motion.velocity(x)
        } else {
            [0.0; 3]
        }
    });
    let per_sample = (interval / s.dt()).round() as u64;
    let mut out = Vec::with_capacity(SAMPLES);
    for _ in 0..SAMPLES {
        for _ in 0..per_sample {
            s.step().map_err(physics)?;
        }
        let y = s.positions();
        out.push(tracked.iter().map(|&i| y[i as usize]).collect());
    }
    let rest = rest_of(&s);
    let points = tracked.iter().map(|&i| rest[i as usize]).collect();
    let run = Run {
        method: method.label(),
        ..Run::peridynamics([nx, n, n], k, started, per_sample * SAMPLES as u64, bonds)
    };
    Ok((run, points, out))
}

/// Steps of the implicit runs over `duration` (s) at `per_frame` steps per 1/24 s frame: the
/// whole number nearest `duration * 24 * per_frame` (the step then divides the duration).
pub(super) fn implicit_steps(duration: f64, per_frame: u32) -> u64 {
    ((duration * FRAME_RATE * per_frame as f64).round() as u64).max(1)
}

/// Xu's model stepped implicitly at `per_frame` steps per frame (the scene's defaults:
/// tolerance 1e-4, at most 100 iterations a step). Its positions move linearly in time over a
/// step (`v_{n+1} = (q_{n+1} - q_n) / dt`), so between steps they are interpolated linearly to
/// the sample times.
fn implicit(
    motion: Motion,
    nx: usize,
    k: f64,
    per_frame: u32,
) -> Result<(Run, Vec<Vec3>, Trajectory), BenchError> {
    let started = Instant::now();
    let method = Method::XuImplicit(per_frame);
    let n = cells_across(nx);
    let case = case_name(motion, method, nx, k);
    let physics = |cause| BenchError::Physics {
        case: case.clone(),
        cause,
    };
    let (b, held) = clamped_bar(&case, LENGTH, SIDE, nx, k, &xu_material(motion)?, KUHN)?;
    let bonds = b.bonds();
    let tracked: Vec<u32> = b.select(|x| x[0] > 0.0);
    let mut loads = Loads::new(b.rest().len()).with_gravity(motion.gravity());
    loads.anchor(&held, [0.0; 3]).map_err(physics)?;
    let steps = implicit_steps(motion.duration(), per_frame);
    let dt = motion.duration() / steps as f64;
    let mut s: Implicit<XuModel> = b.implicit(&case, loads, ImplicitConfig::with_dt(dt))?;
    set_velocities(&mut s, |x| {
        if x[0] > 0.0 {
            motion.velocity(x)
        } else {
            [0.0; 3]
        }
    });
    let pick = |y: &[Vec3]| -> Vec<Vec3> { tracked.iter().map(|&i| y[i as usize]).collect() };
    let mut before = pick(s.positions());
    let mut after = before.clone();
    let mut out = Vec::with_capacity(SAMPLES);
    let mut taken = 0u64;
    for sample in 1..=SAMPLES {
        let at = motion.duration() * sample as f64 / SAMPLES as f64;
        // step until the step's end reaches the sample time (to rounding)
        while (taken as f64) * dt < at - 1e-9 * dt && taken < steps {
            before = after;
            s.step().map_err(physics)?;
            taken += 1;
            after = pick(s.positions());
        }
        let w = ((at - (taken as f64 - 1.0) * dt) / dt).clamp(0.0, 1.0);
        out.push(
            before
                .iter()
                .zip(&after)
                .map(|(p, q)| std::array::from_fn(|d| p[d] + w * (q[d] - p[d])))
                .collect(),
        );
    }
    let rest = rest_of(&s);
    let points = tracked.iter().map(|&i| rest[i as usize]).collect();
    let run = Run {
        method: method.label(),
        implicit: Some(Solver::stats(&s)),
        ..Run::peridynamics([nx, n, n], k, started, taken, bonds)
    };
    Ok((run, points, out))
}
