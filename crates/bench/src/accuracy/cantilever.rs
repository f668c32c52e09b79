//! The cantilever under gravity: a 1 x 0.1 x 0.1 m bar, E = 1e8 Pa, nu = 0.3,
//! rho = 1000 kg/m^3, g = 9.81 m/s^2 along -z, the face x = 0 clamped; the static deflection of
//! the centre of the free end.
//!
//! Peridynamics has no static solver here, so it relaxes dynamically: critical damping of the
//! first bending mode, run for twelve of its time constants; the clamp is a layer of particles
//! at least one horizon thick behind x = 0, held fixed. The references are closed forms
//! (Euler-Bernoulli, Timoshenko), the 3D answer of scikit-fem quoted in issue 6, and the
//! project's own quadratic tets (P2) refined until the last refinement moves the tip by less
//! than a tenth of the smallest peridynamic error; linear tets (P1) are run to show them lock.

use std::time::Instant;

use perifrac_fem::{static_linear, Sampler};
use perifrac_physics::{Explicit, FaceKind, GhostPlane, GhostReport, Loads};

use super::{
    clamped_fem_bar, material, table_and_plot, CaseReport, Run, DENSITY, HORIZON_FACTORS, LENGTH,
    POISSON, SIDE, YOUNG,
};
use crate::bar::{
    cells_across, clamped_bar, cut_body, fit_line, rest_of, Cut, FittedChen, PdMaterial, KUHN,
    UNSTRUCTURED_SEED,
};
use crate::table::Table;
use crate::{BenchError, Effort};
use perifrac_topology::primitives::Lattice;

const GRAVITY: f64 = 9.81;
/// Euler-Bernoulli tip deflection `q L^4 / (8 E I)` (m), quoted in issue 6.
pub const EULER_BERNOULLI: f64 = 0.014715;
/// Timoshenko tip deflection (m), quoted in issue 6.
pub const TIMOSHENKO: f64 = 0.014865;
/// Converged 3D linear elasticity (quadratic tets, scikit-fem), quoted in issue 6 (m).
pub const SCIKIT_FEM: f64 = 0.014728;

/// First bending frequency of the clamped bar, Euler-Bernoulli (rad/s).
pub(crate) fn omega1() -> f64 {
    let i = SIDE.powi(4) / 12.0;
    1.875104f64.powi(2) * (YOUNG * i / (DENSITY * SIDE * SIDE * LENGTH.powi(4))).sqrt()
}

/// The name of a peridynamic series: the correction and the mesh.
fn series(fitted: bool, cut: Cut) -> String {
    let mesh = match cut {
        Cut::Lattice(Lattice::Kuhn) => "",
        Cut::Lattice(Lattice::Mirrored) => " mirrored",
        Cut::Unstructured(_) => " unstructured",
    };
    format!("PD{}{mesh}", if fitted { " fitted" } else { "" })
}

/// Tip deflection (m) by peridynamics with `nx` cells along the bar and horizon factor `k`
/// (with the fitted dilatation when `fitted`) on the mesh `cut`, the relative change over the
/// last tenth of the relaxation and the tip's sideways deflection over its vertical one.
fn peridynamics(nx: usize, k: f64, fitted: bool, cut: Cut) -> Result<(Run, f64, f64), BenchError> {
    let n = cells_across(nx);
    let case = format!("cantilever PD {nx}x{n}x{n} k={k}");
    let m = material(&case, POISSON)?;
    let method = series(fitted, cut);
    let (run, moved, sideways, _) = if fitted {
        relax(nx, k, &FittedChen(m), cut, Clamp::Held, method)?
    } else {
        relax(nx, k, &m, cut, Clamp::Held, method)?
    };
    Ok((run, moved, sideways))
}

/// How the bar is held at x = 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Clamp {
    /// A layer of held particles at least one horizon thick behind x = 0 (the benchmark's).
    Held,
    /// No layer: the model mirrors the bar across x = 0 (a clamped ghost face,
    /// `perifrac_physics::FaceKind::Clamped`), so nothing is held.
    Mirror,
}

/// The bar's side faces (free) and, with [`Clamp::Mirror`], the face x = 0 (clamped): the
/// planes of a ghosted model of it.
pub(crate) fn bar_planes(clamp: Clamp) -> Vec<GhostPlane> {
    let h = SIDE / 2.0;
    let faces = GhostPlane::box_faces([0.0, -h, -h], [LENGTH, h, h]);
    let mut planes = faces[2..].to_vec();
    if clamp == Clamp::Mirror {
        planes.push(GhostPlane {
            kind: FaceKind::Clamped,
            ..faces[0]
        });
    }
    planes
}

/// [`peridynamics`] for any material, held as `clamp` says; the run is named `method`. With
/// the three figures, what the build of the model's ghosts found, when it has them.
pub(crate) fn relax<T: PdMaterial>(
    nx: usize,
    k: f64,
    material: &T,
    cut: Cut,
    clamp: Clamp,
    method: String,
) -> Result<(Run, f64, f64, Option<GhostReport>), BenchError> {
    let started = Instant::now();
    let n = cells_across(nx);
    let h = LENGTH / nx as f64;
    let case = format!("cantilever PD {nx}x{n}x{n} k={k}");
    let (b, held) = match clamp {
        Clamp::Held => clamped_bar(&case, LENGTH, SIDE, nx, k, material, cut)?,
        Clamp::Mirror => {
            let (lo, hi) = (
                [0.0, -SIDE / 2.0, -SIDE / 2.0],
                [LENGTH, SIDE / 2.0, SIDE / 2.0],
            );
            (
                cut_body(&case, lo, hi, [nx, n, n], k, material, cut)?,
                Vec::new(),
            )
        }
    };
    let bonds = b.bonds();
    let ghosts = T::ghosts(&b.model);
    let tip = b.select(|x| x[0] > LENGTH - 2.0 * h);
    let w1 = omega1();
    let physics = |cause| BenchError::Physics {
        case: case.clone(),
        cause,
    };
    let mut loads = Loads::new(b.rest().len())
        .with_gravity([0.0, 0.0, -GRAVITY])
        .with_damping(2.0 * w1)
        .map_err(physics)?;
    loads.anchor(&held, [0.0; 3]).map_err(physics)?;
    let mut s = b.solver(&case, loads)?;
    let steps = (12.0 / w1 / s.dt()).ceil() as u64;
    // The tip's displacement along `axis`, from a line fitted along the last two cells.
    let tip_at = |s: &Explicit<T::Model>, axis: usize| {
        let (y, rest) = (s.positions(), rest_of(s));
        let x: Vec<f64> = tip.iter().map(|&i| rest[i as usize][0]).collect();
        let u: Vec<f64> = tip
            .iter()
            .map(|&i| y[i as usize][axis] - rest[i as usize][axis])
            .collect();
        let (a, slope) = fit_line(&x, &u);
        a + slope * LENGTH
    };
    let deflection = |s: &Explicit<T::Model>| -tip_at(s, 2);
    let mut at_90 = 0.0;
    for step in 0..steps {
        s.step().map_err(physics)?;
        if step + 1 == steps * 9 / 10 {
            at_90 = deflection(&s);
        }
    }
    let value = deflection(&s);
    let sideways = tip_at(&s, 1).abs() / value;
    let run = Run {
        method,
        value,
        ..Run::peridynamics([nx, n, n], k, started, steps, bonds)
    };
    Ok((run, (value - at_90).abs() / value, sideways, ghosts))
}

/// Tip deflection (m) by linear elasticity on `nx` cells along the bar, P1 or P2.
fn finite_elements(nx: usize, quadratic: bool) -> Result<Run, BenchError> {
    let started = Instant::now();
    let n = cells_across(nx);
    let case = format!("cantilever FEM {nx}x{n}x{n}");
    let fem = |cause| BenchError::Fem {
        case: case.clone(),
        cause,
    };
    let problem =
        clamped_fem_bar(nx, quadratic, YOUNG, POISSON, [0.0, 0.0, -GRAVITY]).map_err(fem)?;
    let solution = static_linear(&problem).map_err(fem)?;
    let sampler = Sampler::new(problem.mesh(), &[[LENGTH, 0.0, 0.0]]).map_err(fem)?;
    let u = sampler.interpolate(&solution.displacements)[0];
    Ok(Run {
        method: if quadratic { "FEM P2" } else { "FEM P1" }.into(),
        resolution: format!("{nx}x{n}x{n}"),
        horizon_factor: None,
        wall_s: started.elapsed().as_secs_f64(),
        steps: 0,
        size: 3 * problem.mesh().node_count(),
        value: -u[2],
        error: 0.0,
        implicit: None,
    })
}

/// The cantilever case: P2 reference refined to convergence, P1 for contrast, peridynamics
/// over the resolution and horizon sweep.
pub fn cantilever(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    let (p2_levels, p1_levels, pd_levels, factors): (&[usize], &[usize], &[usize], &[f64]) =
        match effort {
            Effort::Tiny => (&[10, 20], &[20], &[20, 30], &[1.5]),
            Effort::Full => (
                &[10, 20, 40, 80],
                &[20, 40, 80],
                &[20, 30, 40, 60],
                &HORIZON_FACTORS,
            ),
        };
    let mut runs = Vec::new();
    for &nx in p2_levels {
        progress(&format!("cantilever: FEM P2 at {nx} cells along"));
        runs.push(finite_elements(nx, true)?);
    }
    let reference = runs.last().map_or(SCIKIT_FEM, |r| r.value);
    let moved = match &runs[..] {
        [.., a, b] => (b.value - a.value).abs() / b.value,
        _ => f64::NAN,
    };
    for &nx in p1_levels {
        progress(&format!("cantilever: FEM P1 at {nx} cells along"));
        runs.push(finite_elements(nx, false)?);
    }
    let mut residual: f64 = 0.0;
    // (k, fitted, mesh): the scalar calibration at every factor, then at 1.5 the fitted
    // dilatation and both on the mirrored lattice and on unstructured tets
    let mirrored = Cut::Lattice(Lattice::Mirrored);
    let unstructured = Cut::Unstructured(UNSTRUCTURED_SEED);
    let variants: Vec<(f64, bool, Cut)> = factors
        .iter()
        .map(|&k| (k, false, KUHN))
        .chain([
            (1.5, true, KUHN),
            (1.5, false, mirrored),
            (1.5, true, mirrored),
            (1.5, false, unstructured),
            (1.5, true, unstructured),
        ])
        .collect();
    let mut sideways = Vec::new();
    for &(k, fitted, cut) in &variants {
        for &nx in pd_levels {
            progress(&format!(
                "cantilever: {} at {nx} cells along, k = {k}",
                series(fitted, cut)
            ));
            let (run, r, side) = peridynamics(nx, k, fitted, cut)?;
            residual = residual.max(r);
            sideways.push(side);
            runs.push(run);
        }
    }
    for r in &mut runs {
        r.error = r.value / reference - 1.0;
    }
    let pd: Vec<&Run> = runs.iter().filter(|r| r.method.starts_with("PD")).collect();
    let pd_errors: Vec<f64> = pd.iter().map(|r| r.error.abs()).collect();
    // Observed order of each peridynamic series between successive resolutions (cells along
    // over 20 is the refinement), and the tip's sideways deflection.
    let mut convergence = Table::new(&[
        "method",
        "cells",
        "k",
        "error",
        "observed order",
        "sideways / vertical tip deflection",
    ]);
    // cells along, from the resolution "NXxNxN"
    let cells = |run: &Run| {
        run.resolution
            .split('x')
            .next()
            .and_then(|c| c.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    for (i, r) in pd.iter().enumerate() {
        let prev = i
            .checked_sub(1)
            .map(|j| pd[j])
            .filter(|p| p.method == r.method && p.horizon_factor == r.horizon_factor);
        let order = match prev {
            Some(p) if p.error != 0.0 && r.error != 0.0 => format!(
                "{:.2}",
                (p.error.abs() / r.error.abs()).ln() / (cells(r) / cells(p)).ln()
            ),
            _ => "-".into(),
        };
        convergence.push(vec![
            r.method.clone(),
            r.resolution.clone(),
            r.horizon_factor.map_or("-".into(), |k| format!("{k:.1}")),
            format!("{:+.2}%", 100.0 * r.error),
            order,
            format!("{:.2}%", 100.0 * sideways[i]),
        ]);
    }
    let resolved = pd_errors.iter().filter(|&&e| moved < 0.1 * e).count();
    let (table, plot) = table_and_plot("Cantilever under gravity", "m", &runs);
    let finest = p2_levels.last().copied().unwrap_or(0);
    let text = format!(
        "This case measures the static deflection of the centre of the free end of a \
         1 x 0.1 x 0.1 m bar. The bar has E = 1e8 Pa, nu = 0.3 and rho = 1000 kg/m^3. Gravity \
         is g = 9.81 m/s^2 along -z. The bar is clamped at x = 0. Errors are against the \
         project's own reference: quadratic tets (P2) at {finest} cells along. That reference \
         gives {reference:.6} m. This is {:+.3}% from the converged 3D answer of scikit-fem \
         ({SCIKIT_FEM} m). Euler-Bernoulli gives {EULER_BERNOULLI} m, and Timoshenko gives \
         {TIMOSHENKO} m. The reference's last refinement moved the tip by {:.3}%. This is \
         under a tenth of {resolved} of the {} peridynamic errors, those above {:.2}%. For \
         those errors, the reference is converged at the scale of what it measures. Linear \
         tets (P1) lock in bending. Peridynamics relaxes dynamically. The damping is critical \
         for the first bending mode, and the relaxation lasts 12 time constants. A clamp layer \
         one horizon thick lies behind x = 0. The tip moved by at most {:.1e} of itself over \
         the last tenth of the relaxation. \"PD\" rows scale each particle's constants to its \
         family. This is `correction = \"calibrated\"`, the default before issue 18. \
         \"PD fitted\" rows fit each particle's dilatation weights to read every homogeneous \
         strain exactly. This is `correction = \"fitted\"`, the default (docs/DECISIONS.md). \
         Rows without a mesh named are on the Kuhn lattice, where every cell is the same six \
         tets. In \"mirrored\" rows, every other cell along each axis is cut as the mirror \
         image of its neighbour (`structure = \"mirrored\"`). The \"unstructured\" rows are \
         on the scenes' default mesh. It is Delaunay tets of well-spaced random points, seed \
         {UNSTRUCTURED_SEED}, with as many tets. The second table gives each series' observed \
         order. This is the error's log ratio over the refinement's. The table also gives the \
         tip's sideways deflection over its vertical one. The Kuhn lattice has no mirror \
         symmetry across the bar. The mirrored one has it at an even count of cells across.",
        100.0 * (reference / SCIKIT_FEM - 1.0),
        100.0 * moved,
        pd_errors.len(),
        1000.0 * moved,
        residual,
    );
    Ok(CaseReport {
        name: "cantilever".into(),
        title: "Cantilever under gravity".into(),
        text,
        table,
        plot,
        runs,
        tables: vec![("Convergence and sideways deflection".into(), convergence)],
    })
}
