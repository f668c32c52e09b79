//! `perifrac bench accuracy`: peridynamic runs against references, over resolution and
//! horizon sweeps, and the thin-shell model against plate and membrane answers. Every case shares geometry, material, loads and boundary conditions with its
//! reference, and every reference is shown converged in its own table.

mod cantilever;
mod ghosts;
mod motion;
mod motion_runs;
mod shells;
mod waves;
mod xu;
mod xu_static;

use std::time::Instant;

use perifrac_fem::{FemError, Material, Mesh, Problem};
use perifrac_physics::{ChenMaterial, SolverStats, Vec3};
use perifrac_topology::primitives::bar_data;

use crate::plot::{Plot, Series};
use crate::table::Table;
use crate::{BenchError, Effort};

pub use cantilever::{cantilever, EULER_BERNOULLI, SCIKIT_FEM, TIMOSHENKO};
pub use ghosts::ghosts;
pub use motion::{swing, twist};
pub use shells::{navier_centre, shell_membrane, shell_plate, shell_strip};
pub use waves::{moduli, wave_speed};
pub use xu::{xu_bend, xu_twist};

/// The horizon factors every peridynamic sweep runs (the 1.0, 1.5, 2.0).
pub const HORIZON_FACTORS: [f64; 3] = [1.0, 1.5, 2.0];

/// Length (m) of the cantilever's and the motion cases' bar.
const LENGTH: f64 = 1.0;
/// Side (m) of every case's square section.
const SIDE: f64 = 0.1;
/// Young's modulus (Pa) of the cantilever's material, which the moduli and wave cases share.
const YOUNG: f64 = 1e8;
/// Poisson's ratio of that material.
const POISSON: f64 = 0.3;
/// Density (kg/m^3) of every case's material.
const DENSITY: f64 = 1000.0;

/// The material of [`YOUNG`], Poisson's ratio `nu` (the cases' [`POISSON`] unless a case
/// sweeps it) and [`DENSITY`]; a refusal is an error of `case`.
fn material(case: &str, nu: f64) -> Result<ChenMaterial, BenchError> {
    ChenMaterial::from_young_poisson(YOUNG, nu, DENSITY).map_err(|cause| BenchError::Physics {
        case: case.into(),
        cause,
    })
}

/// The [`LENGTH`] x [`SIDE`] x [`SIDE`] bar of `nx` cells along in quadratic or linear tets of
/// `young` (Pa), `poisson` and [`DENSITY`], under `gravity` (m/s^2), clamped at x = 0.
fn clamped_fem_bar(
    nx: usize,
    quadratic: bool,
    young: f64,
    poisson: f64,
    gravity: Vec3,
) -> Result<Problem, FemError> {
    let (v, t) = bar_data(LENGTH, [SIDE, SIDE], nx);
    let mesh = if quadratic {
        Mesh::quadratic(v, t)
    } else {
        Mesh::linear(v, t)
    }?;
    let material = Material::new(young, poisson, DENSITY)?;
    let mut problem = Problem::new(mesh, material)?.with_gravity(gravity);
    problem.fix_where(|x| x[0] <= 1e-12);
    Ok(problem)
}

/// One run of one method at one resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// `"PD"`, `"FEM P1"`, `"FEM P2"`, ...
    pub method: String,
    /// Cells, e.g. `"40x4x4"`.
    pub resolution: String,
    /// Horizon factor `k` of a peridynamic run.
    pub horizon_factor: Option<f64>,
    /// Wall time of the run, setup included (s).
    pub wall_s: f64,
    /// Time steps (0 for a static solve).
    pub steps: u64,
    /// Directed bonds (peridynamics) or unknowns (FEM).
    pub size: usize,
    /// The measured quantity, in the case's unit.
    pub value: f64,
    /// Relative error against the case's reference.
    pub error: f64,
    /// The implicit integrator's counters (iterations, evaluations, capped steps, ...) for an
    /// implicit run; `None` otherwise.
    pub implicit: Option<SolverStats>,
}

impl Run {
    /// A peridynamic run (`"PD"`) on `cells` with horizon factor `k`, started at `started`:
    /// its cost, value and error 0 for the caller to set.
    fn peridynamics(cells: [usize; 3], k: f64, started: Instant, steps: u64, bonds: usize) -> Run {
        Run {
            method: "PD".into(),
            resolution: format!("{}x{}x{}", cells[0], cells[1], cells[2]),
            horizon_factor: Some(k),
            wall_s: started.elapsed().as_secs_f64(),
            steps,
            size: bonds,
            value: 0.0,
            error: 0.0,
            implicit: None,
        }
    }
}

/// What a case reports: prose, a table of runs, a plot of error against wall time.
#[derive(Debug, Clone)]
pub struct CaseReport {
    /// Short name, used for file names (`cantilever`).
    pub name: String,
    /// Title for the report.
    pub title: String,
    /// Markdown paragraphs: what is measured, the reference and its convergence.
    pub text: String,
    /// The runs as a table.
    pub table: Table,
    /// The runs as a plot.
    pub plot: Plot,
    /// The runs.
    pub runs: Vec<Run>,
    /// Further tables, each under its heading (speed against error, positions read off).
    pub tables: Vec<(String, Table)>,
}

/// The accuracy cases by name, in report order.
pub const CASES: [&str; 11] = [
    "cantilever",
    "swing",
    "twist",
    "moduli",
    "wave_speed",
    "xu_bend",
    "xu_twist",
    "shell_strip",
    "shell_plate",
    "shell_membrane",
    "ghosts",
];

/// Runs the accuracy cases at `effort` (those named in `only`, or all), telling `progress`
/// what starts.
pub fn run_all(
    effort: Effort,
    only: &[String],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<CaseReport>, BenchError> {
    selected(only)
        .into_iter()
        .map(|name| run_case(name, effort, progress))
        .collect()
}

/// The names of [`CASES`] in `only` (all of them when it is empty), in report order.
pub fn selected(only: &[String]) -> Vec<&'static str> {
    CASES
        .into_iter()
        .filter(|name| only.is_empty() || only.iter().any(|o| o == name))
        .collect()
}

/// Runs the accuracy case `name` (one of [`CASES`]) at `effort`.
pub fn run_case(
    name: &str,
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    match name {
        "cantilever" => cantilever(effort, progress),
        "swing" => swing(effort, progress),
        "twist" => twist(effort, progress),
        "moduli" => moduli(effort, progress),
        "wave_speed" => wave_speed(effort, progress),
        "xu_bend" => xu_bend(effort, progress),
        "xu_twist" => xu_twist(effort, progress),
        "shell_strip" => shell_strip(effort, progress),
        "shell_plate" => shell_plate(effort, progress),
        "shell_membrane" => shell_membrane(effort, progress),
        "ghosts" => ghosts(effort, progress),
        other => Err(BenchError::UnknownCase(other.into())),
    }
}

/// The table and plot of `runs`: one row each; one curve per method (and horizon factor).
pub(crate) fn table_and_plot(title: &str, unit: &str, runs: &[Run]) -> (Table, Plot) {
    let mut table = Table::new(&[
        "method",
        "cells",
        "k",
        "wall time (s)",
        "steps",
        "bonds / unknowns",
        &format!("value ({unit})"),
        "error",
    ]);
    let mut series: Vec<Series> = Vec::new();
    for r in runs {
        table.push(vec![
            r.method.clone(),
            r.resolution.clone(),
            r.horizon_factor.map_or("-".into(), |k| format!("{k:.1}")),
            format!("{:.2}", r.wall_s),
            r.steps.to_string(),
            r.size.to_string(),
            format!("{:.6e}", r.value),
            format!("{:+.2}%", 100.0 * r.error),
        ]);
        let name = match r.horizon_factor {
            Some(k) => format!("{} k = {k:.1}", r.method),
            None => r.method.clone(),
        };
        let point = (r.wall_s, r.error.abs());
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name,
                points: vec![point],
            }),
        }
    }
    let plot = Plot {
        title: format!("{title}: error against wall time"),
        x_label: "wall time (s)".into(),
        y_label: "|relative error|".into(),
        series,
    };
    (table, plot)
}
