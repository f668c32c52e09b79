//! `perifrac bench events`: what the explicit step's event search (docs/model.md section 6) buys on
//! an impact. The default scene's glass slab, shot by the steel ball, is run with the fixed
//! step (0.8 of the stable limit), with the event search, with a fixed step shortened until it
//! costs as many force evaluations as the search, and with a fine fixed step as the reference;
//! each is compared with the reference by bonds broken, fragments and the share of broken
//! bonds the two have in common (the crack pattern, not only its size).

use std::path::Path;
use std::time::Instant;

use perifrac_scene::{Scene, Setup};

use crate::plot::{Plot, Series};
use crate::table::Table;
use crate::{BenchError, Effort};

/// The default scene, whose cells and step the runs change.
const WALL: &str = include_str!("../../../data/scenes/wall.toml");

/// One run's end.
struct RunEnd {
    name: String,
    dt: f64,
    evaluations: u64,
    wall: f64,
    broken: u64,
    fragments: usize,
    /// Intact flag per directed bond at the end.
    bonds: Vec<u8>,
    /// (time s, bonds broken so far) after every outer step.
    history: Vec<(f64, f64)>,
}

fn scene_error(case: &str, e: &dyn std::fmt::Display) -> BenchError {
    BenchError::Scene {
        case: case.into(),
        message: e.to_string(),
    }
}

/// The wall at `cells`, with `extra` lines in `[simulation]` (a fixed `dt`, the search), on
/// the Kuhn lattice it was first measured on: the search's figures are about stepping, and the
/// lattice keeps them comparable with earlier landings.
fn wall_scene(cells: &str, extra: &str) -> Result<Scene, BenchError> {
    let text = WALL
        .replace(
            "cells = [24, 24, 3]",
            &format!("{cells}\nstructure = \"lattice\""),
        )
        .replace("dt = \"auto\"", extra);
    Scene::parse(&text, Path::new("wall.toml")).map_err(|e| scene_error("events", &e))
}

fn run(name: &str, scene: &Scene, progress: &mut dyn FnMut(&str)) -> Result<RunEnd, BenchError> {
    progress(&format!("events: {name}"));
    let mut setup = Setup::new(scene, Some(24)).map_err(|e| scene_error(name, &e))?;
    let steps = setup.frames as u64 * setup.steps_per_frame;
    let t0 = Instant::now();
    let mut history = Vec::with_capacity(steps as usize);
    for _ in 0..steps {
        setup.driver.step().map_err(|cause| BenchError::Physics {
            case: name.into(),
            cause,
        })?;
        history.push((
            setup.driver.solver().time(),
            setup.driver.broken_bonds() as f64,
        ));
    }
    let wall = t0.elapsed().as_secs_f64();
    let d = setup.driver;
    let stats = d.solver().stats();
    let evaluations = if d.solver().integrator() == perifrac_physics::IntegratorKind::EventSearch {
        stats.substeps + stats.rejected
    } else {
        steps
    };
    Ok(RunEnd {
        name: name.into(),
        dt: setup.info.dt,
        evaluations,
        wall,
        broken: d.broken_bonds(),
        fragments: d.mesh().pieces().count,
        bonds: d
            .solver()
            .model()
            .damage()
            .map(|m| m.bond_state().to_vec())
            .unwrap_or_default(),
        history,
    })
}

/// `|b - b_ref| / b_ref` at each of `run`'s times, the reference taken at its last time not
/// after it (its steps are finer); times before the reference broke anything are left out.
fn deviation(run: &[(f64, f64)], reference: &[(f64, f64)]) -> Vec<(f64, f64)> {
    run.iter()
        .filter_map(|&(t, b)| {
            let k = reference.partition_point(|&(tr, _)| tr <= t * (1.0 + 1e-9));
            let r = reference.get(k.checked_sub(1)?)?.1;
            (r > 0.0).then(|| (t, (b - r).abs() / r))
        })
        .collect()
}

/// Broken in both over broken in either (1: the same crack).
fn shared(a: &[u8], b: &[u8]) -> f64 {
    let (mut both, mut either) = (0u64, 0u64);
    for (&x, &y) in a.iter().zip(b) {
        let (bx, by) = (x == 0, y == 0);
        both += u64::from(bx && by);
        either += u64::from(bx || by);
    }
    if either == 0 {
        1.0
    } else {
        both as f64 / either as f64
    }
}

/// The table and the plot (bonds broken against time for each run).
pub fn impact(
    effort: Effort,
    progress: &mut dyn FnMut(&str),
) -> Result<(Table, Plot, String), BenchError> {
    let (cells, fine) = match effort {
        Effort::Tiny => ("cells = [8, 8, 1]", 4u32),
        Effort::Full => ("cells = [24, 24, 3]", 16u32),
    };
    let fixed = run(
        "fixed step (0.8 of the stable limit)",
        &wall_scene(cells, "dt = \"auto\"")?,
        progress,
    )?;
    let dt = fixed.dt;
    let search = run(
        "event search (k_max 4, force growth 1.1, overshoot 0.1)",
        &wall_scene(cells, "dt = \"auto\"\nevent_search = true")?,
        progress,
    )?;
    let bonds_only = run(
        "event search, overshoot only (force growth off)",
        &wall_scene(
            cells,
            "dt = \"auto\"\nevent_search = true\nforce_growth = inf",
        )?,
        progress,
    )?;
    let steps = fixed.evaluations.max(1);
    let m = search.evaluations.div_ceil(steps).max(2);
    let same_cost = run(
        &format!("fixed step / {m} (the search's cost)"),
        &wall_scene(cells, &format!("dt = {:e}", dt / f64::from(m as u32)))?,
        progress,
    )?;
    let reference = run(
        &format!("fixed step / {fine} (reference)"),
        &wall_scene(cells, &format!("dt = {:e}", dt / f64::from(fine)))?,
        progress,
    )?;
    let mut t = Table::new(&[
        "run",
        "step (s)",
        "force evaluations",
        "wall (s)",
        "bonds broken",
        "vs reference",
        "fragments",
        "vs reference",
        "broken bonds shared with the reference",
    ]);
    let runs = [&fixed, &search, &bonds_only, &same_cost, &reference];
    let rel = |a: f64, b: f64| format!("{:+.1}%", 100.0 * (a - b) / b.max(1.0));
    for r in runs {
        t.push(vec![
            r.name.clone(),
            format!("{:.3e}", r.dt),
            r.evaluations.to_string(),
            format!("{:.1}", r.wall),
            r.broken.to_string(),
            rel(r.broken as f64, reference.broken as f64),
            r.fragments.to_string(),
            rel(r.fragments as f64, reference.fragments as f64),
            format!("{:.3}", shared(&r.bonds, &reference.bonds)),
        ]);
    }
    let plot = Plot {
        title: "Bonds broken: deviation from the fine-step reference".into(),
        x_label: "time (s)".into(),
        y_label: "|bonds broken - reference| / reference".into(),
        series: runs[..runs.len() - 1]
            .iter()
            .map(|r| Series {
                name: r.name.clone(),
                points: deviation(&r.history, &reference.history),
            })
            .collect(),
    };
    let text = format!(
        "The default scene (`data/scenes/wall.toml`, {cells}, on the Kuhn lattice), 24 frames, stepped without \
         output. Force evaluations count every sub-step the search tried, the undone ones \
         included; the equal-cost fixed step is the stable step over {m}. \"Shared\" is the \
         number of bonds broken in both the run and the reference over those broken in either."
    );
    Ok((t, plot, text))
}
