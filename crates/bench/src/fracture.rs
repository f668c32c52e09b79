//! Dynamic fracture against experiment: the Kalthoff-Winkler impact
//! (`data/scenes/kalthoff_winkler.toml`) at three resolutions. Each run gives the angle at which
//! the cracks leave the notch tips, the crack tips' speed against the Rayleigh speed, and the
//! damage at the end as a picture.

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

/// The plate at `cells`, run to its end.
pub fn kalthoff_winkler(
    cells: [usize; 3],
    progress: &mut dyn FnMut(&str),
) -> Result<KwRun, BenchError> {
    let case = format!("Kalthoff-Winkler {}x{}x{}", cells[0], cells[1], cells[2]);
    let scene_error = |e: &dyn std::fmt::Display| BenchError::Scene {
        case: case.clone(),
        message: e.to_string(),
    };
    let text = KW.replace("cells = [100, 50, 5]", &format!("cells = {cells:?}"));
    let scene =
        Scene::parse(&text, Path::new("kalthoff_winkler.toml")).map_err(|e| scene_error(&e))?;
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
    let mut tips: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    let mut angles = [None; 2];
    let started = Instant::now();
    let mut done = 0;
    while done < total {
        let n = every.min(total - done);
        for _ in 0..n {
            setup.driver.step().map_err(|cause| BenchError::Physics {
                case: case.clone(),
                cause,
            })?;
        }
        done += n;
        let damage = setup.driver.damage();
        for (k, &(tip, side)) in TIPS.iter().enumerate() {
            let points = crack_points(&rest, &damage, tip, side);
            let reach = points.iter().map(|p| p.0).fold(0.0, f64::max);
            tips[k].push((done as f64 * dt, reach));
            if angles[k].is_none() && reach >= ANGLE_RANGE.1 {
                let inside = points
                    .iter()
                    .filter(|p| p.0 >= ANGLE_RANGE.0 && p.0 <= ANGLE_RANGE.1)
                    .map(|p| p.1)
                    .collect();
                angles[k] = Some(median(inside)).filter(|a| a.is_finite());
            }
        }
    }
    let wall = started.elapsed().as_secs_f64();
    let damage = setup.driver.damage();
    let back_edge = rest
        .iter()
        .zip(&damage)
        .filter(|(x, &d)| d >= ON_A_CRACK && x[1] < 0.005 && x[0] > 0.075 && x[0] < 0.125)
        .count();
    let cell = 0.2 / cells[0] as f64;
    Ok(KwRun {
        cells,
        cell,
        particles: setup.info.particles,
        wall,
        steps: done,
        angles,
        tips,
        rayleigh: rayleigh_speed(190e9, 0.3, 8000.0),
        back_edge,
        panel: damage_panel(&rest, &damage, cell, format!("{:.2} mm cells", cell * 1e3)),
    })
}

/// The particles in the plate's top half (z) as triangles of side `cell / 2` (m, drawn in mm)
/// at their rest positions, valued by damage.
fn damage_panel(rest: &[[f64; 3]], damage: &[f64], cell: f64, caption: String) -> Panel {
    let z_mid = 0.0045;
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
    ]);
    let show = |a: Option<f64>| a.map_or("-".to_string(), |a| format!("{a:.1}"));
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
        ]);
    }
    let facets = Facets {
        title: "Kalthoff-Winkler: damage at 90 us (mm)".into(),
        scale: ("damage".into(), 0.6),
        panels: runs.iter().map(|r| r.panel.clone()).collect(),
        rows: 1,
    };
    (table, facets)
}

#[cfg(test)]
mod tests {
    use super::*;

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
