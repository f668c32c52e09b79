//! Elastic constants as the particles see them: Young's modulus and Poisson's ratio measured in
//! uniaxial tension, and the speed of a pulse along a free bar. The material is the
//! cantilever's (E = 1e8 Pa, nu = 0.3, rho = 1000 kg/m^3); the references are exact: a bar in
//! uniaxial tension has a uniform strain away from its ends, and a pulse much longer than the
//! section travels at `sqrt(E / rho)` (Rayleigh-Love: slower by `nu^2 k^2 r_g^2 / 2`, 0.12% for
//! this pulse).

use std::time::Instant;

use perifrac_physics::{ChenModel, Explicit, GhostReport, Loads};

use super::{
    material, table_and_plot, CaseReport, Run, DENSITY, HORIZON_FACTORS, POISSON, SIDE, YOUNG,
};
use crate::bar::{
    cut_body, fit_line, rest_of, set_velocities, Body, Cut, FittedChen, PdMaterial, KUHN,
    UNSTRUCTURED_SEED,
};
use crate::table::Table;
use crate::{BenchError, Effort};

/// A `len` x 0.1 x 0.1 m bar of the cases' material from the origin (Poisson's ratio `nu`),
/// `nx` cells along and `nx / per_cell_across` across, cut as `cut` says.
// The bar's shape, resolution, horizon, correction, material and mesh are each a run's own.
#[allow(clippy::too_many_arguments)]
fn bar(
    case: &str,
    len: f64,
    nx: usize,
    per_cell_across: usize,
    k: f64,
    fitted: bool,
    nu: f64,
    cut: Cut,
) -> Result<Body, BenchError> {
    let n = (nx / per_cell_across).max(1);
    let m = material(case, nu)?;
    let size = [len, SIDE, SIDE];
    if fitted {
        cut_body(case, [0.0; 3], size, [nx, n, n], k, &FittedChen(m), cut)
    } else {
        cut_body(case, [0.0; 3], size, [nx, n, n], k, &m, cut)
    }
}

/// Measured `(E / E0, nu)`, the run's cost and the horizon (m): a 0.4 x 0.1 x 0.1 m bar of
/// `nx` cells along, both end layers (one horizon deep) anchored, one pulled to 0.1% strain,
/// relaxed with
/// critical damping of the first axial mode over 40 of its time constants. Strains are fitted
/// over the middle third; the stress is the pulled anchor's reaction over the section. `nu`
/// is the material's Poisson's ratio (E is the cases' [`YOUNG`]); `cut` the bar's mesh.
fn tension(
    nx: usize,
    k: f64,
    fitted: bool,
    nu: f64,
    cut: Cut,
) -> Result<(f64, f64, Run, f64), BenchError> {
    let case = format!("tension PD {nx}x{n}x{n} k={k} nu={nu}", n = (nx / 4).max(1));
    let m = material(&case, nu)?;
    let (e, nu, run, delta, _) = if fitted {
        tension_of(nx, k, &FittedChen(m), nu, cut)?
    } else {
        tension_of(nx, k, &m, nu, cut)?
    };
    Ok((e, nu, run, delta))
}

/// [`tension`] for any material (`nu` its Poisson's ratio, for the starting guess), with what
/// the build of the model's ghosts found, when it has them.
pub(crate) fn tension_of<T: PdMaterial>(
    nx: usize,
    k: f64,
    material: &T,
    nu: f64,
    cut: Cut,
) -> Result<(f64, f64, Run, f64, Option<GhostReport>), BenchError> {
    let started = Instant::now();
    let len = 0.4;
    let n = (nx / 4).max(1);
    let case = format!("tension PD {nx}x{n}x{n} k={k} nu={nu}");
    let b = cut_body(
        &case,
        [0.0; 3],
        [len, SIDE, SIDE],
        [nx, n, n],
        k,
        material,
        cut,
    )?;
    let delta = b.horizon();
    let bonds = b.bonds();
    let ghosts = T::ghosts(&b.model);
    let left = b.select(|x| x[0] < delta);
    let right = b.select(|x| x[0] > len - delta);
    let omega1 = std::f64::consts::PI * (YOUNG / DENSITY).sqrt() / len;
    let physics = |cause| BenchError::Physics {
        case: case.clone(),
        cause,
    };
    let mut loads = Loads::new(b.rest().len())
        .with_damping(2.0 * omega1)
        .map_err(physics)?;
    loads.anchor(&left, [0.0; 3]).map_err(physics)?;
    loads.anchor(&right, [0.0; 3]).map_err(physics)?;
    // Start from the affine answer with the nominal contraction; the relaxation finds the rest.
    let eps = 1e-3;
    let c = SIDE / 2.0;
    let start: Vec<[f64; 3]> = b
        .rest()
        .iter()
        .map(|p| {
            [
                p[0] + eps * p[0].clamp(delta, len - delta),
                p[1] - nu * eps * (p[1] - c),
                p[2] - nu * eps * (p[2] - c),
            ]
        })
        .collect();
    let mut s = b.solver(&case, loads)?;
    s.set_positions(&start);
    let steps = (40.0 / omega1 / s.dt()).ceil() as u64;
    for _ in 0..steps {
        s.step().map_err(physics)?;
    }
    let (y, rest) = (s.positions(), rest_of(&s));
    let mid: Vec<usize> = (0..rest.len())
        .filter(|&i| (rest[i][0] - len / 2.0).abs() < len / 6.0)
        .collect();
    let slope = |d: usize| {
        let u: Vec<f64> = mid.iter().map(|&i| y[i][d] - rest[i][d]).collect();
        let x: Vec<f64> = mid.iter().map(|&i| rest[i][d]).collect();
        fit_line(&x, &u).1
    };
    let exx = slope(0);
    let eyy = 0.5 * (slope(1) + slope(2));
    let reaction: f64 = right.iter().map(|&i| s.forces()[i as usize][0]).sum();
    let stress = -reaction / (SIDE * SIDE);
    let run = Run::peridynamics([nx, n, n], k, started, steps, bonds);
    Ok((stress / exx / YOUNG, -eyy / exx, run, delta, ghosts))
}

/// The moduli case: E and nu from uniaxial tension over the sweep.
pub fn moduli(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<CaseReport, BenchError> {
    let (levels, factors): (&[usize], &[f64]) = match effort {
        Effort::Tiny => (&[16], &[1.5]),
        Effort::Full => (&[16, 24, 32], &HORIZON_FACTORS),
    };
    let mut runs = Vec::new();
    // (horizon factor, fitted dilatation): the scalar calibration at every factor, the fitted
    // dilatation at the 1.5
    let variants: Vec<(f64, bool)> = factors
        .iter()
        .map(|&k| (k, false))
        .chain(std::iter::once((1.5, true)))
        .collect();
    for &(k, fitted) in &variants {
        let tag = if fitted { " fitted" } else { "" };
        for &nx in levels {
            progress(&format!(
                "moduli: uniaxial tension at {nx} cells along, k = {k}{tag}"
            ));
            let (e, nu, run, _) = tension(nx, k, fitted, POISSON, KUHN)?;
            runs.push(Run {
                method: format!("PD{tag} E"),
                value: e * YOUNG,
                error: e - 1.0,
                ..run.clone()
            });
            runs.push(Run {
                method: format!("PD{tag} nu"),
                value: nu,
                error: nu / POISSON - 1.0,
                ..run
            });
        }
    }
    // m-convergence: the horizon held at its 1.5-factor value on the coarsest bar while the
    // cells shrink (k grows with the cells along), calibrated and fitted.
    let mut fixed = Table::new(&[
        "correction",
        "cells",
        "k",
        "horizon (m)",
        "m = horizon / cell",
        "E error",
        "nu",
        "wall time (s)",
    ]);
    let coarsest = levels.first().copied().unwrap_or(16) as f64;
    for fitted in [false, true] {
        for &nx in levels {
            let k = 1.5 * nx as f64 / coarsest;
            let name = if fitted { "fitted" } else { "calibrated" };
            progress(&format!(
                "moduli: fixed horizon, {nx} cells along (k = {k}), {name}"
            ));
            let (e, nu, run, horizon) = tension(nx, k, fitted, POISSON, KUHN)?;
            let cell = 0.4 / nx as f64;
            fixed.push(vec![
                name.into(),
                run.resolution.clone(),
                format!("{k:.2}"),
                format!("{horizon:.4}"),
                format!("{:.2}", horizon / cell),
                format!("{:+.2}%", 100.0 * (e - 1.0)),
                format!("{nu:.4}"),
                format!("{:.1}", run.wall_s),
            ]);
        }
    }
    // The targets: E within 3% and nu within 0.02 at 8 cells across, for nu = 0.1, 0.3
    // and 0.4 (k = 1.5), both corrections on the Kuhn lattice and the default (fitted) on the
    // scenes' unstructured box.
    let mut ratios = Table::new(&[
        "correction",
        "mesh",
        "cells",
        "k",
        "nu given",
        "E error",
        "nu measured",
        "nu - nu given",
        "wall time (s)",
    ]);
    let across8 = *levels.last().unwrap_or(&16);
    let unstructured = Cut::Unstructured(UNSTRUCTURED_SEED);
    for (fitted, cut) in [(false, KUHN), (true, KUHN), (true, unstructured)] {
        let mesh = match cut {
            Cut::Unstructured(_) => "unstructured",
            _ => "Kuhn lattice",
        };
        for nu0 in [0.1, POISSON, 0.4] {
            let name = if fitted { "fitted" } else { "calibrated" };
            progress(&format!(
                "moduli: nu = {nu0} at {across8} cells along, k = 1.5, {name}, {mesh}"
            ));
            let (e, nu, run, _) = tension(across8, 1.5, fitted, nu0, cut)?;
            ratios.push(vec![
                name.into(),
                mesh.into(),
                run.resolution.clone(),
                "1.5".into(),
                format!("{nu0}"),
                format!("{:+.2}%", 100.0 * (e - 1.0)),
                format!("{nu:.4}"),
                format!("{:+.4}", nu - nu0),
                format!("{:.1}", run.wall_s),
            ]);
        }
    }
    let (table, plot) = table_and_plot("Moduli from uniaxial tension", "Pa or 1", &runs);
    let text = format!(
        "Young's modulus and Poisson's ratio are measured on a 0.4 x 0.1 x 0.1 m bar in \
         uniaxial tension. The strain is 0.1%. Both end layers, one horizon deep, are held. The \
         bar relaxes with critical damping of the first axial mode. The stress is the pulled \
         layer's reaction over the section. The strains are fitted over the middle third. The \
         reference is the input: E = {YOUNG:e} Pa and nu = {POISSON}. The two rows of a run \
         share its cost. A section of 4 to 8 cells is 1.6 to 6.3 horizons across. So the \
         particles near the surface, whose families are cut, weigh in. The scalar calibration \
         of the \"PD\" rows (`correction = \"calibrated\"`) makes them stiffer. The constants \
         of docs/model.md make them softer (docs/DECISIONS.md). \"PD fitted\" rows fit each \
         particle's dilatation weights to read every homogeneous strain exactly. This is \
         `correction = \"fitted\"`, the default. The second table holds the horizon (m) fixed \
         at its value on the coarsest bar at k = 1.5 while the cells shrink. This is \
         m-convergence, the peridynamic literature's study. In it, the discrete sums approach \
         the nonlocal model's integrals. The first table's sweeps hold m fixed and shrink the \
         horizon with the cells. The third table sets Poisson's ratio to 0.1, 0.3 and 0.4 on \
         the finest bar at k = 1.5. Issue 18's targets at 8 cells across are E within 3% and \
         nu within 0.02. The third table uses the Kuhn lattice of the other tables. For the \
         default correction, it also uses the scenes' default box. That box is Delaunay tets \
         of well-spaced random points, seed {UNSTRUCTURED_SEED}. Its horizon is 1.5 of its \
         own mean edge."
    );
    Ok(CaseReport {
        name: "moduli".into(),
        title: "Young's modulus and Poisson's ratio".into(),
        text,
        table,
        plot,
        runs,
        tables: vec![
            ("Fixed horizon, finer cells (m-convergence)".into(), fixed),
            (
                "Poisson's ratio 0.1, 0.3 and 0.4 at the finest section".into(),
                ratios,
            ),
        ],
    })
}

/// Mean axial velocity (m/s) of the particles `set`.
fn mean_vx(s: &Explicit<ChenModel>, set: &[u32]) -> f64 {
    set.iter()
        .map(|&i| s.velocities()[i as usize][0])
        .sum::<f64>()
        / set.len() as f64
}

/// Time (s) at which `history` (sampled every `dt`) first reaches half its peak, interpolated.
fn half_peak_arrival(history: &[f64], dt: f64) -> f64 {
    let peak = history.iter().cloned().fold(f64::MIN, f64::max);
    let k = history
        .iter()
        .position(|&v| v >= 0.5 * peak)
        .unwrap_or(history.len() - 1)
        .max(1);
    let (a, b) = (history[k - 1], history[k]);
    (k as f64 - 1.0 + (0.5 * peak - a) / (b - a)) * dt
}

/// Measured speed over `sqrt(E / rho)` and the run's cost: a free 2 x 0.1 x 0.1 m bar of `nx`
/// cells along, a half-Gaussian axial velocity (sigma 0.25 m) at its end x = 0, arrival of
/// the leading edge at half its peak at x = 0.6 and 1.4 m.
fn pulse(nx: usize, k: f64) -> Result<Run, BenchError> {
    let started = Instant::now();
    let len = 2.0;
    let n = (nx / 20).max(1);
    let h = len / nx as f64;
    let case = format!("wave PD {nx}x{n}x{n} k={k}");
    let b = bar(&case, len, nx, 20, k, false, POISSON, KUHN)?;
    let bonds = b.bonds();
    let probe = |at: f64| b.select(move |x| (x[0] - at).abs() < 0.5 * h);
    let (p1, p2) = (probe(0.6), probe(1.4));
    let loads = Loads::new(b.rest().len());
    let mut s = b.solver(&case, loads)?;
    let sigma = 0.25;
    set_velocities(&mut s, |p| {
        [(-0.5 * (p[0] / sigma).powi(2)).exp(), 0.0, 0.0]
    });
    let c0 = (YOUNG / DENSITY).sqrt();
    let steps = (0.9 * len / c0 / s.dt()).ceil() as u64;
    let (mut h1, mut h2) = (vec![mean_vx(&s, &p1)], vec![mean_vx(&s, &p2)]);
    for _ in 0..steps {
        s.step().map_err(|cause| BenchError::Physics {
            case: case.clone(),
            cause,
        })?;
        h1.push(mean_vx(&s, &p1));
        h2.push(mean_vx(&s, &p2));
    }
    let dt = s.dt();
    let speed = 0.8 / (half_peak_arrival(&h2, dt) - half_peak_arrival(&h1, dt));
    Ok(Run {
        value: speed,
        error: speed / c0 - 1.0,
        ..Run::peridynamics([nx, n, n], k, started, steps, bonds)
    })
}

/// The wave-speed case over the sweep.
pub fn wave_speed(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    let (levels, factors): (&[usize], &[f64]) = match effort {
        Effort::Tiny => (&[40], &[1.5]),
        Effort::Full => (&[40, 80, 120], &HORIZON_FACTORS),
    };
    let mut runs = Vec::new();
    for &k in factors {
        for &nx in levels {
            progress(&format!("wave speed: pulse at {nx} cells along, k = {k}"));
            runs.push(pulse(nx, k)?);
        }
    }
    let (table, plot) = table_and_plot("Bar wave speed", "m/s", &runs);
    let text = format!(
        "A smooth pulse is started at the free end of a free 2 x 0.1 x 0.1 m bar. The pulse \
         is a half-Gaussian axial velocity with sigma = 0.25 m. Its leading edge is timed at \
         half its peak at x = 0.6 and 1.4 m. The reference is the bar speed \
         sqrt(E / rho) = {:.3} m/s. The pulse is long enough that its own dispersion in a \
         continuum (Rayleigh-Love) is 0.12%. Its wavelengths are above the 12 horizons where \
         the model's dispersion stays under 1% (docs/model.md section 2).",
        (YOUNG / DENSITY).sqrt()
    );
    Ok(CaseReport {
        name: "wave_speed".into(),
        title: "Bar wave speed".into(),
        text,
        table,
        plot,
        runs,
        tables: Vec::new(),
    })
}
