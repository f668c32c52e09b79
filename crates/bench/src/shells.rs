//! `perifrac bench shells`: the paper's event search on a dropped egg shell against plain
//! steps of several lengths, and the speed of the thin-shell model (crates/shell). Its accuracy
//! against plate and membrane answers is in `perifrac bench accuracy` (`shell_*` cases).

use std::time::Instant;

use perifrac_contact::{Colliders, ContactParams, GroundDesc};
use perifrac_shell::{
    generate, NewmarkConfig, SearchedShell, ShellDynamics, ShellError, ShellFracture,
    ShellMaterial, ShellMesh, ShellModel, ShellSearch,
};

use crate::table::Table;
use crate::{BenchError, Effort};

/// The light bulb of the paper's Figure 1 (`data/scenes/shell_bulb.toml`).
const BULB: &str = include_str!("../../../data/scenes/shell_bulb.toml");

/// A shell error of `case` as a bench error.
pub(crate) fn shell_error(case: &str) -> impl Fn(ShellError) -> BenchError + '_ {
    move |cause| BenchError::Scene {
        case: case.into(),
        message: cause.to_string(),
    }
}

/// The egg of [`egg_drop`]: an ellipsoidal shell (22 x 22 x 29 mm half-axes, 0.35 mm, 30 GPa,
/// breaking at a principal strain of 2e-3) just above the ground, falling at `speed`.
fn egg(subdivisions: u32, speed: f64) -> Result<ShellDynamics, ShellError> {
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
    let mut shell = ShellDynamics::new(model)?;
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

/// The paper's Figure 9: an egg shell dropped on the ground, stepped plainly and with the
/// event search at rising `k_max` and falling force growth, each counted by triangles broken, pieces, force evaluations
/// and wall time. Plain steps come two ways: fixed at a share of the intact shell's stable
/// step (the paper's plain stepping; a run that runs away is reported so), and shortened to
/// that share of the mesh's stable step after each fracture (splits make triangles smaller).
pub fn egg_drop(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<(Table, String), BenchError> {
    let (subdivisions, duration, speed) = match effort {
        Effort::Tiny => (2, 2e-4, 1.0),
        Effort::Full => (3, 2e-3, 1.0),
    };
    // (share of the stable step, whether the step follows the mesh's after fractures)
    let plain: &[(f64, bool)] = match effort {
        Effort::Tiny => &[(0.5, true)],
        Effort::Full => &[
            (0.5, false),
            (0.25, false),
            (0.5, true),
            (0.25, true),
            (0.125, true),
            (0.0625, true),
        ],
    };
    // (k_max, force growth)
    let searches: &[(u32, f64)] = match effort {
        Effort::Tiny => &[(4, 1.1)],
        Effort::Full => &[
            (2, 1.1),
            (4, 1.1),
            (6, 1.1),
            (8, 1.1),
            (10, 1.1),
            (12, 1.1),
            (10, 1.2),
            (10, 1.05),
            (10, 1.02),
        ],
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
    for &(f, follow) in plain {
        let how = if follow { "shortened" } else { "fixed" };
        let case = format!("egg, plain steps of {f} x the stable step, {how}");
        progress(&format!("shells: {case}"));
        let mut shell = probe.clone();
        let mut dt = f * limit;
        let first = dt;
        let started = Instant::now();
        let (mut broken, mut steps) = (0, 0u64);
        let mut ran_away = None;
        while shell.time() < duration * (1.0 - 1e-12) {
            match shell.step(dt.min(duration - shell.time())) {
                Err(ShellError::RanAway { time }) => {
                    ran_away = Some(time);
                    break;
                }
                other => other.map_err(shell_error(&case))?,
            }
            steps += 1;
            let events = shell.fracture().map_err(shell_error(&case))?.events.len();
            if events > 0 {
                broken += events;
                if follow {
                    dt = dt.min(f * shell.stable_step().map_err(shell_error(&case))?);
                }
            }
        }
        let dt = if dt < first {
            format!("{first:.2e} to {dt:.2e}")
        } else {
            format!("{dt:.2e}")
        };
        let (broken, pieces) = outcome(ran_away, broken, shell.model().mesh());
        t.push(vec![
            format!("plain, {f} x stable, {how}"),
            dt,
            steps.to_string(),
            format!("{:.1}", started.elapsed().as_secs_f64()),
            broken,
            pieces,
        ]);
    }
    for &(k, growth) in searches {
        let case = format!("egg, search to k_max {k}, force growth {growth}");
        progress(&format!("shells: {case}"));
        let dt = 0.5 * limit;
        let (s, wall) = search_run(
            &probe,
            k,
            growth,
            dt,
            (duration / dt).ceil() as usize,
            &case,
        )?;
        let st = s.stats();
        t.push(vec![
            format!("search, k_max {k}, growth {growth}"),
            format!("{dt:.2e}"),
            (st.substeps + st.rejected).to_string(),
            format!("{wall:.1}"),
            st.events.len().to_string(),
            pieces(s.shell().model().mesh()).to_string(),
        ]);
    }
    let text = format!(
        "An ellipsoidal egg shell (half-axes 22 x 22 x 29 mm, {faces} triangles, 0.35 mm, \
         E = 30 GPa, nu = 0.3, 2000 kg/m^3, breaking at a principal strain of 2e-3) falls on \
         the ground at {speed} m/s plus gravity, for {:.1} ms. The stable step of the intact \
         shell is {limit:.2e} s. Plain steps are either fixed at the given share of it or \
         shortened to that share of the stable step of the mesh after each fracture (splits \
         make triangles smaller). The search's outer step is half of it and its sub-steps go \
         down to 2^-k_max of that; a trial is undone when the largest force grows by more than \
         the given factor (the paper's 1.1) or a triangle would break in it. Force evaluations count every trial, discarded or not (and \
         not the stable-step estimates).",
        duration * 1e3
    );
    Ok((t, text))
}

/// The paper's Figure 9 with the paper's integrator: the same egg stepped by implicit Newmark
/// (`beta = 1/4`), plainly at steps from 60 times the explicit limit down to under it, and by
/// the search over steps of 15 times it at rising `k_max` and two force growths (the paper's
/// formula `(F' - F) / F <= 1.1` reads as a factor 2.1; its text says 10%). Each run is
/// counted by triangles broken, pieces, solves, L-BFGS iterations and wall time.
pub fn egg_newmark(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<(Table, String), BenchError> {
    let (subdivisions, duration) = match effort {
        Effort::Tiny => (2, 2e-4),
        Effort::Full => (3, 4e-4),
    };
    let plain: &[f64] = match effort {
        Effort::Tiny => &[1e-5],
        Effort::Full => &[4e-5, 1e-5, 4e-6, 1e-6, 2.5e-7],
    };
    let searches: &[(u32, f64)] = match effort {
        Effort::Tiny => &[(4, 1.1)],
        Effort::Full => &[
            (2, 1.1),
            (4, 1.1),
            (6, 1.1),
            (8, 1.1),
            (10, 1.1),
            (6, 2.1),
            (10, 2.1),
        ],
    };
    let outer = 1e-5;
    let mut t = Table::new(&[
        "stepping",
        "step (s)",
        "solves",
        "L-BFGS iterations",
        "wall (s)",
        "triangles broken",
        "pieces",
    ]);
    let mut probe = egg(subdivisions, 1.0).map_err(shell_error("egg"))?;
    let faces = probe.model().mesh().triangles().len();
    let limit = probe.clone().stable_step().map_err(shell_error("egg"))?;
    probe
        .set_newmark(Some(NewmarkConfig::default()))
        .map_err(shell_error("egg"))?;
    let steps = |dt: f64| (duration / dt).round() as usize;
    for &dt in plain {
        let case = format!("egg, Newmark, plain steps of {dt:.1e} s");
        progress(&format!("shells: {case}"));
        let mut shell = probe.clone();
        let started = Instant::now();
        let mut broken = 0;
        let mut ran_away = None;
        for _ in 0..steps(dt) {
            match shell.step(dt) {
                Err(ShellError::RanAway { time }) => {
                    ran_away = Some(time);
                    break;
                }
                other => other.map_err(shell_error(&case))?,
            }
            broken += shell.fracture().map_err(shell_error(&case))?.events.len();
        }
        let st = shell.newmark_stats();
        let (broken, pieces) = outcome(ran_away, broken, shell.model().mesh());
        t.push(vec![
            format!("Newmark, plain, {:.1} x explicit limit", dt / limit),
            format!("{dt:.2e}"),
            st.steps.to_string(),
            st.iterations.to_string(),
            format!("{:.1}", started.elapsed().as_secs_f64()),
            broken,
            pieces,
        ]);
    }
    for &(k, growth) in searches {
        let case = format!("egg, Newmark, search to k_max {k}, force growth {growth}");
        progress(&format!("shells: {case}"));
        let (s, wall) = search_run(&probe, k, growth, outer, steps(outer), &case)?;
        let nm = s.shell().newmark_stats();
        t.push(vec![
            format!("Newmark, search, k_max {k}, growth {growth}"),
            format!("{outer:.2e}"),
            nm.steps.to_string(),
            nm.iterations.to_string(),
            format!("{wall:.1}"),
            s.stats().events.len().to_string(),
            pieces(s.shell().model().mesh()).to_string(),
        ]);
    }
    let text = format!(
        "The egg above ({faces} triangles) at 1 m/s for {:.1} ms, stepped by implicit \
         Newmark (beta = 1/4, gamma = 1/2, the paper's production integrator; L-BFGS to a \
         residual of 1e-6 of the step's force scale, at most {} iterations). Its explicit \
         stable limit is {limit:.2e} s. Plain steps take one solve each and break what is \
         over its threshold after it; the search covers steps of {outer:.0e} s, undoing a \
         trial whose largest force grew past the factor, in which a triangle would break, or \
         whose solve needed more than {} iterations. Solves count every trial.",
        duration * 1e3,
        NewmarkConfig::default().max_iterations,
        ShellSearch::default().trial_iterations
    );
    Ok((t, text))
}

/// A table's "triangles broken" and "pieces" cells: the count, or when the run ran away, when
/// and how many before.
fn outcome(ran_away: Option<f64>, broken: usize, mesh: &ShellMesh) -> (String, String) {
    match ran_away {
        Some(time) => (
            format!("ran away at {:.3} ms ({broken} before)", 1e3 * time),
            "-".to_string(),
        ),
        None => (broken.to_string(), pieces(mesh).to_string()),
    }
}

/// `probe` stepped `steps` times by the search over steps of `dt` (s) to level `k` with force
/// growth `growth`, and the wall time it took (s).
fn search_run(
    probe: &ShellDynamics,
    k: u32,
    growth: f64,
    dt: f64,
    steps: usize,
    case: &str,
) -> Result<(SearchedShell, f64), BenchError> {
    let config = ShellSearch {
        levels: k,
        force_growth: growth,
        ..ShellSearch::default()
    };
    let mut s = SearchedShell::new(probe.clone(), config).map_err(shell_error(case))?;
    let started = Instant::now();
    for _ in 0..steps {
        s.advance(dt).map_err(shell_error(case))?;
    }
    Ok((s, started.elapsed().as_secs_f64()))
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
        let plain = ShellDynamics::new(model.clone()).map_err(shell_error(&case))?;
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

/// The light bulb of the paper's Figure 1 run as its scene (`data/scenes/shell_bulb.toml`: a
/// glass sphere of 1,280 triangles shattered by a steel ball at 20 m/s, its shards repelling
/// each other), and at 320 triangles: triangle updates per second per core over the whole
/// run (fracture, stable-step re-measurements and contact included) and the shares of the
/// stepping spent on self contact (the shell's own pieces: grid, candidate list, penalties) and
/// on contact with the ball. `Tiny` runs 0.1 ms at 320 triangles.
pub fn bulb(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let mut t = Table::new(&[
        "bulb",
        "triangles, start / end",
        "simulated (ms)",
        "sub-steps",
        "stepping (s)",
        "triangle updates/s/core",
        "self contact",
        "ball contact",
        "triangles broken",
        "pieces",
    ]);
    let runs: &[(u32, Option<f64>)] = match effort {
        Effort::Tiny => &[(2, Some(1e-4))],
        Effort::Full => &[(2, None), (3, None)],
    };
    let threads = rayon::current_num_threads();
    for &(subdivisions, duration) in runs {
        let case = format!("light bulb, {subdivisions} subdivisions");
        progress(&format!("shells: {case}"));
        let fail = |message: String| BenchError::Scene {
            case: case.clone(),
            message,
        };
        let path = std::path::Path::new("data/scenes/shell_bulb.toml");
        let mut scene =
            perifrac_scene::ShellScene::parse(BULB, path).map_err(|e| fail(e.to_string()))?;
        scene.file.shell.subdivisions = Some(subdivisions);
        if let Some(d) = duration {
            scene.file.simulation.duration = d;
        }
        let setup = perifrac_scene::ShellSetup::new(&scene, Some(1), true)
            .map_err(|e| fail(e.to_string()))?;
        let start = setup.shell.shell().model().mesh().triangles().len();
        let dir = crate::look::temp_dir("bulb")?;
        let summary = perifrac_scene::run(setup, dir.path(), &mut perifrac_scene::Silent)
            .map_err(|e| fail(e.to_string()))?;
        let s = summary
            .shell()
            .ok_or_else(|| fail("a shell scene ran as a solid".into()))?;
        let stepping = s.physics_time.as_secs_f64().max(1e-9);
        let self_share = s.self_contact.map_or(0.0, |(secs, _)| secs / stepping);
        t.push(vec![
            format!("{subdivisions} subdivisions"),
            format!("{start} / {}", s.triangles),
            format!("{:.2}", 1e3 * summary.time),
            s.substeps.to_string(),
            format!("{stepping:.1}"),
            format!(
                "{:.2e}",
                s.triangle_updates as f64 / stepping / threads as f64
            ),
            format!("{:.1}%", 100.0 * self_share),
            format!("{:.1}%", 100.0 * s.collider_seconds / stepping),
            s.broken_triangles.to_string(),
            summary.fragments.to_string(),
        ]);
    }
    Ok(t)
}
