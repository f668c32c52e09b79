//! `perifrac bench contact`: contact between particles that share no intact bond (docs/model.md
//! section 7). The default wall is shot to pieces with contact off, with contact measuring
//! overlaps but pushing nothing (stiffness 0), and at several stiffnesses: how deep unbonded
//! particles pass through each other, what the step and the run cost, and how often the pair
//! list is built. A block cut into pieces by initial cracks and left at rest gives the cost of
//! contact where pieces touch but nothing moves.

use std::path::Path;
use std::time::Instant;

use perifrac_scene::{Scene, Setup};

use crate::table::Table;
use crate::{BenchError, Effort};

/// The default scene, whose cells, duration and contact keys the runs change.
const WALL: &str = include_str!("../../../data/scenes/wall.toml");

fn scene_error(case: &str, e: &dyn std::fmt::Display) -> BenchError {
    BenchError::Scene {
        case: case.into(),
        message: e.to_string(),
    }
}

/// What one stepped run measured.
struct Measured {
    dt: f64,
    steps: u64,
    /// Stepping only, setup and output left out (s).
    wall: f64,
    /// Share of the step spent on contact (colliders and particles).
    contact_share: f64,
    builds: u64,
    candidates_per_particle: f64,
    most_pairs: usize,
    /// Deepest overlap (m) and as a share of its pair's contact distance.
    deepest: (f64, f64),
    broken: u64,
    fragments: usize,
    particles: usize,
    bonds: usize,
}

/// Sets `scene` up and steps it to its end (or `steps` steps).
fn step_scene(
    case: &str,
    scene: &Scene,
    steps: Option<u64>,
    progress: &mut dyn FnMut(&str),
) -> Result<Measured, BenchError> {
    progress(&format!("contact: {case}"));
    let mut setup = Setup::new(scene, None).map_err(|e| scene_error(case, &e))?;
    let steps = steps.unwrap_or(setup.frames as u64 * setup.steps_per_frame);
    let t0 = Instant::now();
    for _ in 0..steps {
        setup.driver.step().map_err(|cause| BenchError::Physics {
            case: case.into(),
            cause,
        })?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let d = &setup.driver;
    let st = d.stage_times();
    let total = (st.physics + st.topology + st.advect).as_secs_f64();
    let n = d.masses().len();
    let (builds, candidates) = d
        .self_contact()
        .map_or((0, 0), |sc| (sc.rebuilds(), sc.candidates()));
    let deepest = d.self_contact_deepest();
    Ok(Measured {
        dt: setup.info.dt,
        steps,
        wall,
        contact_share: st.contact.as_secs_f64() / total.max(1e-12),
        builds,
        candidates_per_particle: candidates as f64 / n.max(1) as f64,
        most_pairs: deepest.pairs,
        deepest: (deepest.max_overlap, deepest.max_overlap_share),
        broken: d.broken_bonds(),
        fragments: d.mesh().pieces().count,
        particles: n,
        bonds: setup.info.bonds,
    })
}

fn percent(x: f64) -> String {
    format!("{:.1}%", 100.0 * x)
}

/// The default wall shot through with contact between particles off, measuring only, and at
/// stiffness factors 0.1, 0.25 (the default) and 1: one row each.
pub fn wall(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let (cells, duration) = match effort {
        Effort::Tiny => ("cells = [8, 8, 1]", "duration = 0.0005"),
        Effort::Full => ("cells = [24, 24, 3]", "duration = 0.005"),
    };
    let runs = [
        ("off", "self_contact = false"),
        (
            "overlaps measured, no force (stiffness 0)",
            "self_contact_stiffness = 0.0",
        ),
        ("stiffness 0.1", "self_contact_stiffness = 0.1"),
        ("stiffness 0.25 (the default)", ""),
        ("stiffness 1", "self_contact_stiffness = 1.0"),
    ];
    let mut t = Table::new(&[
        "contact between particles",
        "dt (s)",
        "steps",
        "stepping wall time (s)",
        "ms/step",
        "contact share of the step",
        "pair-list builds per 100 steps",
        "candidates per particle (end)",
        "most pairs touching",
        "deepest overlap (mm)",
        "deepest overlap / contact distance",
        "bonds broken",
        "fragments",
    ]);
    for (name, extra) in runs {
        let text = WALL
            .replace("cells = [24, 24, 3]", cells)
            .replace("duration = 0.005", duration)
            .replace("dt = \"auto\"", &format!("dt = \"auto\"\n{extra}"));
        let scene =
            Scene::parse(&text, Path::new("wall.toml")).map_err(|e| scene_error(name, &e))?;
        let m = step_scene(name, &scene, None, progress)?;
        // Without contact between particles there is no list and no pair to report.
        let measured = |v: String| if name == "off" { "-".into() } else { v };
        t.push(vec![
            name.into(),
            format!("{:.3e}", m.dt),
            m.steps.to_string(),
            format!("{:.1}", m.wall),
            format!("{:.2}", 1e3 * m.wall / m.steps.max(1) as f64),
            percent(m.contact_share),
            measured(format!(
                "{:.1}",
                100.0 * m.builds as f64 / m.steps.max(1) as f64
            )),
            measured(format!("{:.1}", m.candidates_per_particle)),
            measured(m.most_pairs.to_string()),
            measured(format!("{:.3}", 1e3 * m.deepest.0)),
            measured(percent(m.deepest.1)),
            m.broken.to_string(),
            m.fragments.to_string(),
        ]);
    }
    Ok(t)
}

/// A glass block of 1 cm cells cut by initial cracks into cubes of `piece` cells, at rest
/// with nothing acting on it: the scene text.
fn pile_scene(cells: [usize; 3], piece: usize, contact: bool) -> String {
    let h = 0.01;
    let size = cells.map(|c| c as f64 * h);
    let mut text = format!(
        "[mesh]\nprimitive = \"box\"\nsize = [{}, {}, {}]\ncells = [{}, {}, {}]\nstructure = \"lattice\"\n\n\
         [[material]]\nbulk_modulus = 3.3e10\nshear_modulus = 2.0e10\ndensity = 2200.0\n\
         s_crit = 0.0005\n\n[simulation]\nduration = 0.001\nself_contact = {contact}\n\n\
         [output]\nframes = 1\n",
        size[0], size[1], size[2], cells[0], cells[1], cells[2]
    );
    for axis in 0..3 {
        for k in (piece..cells[axis]).step_by(piece) {
            let x = k as f64 * h;
            let mut point = [0.0; 3];
            let mut normal = [0.0; 3];
            let (mut lo, mut hi) = ([-1.0; 3], [2.0; 3]);
            point[axis] = x;
            normal[axis] = 1.0;
            lo[axis] = x - 0.1 * h;
            hi[axis] = x + 0.1 * h;
            text.push_str(&format!(
                "\n[[precrack]]\npoint = {point:?}\nnormal = {normal:?}\n\
                 region = {{ min = {lo:?}, max = {hi:?} }}\n"
            ));
        }
    }
    text
}

/// A block of about 100,000 particles cut into pieces, at rest: the step with contact between
/// particles off and on, the contact share and the pair-list builds.
pub fn pile(effort: Effort, progress: &mut dyn FnMut(&str)) -> Result<Table, BenchError> {
    let (cells, piece, steps) = match effort {
        Effort::Tiny => ([6, 6, 6], 3, 5),
        Effort::Full => ([26, 26, 25], 5, 100),
    };
    let mut t = Table::new(&[
        "contact between particles",
        "particles",
        "bonds",
        "pieces",
        "steps",
        "s/step",
        "contact share of the step",
        "pair-list builds",
        "candidates per particle",
        "pairs touching",
    ]);
    for contact in [false, true] {
        let name = if contact { "on" } else { "off" };
        let text = pile_scene(cells, piece, contact);
        let scene =
            Scene::parse(&text, Path::new("pile.toml")).map_err(|e| scene_error(name, &e))?;
        let m = step_scene(
            &format!("pile at rest, contact {name}"),
            &scene,
            Some(steps),
            progress,
        )?;
        t.push(vec![
            name.into(),
            m.particles.to_string(),
            m.bonds.to_string(),
            m.fragments.to_string(),
            m.steps.to_string(),
            format!("{:.4}", m.wall / m.steps.max(1) as f64),
            percent(m.contact_share),
            if contact {
                m.builds.to_string()
            } else {
                "-".into()
            },
            if contact {
                format!("{:.1}", m.candidates_per_particle)
            } else {
                "-".into()
            },
            if contact {
                m.most_pairs.to_string()
            } else {
                "-".into()
            },
        ]);
    }
    Ok(t)
}
