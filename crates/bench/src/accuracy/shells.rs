//! Thin shells (crates/shell, Gingold et al. 2004) against Kirchhoff-Love plate answers and the
//! closed form of a stretched sheet, each at three resolutions:
//!
//! - `shell_strip`: a 10 x 2 cm steel strip, 1 mm, clamped at one end by two held rows of
//!   vertices, under its own weight, with `nu = 0` so the strip is the wide plate: tip
//!   deflection `q L^4 / (8 D)`.
//! - `shell_plate`: a 10 cm simply supported steel square, 1 mm, `nu = 0.3`, under its own
//!   weight (a uniform pressure `rho h g`): Navier's series at the centre.
//! - `shell_membrane`: a 10 x 5 cm steel sheet, 1 mm, `nu = 0.3`, stretched 1% along x and
//!   contracted across by the plane-stress Poisson strain (uniaxial stress): the pull on its
//!   right edge against `Y h W E_xx lambda_x`.
//!
//! The plates relax dynamically (damping of twice the first bending frequency for 25 of its
//! periods over 2 pi, at 0.8 of the stable step) on grids whose quads are split along one
//! diagonal ([`generate::sheet_uniform`]; on the checkerboard grid the square converges 40% too
//! stiff, docs/DECISIONS.md "Plates").

use std::f64::consts::PI;
use std::time::Instant;

use perifrac_shell::{generate, ShellDynamics, ShellMaterial, ShellMesh, ShellModel};

use super::{table_and_plot, CaseReport, Run};
use crate::shells::shell_error;
use crate::table::Table;
use crate::{BenchError, Effort};

/// Gravity (m/s^2) on the plates.
const GRAVITY: f64 = 9.81;
/// Young's modulus (Pa) and density (kg/m^3) of the plates' steel.
const STEEL: (f64, f64) = (200e9, 7800.0);
/// Plate thickness (m).
const THICKNESS: f64 = 1e-3;
/// The method's name in the tables.
const METHOD: &str = "shell (Gingold)";

/// A surface-generation error of `case` as a bench error.
fn mesh_error(case: &str) -> impl Fn(perifrac_shell::generate::GenerateError) -> BenchError + '_ {
    move |e| BenchError::Mesh {
        case: case.into(),
        message: e.to_string(),
    }
}

/// Steps `shell` damped at `c` (1/s) for `time` (s) at 0.8 of its stable step; the steps taken.
fn relax(shell: &mut ShellDynamics, c: f64, time: f64, case: &str) -> Result<u64, BenchError> {
    shell.set_damping(c).map_err(shell_error(case))?;
    let dt = 0.8 * shell.stable_step().map_err(shell_error(case))?;
    let steps = (time / dt).ceil() as u64;
    for _ in 0..steps {
        shell.step(dt).map_err(shell_error(case))?;
    }
    Ok(steps)
}

/// The centre deflection (m) of a simply supported square plate of side `a` (m) under uniform
/// load `q` (Pa) and of bending stiffness `d` (N m): Navier's series
/// `16 q a^4 / (pi^6 D) sum_{m,n odd} (-1)^((m+n)/2-1) / (m n (m^2 + n^2)^2)`, summed to
/// m, n < 200 (the terms fall as 1/(m n)^3: the tail is under 1e-9 of the sum).
pub fn navier_centre(q: f64, a: f64, d: f64) -> f64 {
    let mut sum = 0.0;
    for m in (1..200).step_by(2) {
        for n in (1..200).step_by(2) {
            let sign = if ((m + n) / 2 - 1) % 2 == 0 {
                1.0
            } else {
                -1.0
            };
            let (mf, nf) = (m as f64, n as f64);
            sum += sign / (mf * nf * (mf * mf + nf * nf).powi(2));
        }
    }
    16.0 * q * a.powi(4) / (PI.powi(6) * d) * sum
}

/// A row of the observed order of convergence between successive runs of `runs` with grid
/// spacings `spacing` (m): `ln(e0 / e1) / ln(h0 / h1)`.
fn orders(runs: &[Run], spacing: &[f64]) -> Table {
    let mut t = Table::new(&["from", "to", "error from", "error to", "observed order"]);
    for i in 1..runs.len() {
        let (a, b) = (&runs[i - 1], &runs[i]);
        let order = (a.error.abs() / b.error.abs()).ln() / (spacing[i - 1] / spacing[i]).ln();
        t.push(vec![
            a.resolution.clone(),
            b.resolution.clone(),
            format!("{:+.2}%", 100.0 * a.error),
            format!("{:+.2}%", 100.0 * b.error),
            format!("{order:.2}"),
        ]);
    }
    t
}

/// A plate case's report: its runs' table and plot (deflections in m) and, past one run, the
/// observed order between successive grid spacings `spacing` (m).
fn plate_report(
    name: &str,
    title: &str,
    text: String,
    runs: Vec<Run>,
    spacing: &[f64],
) -> CaseReport {
    let (table, plot) = table_and_plot(title, "m", &runs);
    let tables = if runs.len() > 1 {
        vec![("Observed order".to_string(), orders(&runs, spacing))]
    } else {
        Vec::new()
    };
    CaseReport {
        name: name.into(),
        title: title.into(),
        text,
        table,
        plot,
        runs,
        tables,
    }
}

/// A plate run of `nx` x `ny` quads: its row with the deflection and the error against
/// `reference` (m).
fn plate_run(
    nx: usize,
    ny: usize,
    started: Instant,
    steps: u64,
    vertices: usize,
    deflection: f64,
    reference: f64,
) -> Run {
    Run {
        method: METHOD.into(),
        resolution: format!("{nx}x{ny}"),
        horizon_factor: None,
        wall_s: started.elapsed().as_secs_f64(),
        steps,
        size: 3 * vertices,
        value: deflection,
        error: (deflection - reference) / reference,
        implicit: None,
    }
}

/// The clamped strip (`shell_strip`).
pub fn shell_strip(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    let (l, b, h): (f64, f64, f64) = (0.1, 0.02, THICKNESS);
    let steel = ShellMaterial::new(STEEL.0, 0.0, STEEL.1, h).map_err(shell_error("strip"))?;
    let d = steel.young * h * h * h / 12.0;
    let q = steel.areal_density() * GRAVITY;
    let reference = q * l.powi(4) / (8.0 * d);
    // First bending frequency of the cantilever: 1.875^2 sqrt(D / (rho h L^4)).
    let w1 = 1.875f64.powi(2) * (d / (steel.areal_density() * l.powi(4))).sqrt();
    let sizes: &[(usize, usize)] = match effort {
        Effort::Tiny => &[(10, 2)],
        Effort::Full => &[(10, 2), (20, 4), (40, 8)],
    };
    let mut runs = Vec::new();
    let mut spacing = Vec::new();
    for &(nx, ny) in sizes {
        let case = format!("shell_strip {nx}x{ny}");
        progress(&format!("accuracy: {case}"));
        let started = Instant::now();
        let s = generate::sheet_uniform(l, b, nx, ny).map_err(mesh_error(&case))?;
        let mesh = ShellMesh::new(s.vertices.clone(), s.triangles).map_err(shell_error(&case))?;
        let model = ShellModel::new(mesh, steel).map_err(shell_error(&case))?;
        let mut shell = ShellDynamics::new(model).map_err(shell_error(&case))?;
        let dx = l / nx as f64;
        // Two rows held: their triangles stay flat, clamping the slope.
        for (i, p) in s.vertices.iter().enumerate() {
            if p[0] < dx + 1e-9 {
                shell.pin(i);
            }
        }
        shell.set_gravity([0.0, 0.0, -GRAVITY]);
        let steps = relax(&mut shell, 2.0 * w1, 25.0 / w1, &case)?;
        let tip: Vec<f64> = s
            .vertices
            .iter()
            .zip(shell.positions())
            .filter(|(p, _)| p[0] > l - 1e-9)
            .map(|(_, x)| -x[2])
            .collect();
        let w = tip.iter().sum::<f64>() / tip.len() as f64;
        runs.push(plate_run(
            nx,
            ny,
            started,
            steps,
            s.vertices.len(),
            w,
            reference,
        ));
        spacing.push(dx);
    }
    let title = "Thin shell: clamped strip under its own weight";
    let text = format!(
        "A 10 x 2 cm steel strip sags under gravity. Its steel has a modulus of 200 GPa and a \
         density of 7800 kg/m^3. The strip is 1 mm thick, with `nu = 0`. It is clamped at \
         x = 0 by two held rows of vertices. The mean tip deflection is measured against \
         Kirchhoff's `q L^4 / (8 D)` = {reference:.4e} m. With `nu = 0`, the strip is the wide \
         plate. The shell relaxes with damping of twice its first bending frequency. The error \
         comes from the clamp. The held second row shortens the free length by up to a grid \
         spacing. So the error falls at first order."
    );
    Ok(plate_report("shell_strip", title, text, runs, &spacing))
}

/// The simply supported square (`shell_plate`).
pub fn shell_plate(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    let (a, h): (f64, f64) = (0.1, THICKNESS);
    let nu = 0.3;
    let steel = ShellMaterial::new(STEEL.0, nu, STEEL.1, h).map_err(shell_error("plate"))?;
    let d = steel.young * h * h * h / (12.0 * (1.0 - nu * nu));
    let reference = navier_centre(steel.areal_density() * GRAVITY, a, d);
    let w11 = 2.0 * PI * PI / (a * a) * (d / steel.areal_density()).sqrt();
    let sizes: &[usize] = match effort {
        Effort::Tiny => &[8],
        Effort::Full => &[8, 16, 32],
    };
    let mut runs = Vec::new();
    let mut spacing = Vec::new();
    for &n in sizes {
        let case = format!("shell_plate {n}x{n}");
        progress(&format!("accuracy: {case}"));
        let started = Instant::now();
        let s = generate::sheet_uniform(a, a, n, n).map_err(mesh_error(&case))?;
        let mesh = ShellMesh::new(s.vertices.clone(), s.triangles).map_err(shell_error(&case))?;
        let model = ShellModel::new(mesh, steel).map_err(shell_error(&case))?;
        let mut shell = ShellDynamics::new(model).map_err(shell_error(&case))?;
        // The edge held in place, free to turn about it: simply supported.
        for (i, p) in s.vertices.iter().enumerate() {
            let edge = |x: f64| x < 1e-9 || x > a - 1e-9;
            if edge(p[0]) || edge(p[1]) {
                shell.pin(i);
            }
        }
        shell.set_gravity([0.0, 0.0, -GRAVITY]);
        let steps = relax(&mut shell, 2.0 * w11, 25.0 / w11, &case)?;
        let centre = s
            .vertices
            .iter()
            .position(|p| (p[0] - a / 2.0).abs() < 1e-9 && (p[1] - a / 2.0).abs() < 1e-9)
            .map(|i| -shell.positions()[i][2])
            .ok_or_else(|| BenchError::Mesh {
                case: case.clone(),
                message: "no vertex at the plate's centre (an odd grid)".into(),
            })?;
        runs.push(plate_run(
            n,
            n,
            started,
            steps,
            s.vertices.len(),
            centre,
            reference,
        ));
        spacing.push(a / n as f64);
    }
    let title = "Thin shell: simply supported square plate under uniform load";
    let text = format!(
        "A 10 cm steel square is loaded by its own weight. Its steel has a modulus of 200 GPa \
         and a density of 7800 kg/m^3. It is 1 mm thick, with `nu = 0.3`. Its edges are held \
         in place and free to turn. Its weight is a uniform load of {:.1} Pa. The centre \
         deflection is measured against Navier's series for the Kirchhoff-Love plate, \
         {reference:.4e} m. It converges from below at about first order. The boundary \
         triangles' free edges carry no curvature.",
        steel.areal_density() * GRAVITY
    );
    Ok(plate_report("shell_plate", title, text, runs, &spacing))
}

/// The stretched sheet (`shell_membrane`): the model's membrane strain is exact for an affine
/// map, so every resolution should give the closed form to round-off; the largest force on a
/// vertex off the loaded ends (which should be in balance) is reported beside.
pub fn shell_membrane(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<CaseReport, BenchError> {
    let (w, hgt, h, nu): (f64, f64, f64, f64) = (0.1, 0.05, THICKNESS, 0.3);
    let steel = ShellMaterial::new(STEEL.0, nu, STEEL.1, h).map_err(shell_error("membrane"))?;
    // Green strain of a 1% stretch; the cross contraction makes the stress uniaxial.
    let exx: f64 = 0.01 + 0.5 * 0.01 * 0.01;
    let (lx, ly) = ((1.0 + 2.0 * exx).sqrt(), (1.0 - 2.0 * nu * exx).sqrt());
    let reference = steel.young * h * hgt * exx * lx;
    let sizes: &[(usize, usize)] = match effort {
        Effort::Tiny => &[(10, 5)],
        Effort::Full => &[(10, 5), (20, 10), (40, 20)],
    };
    let mut runs = Vec::new();
    let mut balance = Table::new(&[
        "quads",
        "relative error of the pull",
        "largest force on any other vertex (N)",
    ]);
    for &(nx, ny) in sizes {
        let case = format!("shell_membrane {nx}x{ny}");
        progress(&format!("accuracy: {case}"));
        let started = Instant::now();
        let s = generate::sheet(w, hgt, nx, ny).map_err(mesh_error(&case))?;
        let mesh = ShellMesh::new(s.vertices.clone(), s.triangles).map_err(shell_error(&case))?;
        let mut model = ShellModel::new(mesh, steel).map_err(shell_error(&case))?;
        let x: Vec<_> = s
            .vertices
            .iter()
            .map(|p| [lx * p[0], ly * p[1], 0.0])
            .collect();
        let mut f = vec![[0.0; 3]; x.len()];
        model.forces(&x, &mut f).map_err(shell_error(&case))?;
        // The internal forces on the right column are minus the pull that holds it.
        let pull: f64 = s
            .vertices
            .iter()
            .zip(&f)
            .filter(|(p, _)| p[0] > w - 1e-9)
            .map(|(_, f)| -f[0])
            .sum();
        let across = s
            .vertices
            .iter()
            .zip(&f)
            .filter(|(p, _)| p[0] > 1e-9 && p[0] < w - 1e-9)
            .map(|(_, f)| f[0].abs().max(f[1].abs()))
            .fold(0.0, f64::max);
        runs.push(Run {
            method: METHOD.into(),
            resolution: format!("{nx}x{ny}"),
            horizon_factor: None,
            wall_s: started.elapsed().as_secs_f64(),
            steps: 0,
            size: 3 * s.vertices.len(),
            value: pull,
            error: (pull - reference) / reference,
            implicit: None,
        });
        let error = (pull - reference) / reference;
        balance.push(vec![
            format!("{nx}x{ny}"),
            format!("{error:+.1e}"),
            format!("{across:.1e}"),
        ]);
    }
    let title = "Thin shell: sheet stretched in its plane";
    let (table, plot) = table_and_plot(title, "N", &runs);
    let text = format!(
        "A 10 x 5 cm steel sheet is 1 mm thick, with `nu = 0.3`. It is stretched 1% along x. \
         It is contracted across by the plane-stress Poisson strain, so the stress is \
         uniaxial. The pull on its right edge is the sum of the internal forces there. It is \
         measured against `Y h W E_xx lambda_x` = {reference:.6e} N. This is the first Piola \
         stress times the rest width. The membrane strain of a triangle is exact for an affine \
         map. So every resolution should match to round-off. Every vertex off the loaded ends \
         should be in balance. The table below gives the error unrounded. It also gives the \
         largest force off the ends, against pulls of order 1e5 N."
    );
    Ok(CaseReport {
        name: "shell_membrane".into(),
        title: title.into(),
        text,
        table,
        plot,
        runs,
        tables: vec![("Round-off and balance".to_string(), balance)],
    })
}
