//! Dynamic fracture against experiment: the Kalthoff-Winkler impact
//! (`data/scenes/kalthoff_winkler.toml`) at three resolutions, and crack branching in a glass
//! plate under tractions (`data/scenes/glass_branching.toml`) at three loads. Each run gives its
//! crack's angle or branching, the crack tips' speed against the Rayleigh speed, and the damage
//! at the end as a picture.

use std::path::Path;
use std::time::Instant;

use perifrac_scene::{Scene, Setup};

use crate::error::BenchError;
use crate::facets::{Facets, Panel};
use crate::table::Table;
use crate::Effort;

/// The scene, whose cells the runs change.
const KW: &str = include_str!("../../../data/scenes/kalthoff_winkler.toml");

/// The notch tips (m, in the plate's x-y plane) and the side each crack runs to (-1: towards
/// smaller x).
pub const TIPS: [([f64; 2], f64); 2] = [([0.075, 0.05], -1.0), ([0.125, 0.05], 1.0)];

/// A particle with at least this damage lies on a crack. A particle beside a crack face has lost
/// the bonds across it, about half its family; one near a crack but not on it loses a few.
pub const ON_A_CRACK: f64 = 0.35;

/// The angle is read from the crack between these distances from its tip (m): past the notch's
/// own damaged zone, before the crack curves.
pub const ANGLE_RANGE: (f64, f64) = (0.004, 0.025);

/// The experiment's angle (degrees) and the range the issue accepts.
pub const EXPERIMENT_ANGLE: f64 = 70.0;

/// Time between two looks at the damage (s): crack-tip positions every 2 us.
const LOOK_EVERY: f64 = 2e-6;

/// One resolution's run.
#[derive(Debug, Clone)]
pub struct KwRun {
    /// Cells along x, y and z.
    pub cells: [usize; 3],
    /// Cell size (m).
    pub cell: f64,
    /// Particles.
    pub particles: usize,
    /// Wall time of the steps (s).
    pub wall: f64,
    /// Steps taken.
    pub steps: u64,
    /// Per notch tip: the angle (degrees) between its crack and the notch, read when the crack
    /// first reaches [`ANGLE_RANGE`]'s far end; `None` when it never does.
    pub angles: [Option<f64>; 2],
    /// Per notch tip: `(time s, distance m)` of the crack's farthest point from the tip.
    pub tips: [Vec<(f64, f64)>; 2],
    /// The Rayleigh speed of the plate's material (m/s).
    pub rayleigh: f64,
    /// Particles on a crack within 5 mm of the back edge, between the notches: cracks the
    /// experiment does not show.
    pub back_edge: usize,
    /// The damage at the end: the particles of the top layer as small triangles.
    pub panel: Panel,
    /// The crack at the end: the rest `(x, y)` (m) of every particle on it.
    pub cracks: Vec<[f64; 2]>,
}

/// Looks a crack-tip speed is fitted over: a tip advances by whole particles, about a cell
/// every look at 2,000 m/s, so one look's difference is mostly rounding; five looks (8 us)
/// bring it to about a fifth.
pub const SPEED_WINDOW: usize = 5;

impl KwRun {
    /// The fastest crack-tip speed (m/s) over both tips: the least-squares slope of the tip's
    /// distance over [`SPEED_WINDOW`] consecutive looks, at its largest.
    pub fn fastest_tip(&self) -> f64 {
        self.tips
            .iter()
            .flat_map(|t| t.windows(SPEED_WINDOW))
            .map(slope)
            .fold(0.0, f64::max)
    }
}

/// The least-squares slope of `points` `(t, r)` (0 for fewer than two distinct times).
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mt, mr) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let (mut num, mut den) = (0.0, 0.0);
    for &(t, r) in points {
        num += (t - mt) * (r - mr);
        den += (t - mt) * (t - mt);
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// The Rayleigh speed (m/s) of an isotropic solid of Young's modulus `young` (Pa), Poisson's
/// ratio `nu` and density `rho` (kg/m^3), by Viktorov's approximation
/// `c_R = c_s (0.862 + 1.14 nu) / (1 + nu)` (within 0.5% for nu in [0, 0.5]).
pub fn rayleigh_speed(young: f64, nu: f64, rho: f64) -> f64 {
    let c_s = (young / (2.0 * (1.0 + nu)) / rho).sqrt();
    c_s * (0.862 + 1.14 * nu) / (1.0 + nu)
}

/// For the crack of the tip `tip` running to `side`: the damaged particles on its side of the
/// tip and below it, as `(distance m, angle degrees from the notch)`. The notch runs towards +y
/// from the tip, so the angle is measured from -y, towards `side`.
fn crack_points(rest: &[[f64; 3]], damage: &[f64], tip: [f64; 2], side: f64) -> Vec<(f64, f64)> {
    rest.iter()
        .zip(damage)
        .filter(|(_, &d)| d >= ON_A_CRACK)
        .filter_map(|(x, _)| {
            let (dx, dy) = (x[0] - tip[0], x[1] - tip[1]);
            // below the tip (a cell's slack), and not back across the notch's plane
            (dy < 0.002 && side * dx > -0.002)
                .then(|| (dx.hypot(dy), (side * dx).atan2(-dy).to_degrees()))
        })
        .collect()
}

/// The median of `v` (NaN when empty).
fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The rest `(x, y)` (m) of the particles on a crack (damage at least [`ON_A_CRACK`]) that
/// `keep` keeps.
fn crack_points_xy(
    rest: &[[f64; 3]],
    damage: &[f64],
    keep: impl Fn(&[f64; 3]) -> bool,
) -> Vec<[f64; 2]> {
    rest.iter()
        .zip(damage)
        .filter(|(p, &d)| d >= ON_A_CRACK && keep(p))
        .map(|(p, _)| [p[0], p[1]])
        .collect()
}

/// The distance (m) between two crack patterns: the mean distance from a point of one to the
/// nearest point of the other, averaged both ways (0 for the same points; infinity when one is
/// empty and the other not).
pub fn path_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let one_way = |a: &[[f64; 2]], b: &[[f64; 2]]| {
        a.iter()
            .map(|p| {
                b.iter()
                    .map(|q| (p[0] - q[0]).hypot(p[1] - q[1]))
                    .fold(f64::INFINITY, f64::min)
            })
            .sum::<f64>()
            / a.len() as f64
    };
    match (a.is_empty(), b.is_empty()) {
        (true, true) => 0.0,
        (true, false) | (false, true) => f64::INFINITY,
        _ => 0.5 * (one_way(a, b) + one_way(b, a)),
    }
}

/// What a run gives its measures: the particles' rest positions (m), the wall time of the steps
/// (s), the steps and the damage at the end.
struct Looked {
    rest: Vec<[f64; 3]>,
    wall: f64,
    steps: u64,
    particles: usize,
    damage: Vec<f64>,
}

/// A measure taken during a run: `look(time s, rest positions m, damage)`.
type Look<'a> = dyn FnMut(f64, &[[f64; 3]], &[f64]) + 'a;

/// Sets up `text` (the scene file `name`) and runs it to its end, calling `look(time s, rest,
/// damage)` every [`LOOK_EVERY`] of simulated time and at the end.
fn run_looking(
    case: &str,
    name: &str,
    text: &str,
    progress: &mut dyn FnMut(&str),
    look: &mut Look,
) -> Result<Looked, BenchError> {
    let scene_error = |e: &dyn std::fmt::Display| BenchError::Scene {
        case: case.into(),
        message: e.to_string(),
    };
    let scene = Scene::parse(text, Path::new(name)).map_err(|e| scene_error(&e))?;
    let mut setup = Setup::new(&scene, None).map_err(|e| scene_error(&e))?;
    progress(&format!(
        "fracture: {case}, {} particles",
        setup.info.particles
    ));
    let dt = setup.info.dt;
    let total = setup.frames as u64 * setup.steps_per_frame;
    let every = ((LOOK_EVERY / dt).round() as u64).max(1);
    let rest: Vec<[f64; 3]> = setup
        .driver
        .solver()
        .model()
        .discretization()
        .rest_positions()
        .to_vec();
    let started = Instant::now();
    let mut done = 0;
    while done < total {
        let n = every.min(total - done);
        for _ in 0..n {
            setup.driver.step().map_err(|cause| BenchError::Physics {
                case: case.into(),
                cause,
            })?;
        }
        done += n;
        look(done as f64 * dt, &rest, &setup.driver.damage());
    }
    Ok(Looked {
        wall: started.elapsed().as_secs_f64(),
        steps: done,
        particles: setup.info.particles,
        damage: setup.driver.damage(),
        rest,
    })
}

/// The plate at `cells`, run to its end.
pub fn kalthoff_winkler(
    cells: [usize; 3],
    progress: &mut dyn FnMut(&str),
) -> Result<KwRun, BenchError> {
    let case = format!("Kalthoff-Winkler {}x{}x{}", cells[0], cells[1], cells[2]);
    let text = KW.replace("cells = [100, 50, 5]", &format!("cells = {cells:?}"));
    let mut tips: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    let mut angles = [None; 2];
    let mut look = |time: f64, rest: &[[f64; 3]], damage: &[f64]| {
        for (k, &(tip, side)) in TIPS.iter().enumerate() {
            let points = crack_points(rest, damage, tip, side);
            let reach = points.iter().map(|p| p.0).fold(0.0, f64::max);
            tips[k].push((time, reach));
            if angles[k].is_none() && reach >= ANGLE_RANGE.1 {
                let inside = points
                    .iter()
                    .filter(|p| p.0 >= ANGLE_RANGE.0 && p.0 <= ANGLE_RANGE.1)
                    .map(|p| p.1)
                    .collect();
                angles[k] = Some(median(inside)).filter(|a| a.is_finite());
            }
        }
    };
    let run = run_looking(&case, "kalthoff_winkler.toml", &text, progress, &mut look)?;
    let back_edge = run
        .rest
        .iter()
        .zip(&run.damage)
        .filter(|(x, &d)| d >= ON_A_CRACK && x[1] < 0.005 && x[0] > 0.075 && x[0] < 0.125)
        .count();
    let cell = 0.2 / cells[0] as f64;
    Ok(KwRun {
        cells,
        cell,
        particles: run.particles,
        wall: run.wall,
        steps: run.steps,
        angles,
        tips,
        rayleigh: rayleigh_speed(190e9, 0.3, 8000.0),
        back_edge,
        cracks: crack_points_xy(&run.rest, &run.damage, |_| true),
        panel: damage_panel(
            &run.rest,
            &run.damage,
            cell,
            format!("{:.2} mm cells", cell * 1e3),
        ),
    })
}

/// `panels` of damage under `title`, three to a row, on one scale from 0 to 0.6 (a particle on
/// a crack has about half its bonds).
fn damage_facets(title: &str, panels: Vec<Panel>) -> Facets {
    Facets {
        title: title.into(),
        scale: ("damage".into(), 0.6),
        rows: panels.len().div_ceil(3).max(1),
        panels,
    }
}

/// The particles in the plate's top half (z, or all of a plate one particle thick) as triangles of side `cell / 2` (m, drawn in mm)
/// at their rest positions, valued by damage.
fn damage_panel(rest: &[[f64; 3]], damage: &[f64], cell: f64, caption: String) -> Panel {
    let z_mid = rest.iter().map(|p| p[2]).fold(0.0, f64::max) / 2.0;
    let s = 0.5 * cell * 1e3;
    let mut triangles = Vec::new();
    let mut values = Vec::new();
    // intact particles first, so the cracks are drawn over them
    let mut order: Vec<usize> = (0..rest.len()).filter(|&i| rest[i][2] > z_mid).collect();
    order.sort_by(|&a, &b| damage[a].total_cmp(&damage[b]));
    for i in order {
        let (x, y) = (rest[i][0] * 1e3, rest[i][1] * 1e3);
        triangles.push([[x - s, y - s], [x + s, y - s], [x, y + s]]);
        values.push(damage[i]);
    }
    Panel {
        caption,
        triangles,
        values,
    }
}

/// The resolutions of a report: 4, 2.67 and 2 mm cells (one of 4 mm for a quick run).
pub fn resolutions(effort: Effort) -> Vec<[usize; 3]> {
    match effort {
        Effort::Tiny => vec![[50, 25, 3]],
        Effort::Full => vec![[50, 25, 3], [75, 38, 4], [100, 50, 5]],
    }
}

/// The branching plate, whose cells and tractions the runs change.
const BRANCHING: &str = include_str!("../../../data/scenes/glass_branching.toml");

/// The tip of the branching plate's pre-crack (m).
pub const PRECRACK_TIP: [f64; 2] = [0.05, 0.02];

/// The layer along each long edge that the traction loads as a body force (m): the scene's.
const LOAD_LAYER: f64 = 0.003;

/// Damage this close to a loaded edge (m) is the load's, not the crack's.
const EDGE_BAND: f64 = 0.003;

/// Width of the columns across which [`crack_count`] counts cracks (m).
pub const COLUMN: f64 = 0.002;

/// Two damaged particles of a column further apart than this (m) across the plate lie on two
/// cracks: a crack's damaged band is about two horizons wide.
const CRACK_GAP: f64 = 0.004;

/// One run of the branching plate.
#[derive(Debug, Clone)]
pub struct BranchingRun {
    /// The traction on the long edges (Pa).
    pub traction: f64,
    /// Cells along x, y and z.
    pub cells: [usize; 3],
    /// Particles.
    pub particles: usize,
    /// Wall time of the steps (s).
    pub wall: f64,
    /// Where the crack first runs as two (m along x), `None` when it never does.
    pub first_branch: Option<f64>,
    /// Cracks that reach the plate's far edge (the last 5 mm).
    pub at_far_edge: usize,
    /// `(time s, distance m)` of the damage farthest from the pre-crack's tip.
    pub tip: Vec<(f64, f64)>,
    /// The Rayleigh speed of the glass (m/s).
    pub rayleigh: f64,
    /// The damage at the end.
    pub panel: Panel,
    /// The cracks at the end, away from the loaded edges: the rest `(x, y)` (m) of every
    /// particle on one.
    pub cracks: Vec<[f64; 2]>,
}

impl BranchingRun {
    /// The fastest crack-tip speed (m/s), fitted as [`KwRun::fastest_tip`] fits it.
    pub fn fastest_tip(&self) -> f64 {
        self.tip
            .windows(SPEED_WINDOW)
            .map(slope)
            .fold(0.0, f64::max)
    }

    /// The mean speed (m/s) of the tip while it runs: fitted over the looks at which it is
    /// 5 to 45 mm from the pre-crack's tip (the far edge is 50 mm away).
    pub fn running_speed(&self) -> f64 {
        let running: Vec<(f64, f64)> = self
            .tip
            .iter()
            .copied()
            .filter(|&(_, r)| (0.005..=0.045).contains(&r))
            .collect();
        slope(&running)
    }
}

/// The cracks across the column of the plate `[x, x + COLUMN)`: clusters of damaged particles'
/// y, away from the loaded edges, split where two are [`CRACK_GAP`] apart.
fn crack_count(rest: &[[f64; 3]], damage: &[f64], x: f64, height: f64) -> usize {
    let mut ys: Vec<f64> = rest
        .iter()
        .zip(damage)
        .filter(|(p, &d)| {
            d >= ON_A_CRACK
                && p[0] >= x
                && p[0] < x + COLUMN
                && p[1] > EDGE_BAND
                && p[1] < height - EDGE_BAND
        })
        .map(|(p, _)| p[1])
        .collect();
    if ys.is_empty() {
        return 0;
    }
    ys.sort_by(f64::total_cmp);
    1 + ys.windows(2).filter(|w| w[1] - w[0] > CRACK_GAP).count()
}

/// The branching plate at `cells` under `traction` (Pa) on its long edges, run to its end.
pub fn branching(
    cells: [usize; 3],
    traction: f64,
    progress: &mut dyn FnMut(&str),
) -> Result<BranchingRun, BenchError> {
    let case = format!(
        "branching at {:.0} MPa, {}x{}x{}",
        traction / 1e6,
        cells[0],
        cells[1],
        cells[2]
    );
    let text = BRANCHING
        .replace("cells = [100, 40, 2]", &format!("cells = {cells:?}"))
        .replace("-1.3333333333e9", &format!("{:e}", -traction / LOAD_LAYER))
        .replace("1.3333333333e9", &format!("{:e}", traction / LOAD_LAYER));
    let (length, height) = (0.1, 0.04);
    let mut tip = Vec::new();
    let mut look = |time: f64, rest: &[[f64; 3]], damage: &[f64]| {
        let reach = rest
            .iter()
            .zip(damage)
            .filter(|(p, &d)| {
                d >= ON_A_CRACK
                    && p[0] > PRECRACK_TIP[0]
                    && p[1] > EDGE_BAND
                    && p[1] < height - EDGE_BAND
            })
            .map(|(p, _)| (p[0] - PRECRACK_TIP[0]).hypot(p[1] - PRECRACK_TIP[1]))
            .fold(0.0, f64::max);
        tip.push((time, reach));
    };
    let run = run_looking(&case, "glass_branching.toml", &text, progress, &mut look)?;
    let (rest, damage) = (&run.rest, &run.damage);
    // the first column past the pre-crack's tip from which the crack runs as two for three
    // columns running
    let columns = ((length - PRECRACK_TIP[0]) / COLUMN) as usize;
    let counts: Vec<usize> = (0..columns)
        .map(|c| crack_count(rest, damage, PRECRACK_TIP[0] + c as f64 * COLUMN, height))
        .collect();
    let first_branch = counts
        .windows(3)
        .position(|w| w.iter().all(|&n| n >= 2))
        .map(|c| PRECRACK_TIP[0] + c as f64 * COLUMN);
    let at_far_edge = (0..(0.005 / COLUMN) as usize)
        .map(|c| crack_count(rest, damage, length - 0.005 + c as f64 * COLUMN, height))
        .max()
        .unwrap_or(0);
    let cell = length / cells[0] as f64;
    Ok(BranchingRun {
        traction,
        cells,
        particles: run.particles,
        wall: run.wall,
        first_branch,
        at_far_edge,
        tip,
        rayleigh: rayleigh_speed(72e9, 0.22, 2440.0),
        cracks: crack_points_xy(rest, damage, |p| {
            p[1] > EDGE_BAND && p[1] < height - EDGE_BAND
        }),
        panel: damage_panel(
            rest,
            damage,
            cell,
            format!("{:.0} MPa, {:.2} mm cells", traction / 1e6, cell * 1e3),
        ),
    })
}

/// The tractions (Pa) of a branching report: 2, 4 and 12 MPa at 1 mm cells, and 2 and 4 MPa at
/// 1.33 and 0.67 mm for convergence (4 MPa at 1 mm alone for a quick run: at 2 mm cells the
/// damage front jumps ahead of the crack by a horizon).
pub fn branching_cases(effort: Effort) -> Vec<([usize; 3], f64)> {
    match effort {
        Effort::Tiny => vec![([100, 40, 2], 4e6)],
        Effort::Full => vec![
            ([75, 30, 2], 2e6),
            ([100, 40, 2], 2e6),
            ([150, 60, 3], 2e6),
            ([75, 30, 2], 4e6),
            ([100, 40, 2], 4e6),
            ([150, 60, 3], 4e6),
            ([100, 40, 2], 12e6),
        ],
    }
}

/// The branching report's table and picture.
pub fn branching_report(runs: &[BranchingRun]) -> (Table, Facets) {
    let mut table = Table::new(&[
        "traction (MPa)",
        "cell (mm)",
        "particles",
        "wall (s)",
        "first branch (x, mm)",
        "cracks at the far edge",
        "fastest tip (m/s)",
        "over Rayleigh",
        "mean while running (m/s)",
        "crack path to the finest (mm)",
    ]);
    for r in runs {
        let fastest = r.fastest_tip();
        let finest = runs
            .iter()
            .filter(|f| f.traction == r.traction)
            .max_by_key(|f| f.particles);
        table.push(vec![
            format!("{:.0}", r.traction / 1e6),
            format!("{:.2}", 100.0 / r.cells[0] as f64),
            r.particles.to_string(),
            format!("{:.1}", r.wall),
            r.first_branch
                .map_or("none".to_string(), |x| format!("{:.0}", x * 1e3)),
            r.at_far_edge.to_string(),
            format!("{fastest:.0}"),
            format!("{:.2}", fastest / r.rayleigh),
            format!("{:.0}", r.running_speed()),
            finest.map_or("-".to_string(), |f| {
                format!("{:.2}", 1e3 * path_distance(&r.cracks, &f.cracks))
            }),
        ]);
    }
    let panels = runs.iter().map(|r| r.panel.clone()).collect();
    (
        table,
        damage_facets("Glass branching: damage at 46 us (mm)", panels),
    )
}

/// The report's table and picture of `runs`.
pub fn report(runs: &[KwRun]) -> (Table, Facets) {
    let mut table = Table::new(&[
        "cell (mm)",
        "particles",
        "steps",
        "wall (s)",
        "angle, left tip (deg)",
        "angle, right tip (deg)",
        "fastest tip (m/s)",
        "over Rayleigh",
        "back-edge particles",
        "crack path to the finest (mm)",
    ]);
    let show = |a: Option<f64>| a.map_or("-".to_string(), |a| format!("{a:.1}"));
    let finest = runs.iter().max_by_key(|r| r.particles);
    for r in runs {
        let fastest = r.fastest_tip();
        table.push(vec![
            format!("{:.2}", r.cell * 1e3),
            r.particles.to_string(),
            r.steps.to_string(),
            format!("{:.1}", r.wall),
            show(r.angles[0]),
            show(r.angles[1]),
            format!("{fastest:.0}"),
            format!("{:.2}", fastest / r.rayleigh),
            r.back_edge.to_string(),
            finest.map_or("-".to_string(), |f| {
                format!("{:.2}", 1e3 * path_distance(&r.cracks, &f.cracks))
            }),
        ]);
    }
    let panels = runs.iter().map(|r| r.panel.clone()).collect();
    (
        table,
        damage_facets("Kalthoff-Winkler: damage at 90 us (mm)", panels),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_distance_is_the_mean_gap_both_ways() {
        // a line of points and the same line 1 mm off: 1 mm both ways
        let a: Vec<[f64; 2]> = (0..10).map(|i| [i as f64 * 1e-3, 0.0]).collect();
        let b: Vec<[f64; 2]> = a.iter().map(|p| [p[0], 1e-3]).collect();
        assert!((path_distance(&a, &b) - 1e-3).abs() < 1e-15);
        assert_eq!(path_distance(&a, &a), 0.0);
        // a branch one run lacks counts on its side only
        let mut c = a.clone();
        c.push([5e-3, 4e-3]);
        let d = path_distance(&c, &a);
        assert!((d - 0.5 * 4e-3 / 11.0).abs() < 1e-15, "{d}");
        assert!(path_distance(&a, &[]).is_infinite());
    }

    #[test]
    fn the_rayleigh_speed_is_viktorovs() {
        // at nu = 0.25 the Rayleigh equation's root is c_R / c_s = 0.9194; Viktorov's
        // approximation gives 0.9176, 0.2% low
        let (young, nu, rho): (f64, f64, f64) = (2.5, 0.25, 1.0);
        let c_s = (young / (2.0 * (1.0 + nu)) / rho).sqrt();
        let ratio = rayleigh_speed(young, nu, rho) / c_s;
        assert!((ratio / 0.9194 - 1.0).abs() < 0.005, "{ratio}");
    }
}
