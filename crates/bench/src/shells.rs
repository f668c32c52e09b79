//! `perifrac bench shells`: the thin-shell model (crates/shell) against Kirchhoff's plate
//! answers at three resolutions, and the paper's event search on a dropped egg shell against
//! plain steps of several lengths.

use std::f64::consts::PI;
use std::time::Instant;

use perifrac_contact::{Colliders, ContactParams, GroundDesc};
use perifrac_shell::{
    generate, ExplicitShell, SearchedShell, ShellError, ShellFracture, ShellMaterial, ShellMesh,
    ShellModel, ShellSearch,
};

use crate::table::Table;
use crate::{BenchError, Effort};

fn shell_error(case: &str) -> impl Fn(ShellError) -> BenchError + '_ {
    move |cause| BenchError::Scene {
        case: case.into(),
        message: cause.to_string(),
    }
}

/// Steps `shell` damped at `c` (1/s) for `time` (s) at 0.8 of its stable step.
fn relax(shell: &mut ExplicitShell, c: f64, time: f64, case: &str) -> Result<usize, BenchError> {
    shell.set_damping(c).map_err(shell_error(case))?;
    let dt = 0.8 * shell.stable_step().map_err(shell_error(case))?;
    let steps = (time / dt).ceil() as usize;
    for _ in 0..steps {
        shell.step(dt).map_err(shell_error(case))?;
    }
    Ok(steps)
}

/// The centre deflection of a simply supported square plate of side `a` under uniform load
/// `q`, over `D`: Navier's series `16 q a^4 / (pi^6 D) sum_{m,n odd} (-1)^((m+n)/2-1) /
/// (m n (m^2 + n^2)^2)`, summed to m, n < 200 (the terms fall as 1/(m n)^3).
fn navier_centre(q: f64, a: f64, d: f64) -> f64 {
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

/// Plates under their own weight against Kirchhoff: a strip clamped at one end (tip
/// deflection `q L^4 / (8 D)`, with `nu = 0` so the strip is the wide plate) and a simply
/// supported square (Navier's centre deflection, `nu = 0.3`), each at three resolutions, with
/// the observed order of convergence.
pub fn plates(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let mut t = Table::new(&[
        "case",
        "quads",
        "vertices",
        "steps",
        "deflection (m)",
        "Kirchhoff (m)",
        "error",
        "order",
    ]);
    let g = 9.81;
    // Clamped strip: 10 x 2 cm steel, 1 mm.
    let (l, b, h): (f64, f64, f64) = (0.1, 0.02, 1e-3);
    let steel0 = ShellMaterial::new(200e9, 0.0, 7800.0, h).map_err(shell_error("strip"))?;
    let d0 = steel0.young * h * h * h / 12.0;
    let q = steel0.areal_density() * g;
    let strip_ref = q * l.powi(4) / (8.0 * d0);
    // First bending frequency of the cantilever: 1.875^2 sqrt(D / (rho h L^4)).
    let w1 = 1.875f64.powi(2) * (d0 / (steel0.areal_density() * l.powi(4))).sqrt();
    let strips: &[(usize, usize)] = match effort {
        Effort::Tiny => &[(10, 2)],
        Effort::Full => &[(10, 2), (20, 4), (40, 8)],
    };
    let mut last: Option<(f64, f64)> = None;
    for &(nx, ny) in strips {
        let case = format!("clamped strip {nx} x {ny}");
        progress(&format!("shells: {case}"));
        let s = generate::sheet_uniform(l, b, nx, ny).map_err(|e| BenchError::Mesh {
            case: case.clone(),
            message: e.to_string(),
        })?;
        let mesh = ShellMesh::new(s.vertices.clone(), s.triangles).map_err(shell_error(&case))?;
        let model = ShellModel::new(mesh, steel0).map_err(shell_error(&case))?;
        let mut shell = ExplicitShell::new(model).map_err(shell_error(&case))?;
        let dx = l / nx as f64;
        // Two rows held: their triangles stay flat, clamping the slope.
        for (i, p) in s.vertices.iter().enumerate() {
            if p[0] < dx + 1e-9 {
                shell.pin(i);
            }
        }
        shell.set_gravity([0.0, 0.0, -g]);
        let steps = relax(&mut shell, 2.0 * w1, 25.0 / w1, &case)?;
        let tip: Vec<f64> = s
            .vertices
            .iter()
            .zip(shell.positions())
            .filter(|(p, _)| p[0] > l - 1e-9)
            .map(|(_, x)| -x[2])
            .collect();
        let w = tip.iter().sum::<f64>() / tip.len() as f64;
        let err = (w - strip_ref) / strip_ref;
        let order = last
            .map(|(e0, h0)| format!("{:.2}", (e0.abs() / err.abs()).ln() / (h0 / dx).ln()))
            .unwrap_or_else(|| "-".into());
        last = Some((err, dx));
        t.push(vec![
            "clamped strip 10 x 2 cm, 1 mm steel, nu 0".into(),
            format!("{nx} x {ny}"),
            s.vertices.len().to_string(),
            steps.to_string(),
            format!("{w:.4e}"),
            format!("{strip_ref:.4e}"),
            format!("{:+.2}%", 100.0 * err),
            order,
        ]);
    }
    // Simply supported square: 10 x 10 cm steel, 1 mm, nu = 0.3.
    let a: f64 = 0.1;
    let steel = ShellMaterial::new(200e9, 0.3, 7800.0, h).map_err(shell_error("plate"))?;
    let d = steel.young * h * h * h / (12.0 * (1.0 - 0.09));
    let plate_ref = navier_centre(steel.areal_density() * g, a, d);
    let w11 = 2.0 * PI * PI / (a * a) * (d / steel.areal_density()).sqrt();
    let plates: &[usize] = match effort {
        Effort::Tiny => &[8],
        Effort::Full => &[8, 16, 32],
    };
    let mut last: Option<(f64, f64)> = None;
    for &n in plates {
        let case = format!("simply supported plate {n} x {n}");
        progress(&format!("shells: {case}"));
        let s = generate::sheet_uniform(a, a, n, n).map_err(|e| BenchError::Mesh {
            case: case.clone(),
            message: e.to_string(),
        })?;
        let mesh = ShellMesh::new(s.vertices.clone(), s.triangles).map_err(shell_error(&case))?;
        let model = ShellModel::new(mesh, steel).map_err(shell_error(&case))?;
        let mut shell = ExplicitShell::new(model).map_err(shell_error(&case))?;
        // The edge held in place, free to turn about it: simply supported.
        for (i, p) in s.vertices.iter().enumerate() {
            let edge = |x: f64| x < 1e-9 || x > a - 1e-9;
            if edge(p[0]) || edge(p[1]) {
                shell.pin(i);
            }
        }
        shell.set_gravity([0.0, 0.0, -g]);
        let steps = relax(&mut shell, 2.0 * w11, 25.0 / w11, &case)?;
        let centre = s
            .vertices
            .iter()
            .position(|p| (p[0] - a / 2.0).abs() < 1e-9 && (p[1] - a / 2.0).abs() < 1e-9)
            .map(|i| -shell.positions()[i][2])
            .unwrap_or(f64::NAN);
        let dx = a / n as f64;
        let err = (centre - plate_ref) / plate_ref;
        let order = last
            .map(|(e0, h0)| format!("{:.2}", (e0.abs() / err.abs()).ln() / (h0 / dx).ln()))
            .unwrap_or_else(|| "-".into());
        last = Some((err, dx));
        t.push(vec![
            "simply supported square 10 cm, 1 mm steel, nu 0.3".into(),
            format!("{n} x {n}"),
            s.vertices.len().to_string(),
            steps.to_string(),
            format!("{centre:.4e}"),
            format!("{plate_ref:.4e}"),
            format!("{:+.2}%", 100.0 * err),
            order,
        ]);
    }
    Ok(t)
}

/// A sheet stretched uniformly in its plane against the closed form: 10 x 5 cm steel, 1 mm,
/// `nu = 0.3`, stretched by 1% along x and contracted across by the plane-stress Poisson
/// strain (Green strains `E_yy = -nu E_xx`), so the stress is uniaxial; the pull on the right
/// edge is `Y h W E_xx lambda_x` (first Piola stress times the rest width) and the top and
/// bottom edges carry nothing, so every vertex off the ends is in balance. The discrete model
/// should give both to round-off at every resolution (its membrane strain is exact for an
/// affine map).
pub fn membrane(effort: Effort) -> Result<Table, BenchError> {
    let mut t = Table::new(&[
        "quads",
        "pull on the right edge (N)",
        "closed form (N)",
        "error",
        "largest force on any other vertex (N)",
    ]);
    let (w, hgt, h, nu): (f64, f64, f64, f64) = (0.1, 0.05, 1e-3, 0.3);
    let steel = ShellMaterial::new(200e9, nu, 7800.0, h).map_err(shell_error("membrane"))?;
    let exx: f64 = 0.01 + 0.5 * 0.01 * 0.01;
    let (lx, ly) = ((1.0 + 2.0 * exx).sqrt(), (1.0 - 2.0 * nu * exx).sqrt());
    let expected = steel.young * h * hgt * exx * lx;
    let sizes: &[(usize, usize)] = match effort {
        Effort::Tiny => &[(10, 5)],
        Effort::Full => &[(10, 5), (20, 10), (40, 20)],
    };
    for &(nx, ny) in sizes {
        let case = format!("membrane {nx} x {ny}");
        let s = generate::sheet(w, hgt, nx, ny).map_err(|e| BenchError::Mesh {
            case: case.clone(),
            message: e.to_string(),
        })?;
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
        t.push(vec![
            format!("{nx} x {ny}"),
            format!("{pull:.6e}"),
            format!("{expected:.6e}"),
            format!("{:.1e}", (pull - expected).abs() / expected),
            format!("{across:.1e}"),
        ]);
    }
    Ok(t)
}

/// The egg of [`egg_drop`]: an ellipsoidal shell (22 x 22 x 29 mm half-axes, 0.35 mm, 30 GPa,
/// breaking at a principal strain of 2e-3) just above the ground, falling at `speed`.
fn egg(subdivisions: u32, speed: f64) -> Result<ExplicitShell, ShellError> {
    let s = generate::ellipsoid([0.022, 0.022, 0.029], subdivisions)
        .map_err(|e| ShellError::Contact(e.to_string()))?;
    let h = 3.5e-4;
    let v: Vec<_> = s
        .vertices
        .iter()
        .map(|p| [p[0], p[1], p[2] + 0.029 + 0.5 * h + 1e-4])
        .collect();
    let mesh = ShellMesh::new(v, s.triangles)?;
    let material = ShellMaterial::new(30e9, 0.3, 2000.0, h)?;
    let model =
        ShellModel::new(mesh, material)?.with_fracture(ShellFracture::new(2e-3, 2e-3, 0.25, 1.0)?);
    let mut shell = ExplicitShell::new(model)?;
    for v in shell.velocities_mut() {
        *v = [0.0, 0.0, -speed];
    }
    shell.set_gravity([0.0, 0.0, -9.81]);
    let ground = GroundDesc {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        params: ContactParams::from_material(30e9, 0.5 * h, 1.0, 0.1, 0.3),
    };
    let colliders = Colliders::new(vec![ground], vec![], [0.0, 0.0, -9.81])
        .map_err(|e| ShellError::Contact(e.to_string()))?;
    shell.set_colliders(colliders, 0.5 * h)?;
    Ok(shell)
}

/// Connected pieces of a shell's mesh.
fn pieces(m: &ShellMesh) -> usize {
    perifrac_shell::pieces(m)
        .iter()
        .max()
        .map_or(0, |&p| p as usize + 1)
}

/// The paper's Figure 9: an egg shell dropped gently on the ground, stepped plainly at
/// shortening fixed steps (the shortest the reference) and with the event search at rising
/// `k_max`, each counted by triangles broken, pieces, force evaluations and wall time.
pub fn egg_drop(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<(Table, String), BenchError> {
    let (subdivisions, duration, speed) = match effort {
        Effort::Tiny => (2, 2e-4, 0.5),
        Effort::Full => (3, 2e-3, 0.5),
    };
    let plain: &[f64] = match effort {
        Effort::Tiny => &[0.5],
        Effort::Full => &[0.5, 0.25, 0.125, 0.0625],
    };
    let levels: &[u32] = match effort {
        Effort::Tiny => &[4],
        Effort::Full => &[2, 4, 6, 8, 10],
    };
    let mut t = Table::new(&[
        "stepping",
        "step (s)",
        "force evaluations",
        "wall (s)",
        "triangles broken",
        "pieces",
    ]);
    let probe = egg(subdivisions, speed).map_err(shell_error("egg"))?;
    let faces = probe.model().mesh().triangles().len();
    let mut p = probe.clone();
    let limit = p.stable_step().map_err(shell_error("egg"))?;
    for &f in plain {
        let case = format!("egg, plain steps of {f} x the stable step");
        progress(&format!("shells: {case}"));
        let mut shell = probe.clone();
        let mut dt = f * limit;
        let first = dt;
        let started = Instant::now();
        let (mut broken, mut steps) = (0, 0u64);
        while shell.time() < duration * (1.0 - 1e-12) {
            shell
                .step(dt.min(duration - shell.time()))
                .map_err(shell_error(&case))?;
            steps += 1;
            let events = shell.fracture().map_err(shell_error(&case))?.events.len();
            if events > 0 {
                broken += events;
                // Splits make triangles smaller: the step follows the mesh's stable step.
                dt = dt.min(f * shell.stable_step().map_err(shell_error(&case))?);
            }
        }
        let dt = if dt < first {
            format!("{first:.2e} to {dt:.2e}")
        } else {
            format!("{dt:.2e}")
        };
        t.push(vec![
            format!("plain, {f} x stable"),
            dt,
            steps.to_string(),
            format!("{:.1}", started.elapsed().as_secs_f64()),
            broken.to_string(),
            pieces(shell.model().mesh()).to_string(),
        ]);
    }
    for &k in levels {
        let case = format!("egg, search to k_max {k}");
        progress(&format!("shells: {case}"));
        let config = ShellSearch {
            levels: k,
            ..ShellSearch::default()
        };
        let mut s = SearchedShell::new(probe.clone(), config).map_err(shell_error(&case))?;
        let dt = 0.5 * limit;
        let steps = (duration / dt).ceil() as usize;
        let started = Instant::now();
        for _ in 0..steps {
            s.advance(dt).map_err(shell_error(&case))?;
        }
        let st = s.stats();
        t.push(vec![
            format!("search, k_max {k}"),
            format!("{dt:.2e}"),
            (st.substeps + st.rejected).to_string(),
            format!("{:.1}", started.elapsed().as_secs_f64()),
            st.events.len().to_string(),
            pieces(s.shell().model().mesh()).to_string(),
        ]);
    }
    let text = format!(
        "An ellipsoidal egg shell (half-axes 22 x 22 x 29 mm, {faces} triangles, 0.35 mm, \
         E = 30 GPa, nu = 0.3, 2000 kg/m^3, breaking at a principal strain of 2e-3) falls on \
         the ground at {speed} m/s plus gravity, for {:.1} ms. The stable step of the intact \
         shell is {limit:.2e} s; the search's outer step is half of it and its sub-steps go \
         down to 2^-k_max of that. Plain steps are shortened to the given share of the \
         stable step of the mesh after each fracture (splits make triangles smaller). Force \
         evaluations count every trial, discarded or not (and not the stable-step estimates).",
        duration * 1e3
    );
    Ok((t, text))
}

/// Median of `runs` timings (s) of `f`.
fn median_time(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let started = Instant::now();
            f();
            started.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Speed of the shell's force pass and step: a glass sphere (3 cm, 0.5 mm) at two sizes,
/// triangle updates per second per core on one and two threads, and the share of a step that
/// contact with a ground plane and a ball takes (the step with colliders against without).
pub fn speed(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let mut t = Table::new(&[
        "sphere",
        "triangles",
        "force pass, 1 thread (ms)",
        "triangle updates/s/core, 1 thread",
        "force pass, 2 threads (ms)",
        "triangle updates/s/core, 2 threads",
        "step with colliders (ms)",
        "contact share of the step",
    ]);
    let sizes: &[u32] = match effort {
        Effort::Tiny => &[3],
        Effort::Full => &[5, 6],
    };
    for &sub in sizes {
        let case = format!("sphere, {sub} subdivisions");
        progress(&format!("shells: speed, {case}"));
        let s = generate::icosphere(0.03, sub).map_err(|e| BenchError::Mesh {
            case: case.clone(),
            message: e.to_string(),
        })?;
        let faces = s.triangles.len();
        let lift = 0.03 + 0.25e-3 + 1e-4;
        let v: Vec<_> = s
            .vertices
            .iter()
            .map(|p| [p[0], p[1], p[2] + lift])
            .collect();
        let mesh = ShellMesh::new(v.clone(), s.triangles).map_err(shell_error(&case))?;
        let glass = ShellMaterial::new(70e9, 0.22, 2500.0, 5e-4).map_err(shell_error(&case))?;
        let mut model = ShellModel::new(mesh, glass).map_err(shell_error(&case))?;
        // A deformed state, so every bending and membrane term is live.
        let x: Vec<_> = v
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let w = 1e-5 * ((i * 7919 % 1000) as f64 / 1000.0 - 0.5);
                [p[0] + w, p[1] - w, p[2] + 0.5 * w]
            })
            .collect();
        let mut f = vec![[0.0; 3]; x.len()];
        let runs = match effort {
            Effort::Tiny => 3,
            Effort::Full => 30,
        };
        let mut per_threads = Vec::new();
        for threads in [1, 2] {
            let pool = crate::speed::pool(threads)?;
            let time = pool.install(|| {
                median_time(runs, || {
                    let _ = model.forces(&x, &mut f);
                })
            });
            per_threads.push((time, faces as f64 / time / threads as f64));
        }
        // Steps with and without colliders: a ground under the sphere and a kinematic ball
        // pressing on its top.
        let ground = GroundDesc {
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            params: ContactParams::from_material(70e9, 2.5e-4, 1.0, 0.1, 0.3),
        };
        let ball = perifrac_contact::BallDesc {
            center: [0.0, 0.0, 2.0 * lift + 0.01 + 2.6e-4],
            radius: 0.01,
            motion: perifrac_contact::BallMotion::Kinematic {
                velocity: [0.0, 0.0, -1.0],
            },
            params: ContactParams::from_material(70e9, 2.5e-4, 1.0, 0.1, 0.3),
        };
        let plain = ExplicitShell::new(model.clone()).map_err(shell_error(&case))?;
        let mut touching = plain.clone();
        let colliders = Colliders::new(vec![ground], vec![ball], [0.0; 3])
            .map_err(|e| shell_error(&case)(ShellError::Contact(e.to_string())))?;
        touching
            .set_colliders(colliders, 2.5e-4)
            .map_err(shell_error(&case))?;
        let mut plain = plain;
        let dt = 0.5 * plain.stable_step().map_err(shell_error(&case))?;
        let steps = 20;
        let pool = crate::speed::pool(2)?;
        let (bare, with) = pool.install(|| {
            let bare = median_time(runs.min(10), || {
                for _ in 0..steps {
                    let _ = plain.step(dt);
                }
            });
            let with = median_time(runs.min(10), || {
                for _ in 0..steps {
                    let _ = touching.step(dt);
                }
            });
            (bare / steps as f64, with / steps as f64)
        });
        t.push(vec![
            format!("{sub} subdivisions"),
            faces.to_string(),
            format!("{:.2}", 1e3 * per_threads[0].0),
            format!("{:.2e}", per_threads[0].1),
            format!("{:.2}", 1e3 * per_threads[1].0),
            format!("{:.2e}", per_threads[1].1),
            format!("{:.2}", 1e3 * with),
            format!("{:.0}%", 100.0 * (1.0 - bare / with).max(0.0)),
        ]);
    }
    Ok(t)
}
