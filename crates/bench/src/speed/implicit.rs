//! The implicit step's speed: a body of about 6,000 particles (18,000 unknowns) of Xu's
//! neo-Hookean-like material on a fixed base, dropped under gravity and stepped implicitly at
//! one step per 1/24 s frame; where a step's time goes (objective evaluations, triangular
//! solves, the rest of L-BFGS and the line search), the factorisation apart, on one thread and
//! on all of them.
//!
//! The body is the Stanford armadillo of `../shared/data/meshes/armadillo.obj` (about 1 m tall,
//! up along +y), meshed by the built-in mesher at 19 lattice cells across its longest side,
//! when the file is there; otherwise a 10 x 10 x 10-cell cube of 0.5 m (6,000 tets).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use perifrac_physics::{
    ForceModel, Implicit, ImplicitConfig, Loads, QuasiNewtonModel, Solver, Vec3, XuModel,
};
use perifrac_topology::mesher::{mesh_surface, MesherOptions};
use perifrac_topology::primitives::box_data;

use super::one_thread;
use crate::bar::{mesh_body, tet_mesh, xu_neo_hookean, Body};
use crate::table::Table;
use crate::{BenchError, Effort};

/// The step (s): one 24 fps frame.
const DT: f64 = 1.0 / 24.0;
/// Young's modulus (Pa), Poisson's ratio and density (kg/m^3): a soft rubber that sags
/// visibly under its own weight.
const YOUNG: f64 = 1e5;
const POISSON: f64 = 0.3;
const DENSITY: f64 = 1000.0;
/// Horizon factor.
const HORIZON_FACTOR: f64 = 1.5;
/// Lattice cells across the armadillo's longest side (about 6,000 tets).
const ARMADILLO_RESOLUTION: usize = 19;
/// The target (s per step on 2 cores) and the paper's time for its 18k-DOF body (s).
const TARGET_S: f64 = 0.1;
const PAPER_S: f64 = 0.323;
/// Evaluations timed on their own, the median reported.
const TIMED_EVALUATIONS: usize = 9;

/// The armadillo's surface, found from this crate's directory (the workspace's `../shared`).
fn armadillo_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes/armadillo.obj")
}

/// The body, a name for it, its base particles (held fixed) and gravity (m/s^2).
fn body(effort: Effort, case: &str) -> Result<(Body<XuModel>, String, Vec<u32>, Vec3), BenchError> {
    let material = xu_neo_hookean(case, YOUNG, POISSON, DENSITY)?;
    let path = armadillo_path();
    if effort == Effort::Full && path.is_file() {
        let mesh_err = |message: String| BenchError::Mesh {
            case: case.into(),
            message,
        };
        let s = perifrac_io::read_surface(&path).map_err(|e| mesh_err(e.to_string()))?;
        let opts = MesherOptions {
            edge_length: None,
            resolution: Some(ARMADILLO_RESOLUTION),
        };
        let out =
            mesh_surface(&s.vertices, &s.faces, &opts).map_err(|e| mesh_err(e.to_string()))?;
        let mesh = tet_mesh(case, out.vertices, out.tets)?;
        let b = mesh_body(case, &mesh, HORIZON_FACTOR, &material)?;
        // the feet: the lowest 5% of the height (up is +y)
        let (lo, hi) = b
            .rest()
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(x[1]), hi.max(x[1]))
            });
        let base = b.select(|x| x[1] < lo + 0.05 * (hi - lo));
        let name = format!("armadillo, resolution {ARMADILLO_RESOLUTION}");
        return Ok((b, name, base, [0.0, -9.81, 0.0]));
    }
    let n = match effort {
        Effort::Tiny => 5,
        Effort::Full => 10,
    };
    let (v, t) = box_data([0.0; 3], [0.5; 3], [n; 3]);
    let mesh = tet_mesh(case, v, t)?;
    let b = mesh_body(case, &mesh, HORIZON_FACTOR, &material)?;
    let base = b.select(|x| x[2] < 0.5 / n as f64);
    Ok((
        b,
        format!("cube, {n}x{n}x{n} cells"),
        base,
        [0.0, 0.0, -9.81],
    ))
}

/// What one timed run measured.
struct Measured {
    particles: usize,
    bonds: usize,
    name: String,
    step: Duration,
    steps: u64,
    evaluation: Duration,
    stats: perifrac_physics::SolverStats,
    /// Wall time of all steps (s).
    stepping: f64,
}

/// Builds the body, steps it `steps` times and times each step and some evaluations.
fn measure(effort: Effort, steps: u64) -> Result<Measured, BenchError> {
    let case = "speed implicit step";
    let physics = |cause| BenchError::Physics {
        case: case.into(),
        cause,
    };
    let (b, name, base, gravity) = body(effort, case)?;
    let (particles, bonds) = (b.rest().len(), b.bonds());
    let mut loads = Loads::new(particles).with_gravity(gravity);
    loads.anchor(&base, [0.0; 3]).map_err(physics)?;
    let mut s: Implicit<XuModel> = b.implicit(case, loads, ImplicitConfig::with_dt(DT))?;
    let mut times = Vec::with_capacity(steps as usize);
    let started = Instant::now();
    for _ in 0..steps {
        let t = Instant::now();
        s.step().map_err(physics)?;
        times.push(t.elapsed());
    }
    let stepping = started.elapsed().as_secs_f64();
    let stats = Solver::stats(&s);
    let y = s.positions().to_vec();
    let mut forces = vec![[0.0; 3]; y.len()];
    let mut evals = Vec::with_capacity(TIMED_EVALUATIONS);
    for _ in 0..TIMED_EVALUATIONS {
        let t = Instant::now();
        std::hint::black_box(s.model_mut().energy_and_forces(&y, &mut forces));
        evals.push(t.elapsed());
    }
    debug_assert!(s.model().num_particles() == particles);
    Ok(Measured {
        particles,
        bonds,
        name,
        step: median(&mut times),
        steps,
        evaluation: median(&mut evals),
        stats,
        stepping,
    })
}

fn median(v: &mut [Duration]) -> Duration {
    v.sort();
    v.get(v.len() / 2).copied().unwrap_or_default()
}

/// Seconds per implicit step of the body, on one thread and on the global pool, with the
/// iterations, evaluations and solves per step, the time of each, the factorisation and the
/// factor's memory.
pub fn implicit_step(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let steps: u64 = match effort {
        Effort::Tiny => 3,
        Effort::Full => 24,
    };
    let threads = rayon::current_num_threads();
    let mut t = Table::new(&[
        "body",
        "particles",
        "bonds",
        "threads",
        "s/step (median)",
        "iterations/step",
        "evaluations/step",
        "ms/evaluation",
        "ms/solve",
        "evaluations, solves: share of the steps",
        "factorisation (s)",
        "factor memory (MB)",
        "target 0.1 s/step (2 cores); paper 0.323 s",
    ]);
    for count in [1, threads] {
        progress(&format!(
            "speed: implicit steps on {count} thread(s), {steps} steps of 1/24 s"
        ));
        let m = if count == 1 {
            one_thread(move || measure(effort, steps))??
        } else {
            measure(effort, steps)?
        };
        let st = m.stats;
        let n = m.steps.max(1) as f64;
        let eval_s = m.evaluation.as_secs_f64();
        let solve_s = st.solve_seconds / st.solves.max(1) as f64;
        let stepping = m.stepping.max(f64::MIN_POSITIVE);
        let per_step = m.step.as_secs_f64();
        t.push(vec![
            m.name.clone(),
            m.particles.to_string(),
            m.bonds.to_string(),
            count.to_string(),
            format!("{per_step:.4}"),
            format!("{:.1}", st.iterations as f64 / n),
            format!("{:.1}", st.evaluations as f64 / n),
            format!("{:.2}", 1e3 * eval_s),
            format!("{:.3}", 1e3 * solve_s),
            format!(
                "{:.0}%, {:.0}%",
                100.0 * eval_s * st.evaluations as f64 / stepping,
                100.0 * st.solve_seconds / stepping
            ),
            format!(
                "{:.3} ({} factorisation(s))",
                st.factor_seconds / st.factorizations.max(1) as f64,
                st.factorizations
            ),
            format!("{:.1}", st.factor_bytes as f64 / 1e6),
            format!(
                "{:.2} x target, {:.2} x paper",
                per_step / TARGET_S,
                per_step / PAPER_S
            ),
        ]);
    }
    Ok(t)
}
