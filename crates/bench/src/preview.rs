//! Preview and final alike: a scene run at a coarse, a middle and a fine resolution breaks into
//! the same large fragments, with the same mass shares and a damaged zone of the same size.
//! Each scene is run twice: with its `s_crit` (the paper's), and with the `fracture_energy`
//! that gives that `s_crit` at the middle resolution.

use std::path::{Path, PathBuf};
use std::time::Instant;

use perifrac_scene::{Scene, Setup};

use crate::error::BenchError;
use crate::fracture::ON_A_CRACK;
use crate::table::Table;
use crate::Effort;

/// The default wall.
const WALL: &str = include_str!("../../../data/scenes/wall.toml");
/// The bunny drop (its mesh is in `../shared/data`).
const BUNNY: &str = include_str!("../../../data/scenes/bunny_drop.toml");

/// A fragment counts as large from this share of the mass.
pub const LARGE: f64 = 0.01;

/// One scene at one resolution with one fracture key.
#[derive(Debug, Clone)]
pub struct PreviewRun {
    /// The scene's name.
    pub scene: &'static str,
    /// The resolution, as the scene gives it.
    pub resolution: String,
    /// The fracture key and its value, as written.
    pub key: String,
    /// Particles.
    pub particles: usize,
    /// The threshold the run used (1).
    pub s_crit: f64,
    /// Wall time of the steps (s).
    pub wall: f64,
    /// Mass shares of the fragments of at least [`LARGE`] of the mass, largest first.
    pub shares: Vec<f64>,
    /// The damaged zone's radius (m): the mass-weighted RMS distance of the particles with at
    /// least [`ON_A_CRACK`] damage from their centre, at rest.
    pub radius: f64,
    /// The share of the mass (0 to 1) in particles with at least [`ON_A_CRACK`] damage.
    pub damaged: f64,
}

/// A scene of the study: its name, text, the file it is read as, the line that sets its
/// resolution, the resolutions (as that line's replacement), the line that sets its threshold
/// and the paper's `s_crit`.
pub struct PreviewScene {
    /// The scene's name.
    pub name: &'static str,
    text: &'static str,
    path: PathBuf,
    resolution_line: &'static str,
    /// The resolutions, coarse to fine, as the line that sets each.
    pub resolutions: Vec<String>,
    threshold_line: &'static str,
    /// The paper's threshold (1).
    pub s_crit: f64,
}

/// The wall at 16, 24 and 32 cells across and the bunny at resolutions 14, 20 and 28 (the
/// wall alone at 16 cells for a quick run). The bunny needs `../shared/data`.
pub fn scenes(effort: Effort) -> Vec<PreviewScene> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/scenes");
    let wall = PreviewScene {
        name: "wall",
        text: WALL,
        path: root.join("wall.toml"),
        resolution_line: "cells = [24, 24, 3]",
        resolutions: match effort {
            Effort::Tiny => vec!["cells = [16, 16, 2]".into()],
            Effort::Full => vec![
                "cells = [16, 16, 2]".into(),
                "cells = [24, 24, 3]".into(),
                "cells = [32, 32, 4]".into(),
            ],
        },
        threshold_line: "s_crit = 0.0005",
        s_crit: 5e-4,
    };
    let bunny = PreviewScene {
        name: "bunny drop",
        text: BUNNY,
        path: root.join("bunny_drop.toml"),
        resolution_line: "resolution = 20",
        resolutions: vec![
            "resolution = 14".into(),
            "resolution = 20".into(),
            "resolution = 28".into(),
        ],
        threshold_line: "fracture_energy = 228.0",
        s_crit: 0.13,
    };
    match effort {
        Effort::Tiny => vec![wall],
        Effort::Full => vec![wall, bunny],
    }
}

impl PreviewScene {
    /// The scene's text at resolution `resolution` (a line of [`PreviewScene::resolutions`])
    /// with its threshold set by `key` (a line such as `s_crit = 0.13`).
    fn text(&self, resolution: &str, key: &str) -> String {
        self.text
            .replace(self.resolution_line, resolution)
            .replace(self.threshold_line, key)
    }

    /// The line that sets the paper's threshold.
    pub fn s_crit_line(&self) -> String {
        format!("s_crit = {}", self.s_crit)
    }

    /// The fracture energy (J/m^2) that gives the paper's `s_crit` at `resolution`: Chen's
    /// threshold from `G_c` goes as its square root, so one setup with `G_c = 1` gives it.
    pub fn matching_energy(&self, resolution: &str) -> Result<f64, BenchError> {
        let case = format!("{} {resolution}, matching energy", self.name);
        let text = self.text(resolution, "fracture_energy = 1.0");
        let scene = Scene::parse(&text, &self.path).map_err(|e| scene_error(&case, &e))?;
        let setup = Setup::new(&scene, Some(1)).map_err(|e| scene_error(&case, &e))?;
        let unit = setup
            .info
            .from_energy
            .first()
            .map(|f| f.s_crit)
            .ok_or_else(|| scene_error(&case, &"no threshold came from the energy"))?;
        Ok((self.s_crit / unit).powi(2))
    }

    /// Runs the scene at `resolution` with its threshold set by `key` to its end.
    pub fn run(
        &self,
        resolution: &str,
        key: &str,
        progress: &mut dyn FnMut(&str),
    ) -> Result<PreviewRun, BenchError> {
        let case = format!("{}, {resolution}, {key}", self.name);
        let text = self.text(resolution, key);
        if !text.contains(key) {
            return Err(scene_error(
                &case,
                &"the scene's threshold line is not where it was",
            ));
        }
        let scene = Scene::parse(&text, &self.path).map_err(|e| scene_error(&case, &e))?;
        let mut setup = Setup::new(&scene, None).map_err(|e| scene_error(&case, &e))?;
        progress(&format!(
            "preview: {case}, {} particles",
            setup.info.particles
        ));
        let s_crit = setup
            .info
            .from_energy
            .first()
            .map_or(self.s_crit, |f| f.s_crit);
        let rest: Vec<[f64; 3]> = setup
            .driver
            .solver()
            .model()
            .discretization()
            .rest_positions()
            .to_vec();
        let started = Instant::now();
        for _ in 0..setup.frames as u64 * setup.steps_per_frame {
            setup.driver.step().map_err(|cause| BenchError::Physics {
                case: case.clone(),
                cause,
            })?;
        }
        let wall = started.elapsed().as_secs_f64();
        let pieces = setup.driver.mesh().pieces();
        let masses = setup.driver.masses();
        let shares = large_shares(&pieces.piece_of_tet, pieces.count, masses);
        let damage = setup.driver.damage();
        let radius = damaged_radius(&rest, &damage, masses);
        let total: f64 = masses.iter().sum();
        let damaged = damage
            .iter()
            .zip(masses)
            .filter(|(&d, _)| d >= ON_A_CRACK)
            .map(|(_, &m)| m)
            .sum::<f64>()
            / total;
        Ok(PreviewRun {
            scene: self.name,
            resolution: resolution.to_string(),
            key: key.to_string(),
            particles: setup.info.particles,
            s_crit,
            wall,
            shares,
            radius,
            damaged,
        })
    }
}

fn scene_error(case: &str, e: &dyn std::fmt::Display) -> BenchError {
    BenchError::Scene {
        case: case.into(),
        message: e.to_string(),
    }
}

/// Mass shares of the pieces of at least [`LARGE`] of the mass, largest first; `piece[p]` is
/// particle `p`'s piece, `count` the pieces.
pub fn large_shares(piece: &[u32], count: usize, masses: &[f64]) -> Vec<f64> {
    let mut mass = vec![0.0; count];
    for (&k, &m) in piece.iter().zip(masses) {
        mass[k as usize] += m;
    }
    let total: f64 = mass.iter().sum();
    let mut shares: Vec<f64> = mass
        .iter()
        .map(|m| m / total)
        .filter(|&s| s >= LARGE)
        .collect();
    shares.sort_by(|a, b| b.total_cmp(a));
    shares
}

/// The mass-weighted RMS distance (m) of the particles with at least [`ON_A_CRACK`] damage from
/// their mass-weighted centre, at their rest positions `rest`; 0 when none is damaged.
pub fn damaged_radius(rest: &[[f64; 3]], damage: &[f64], masses: &[f64]) -> f64 {
    let on: Vec<usize> = (0..rest.len())
        .filter(|&p| damage[p] >= ON_A_CRACK)
        .collect();
    let total: f64 = on.iter().map(|&p| masses[p]).sum();
    if total <= 0.0 {
        return 0.0;
    }
    let centre: [f64; 3] =
        std::array::from_fn(|k| on.iter().map(|&p| masses[p] * rest[p][k]).sum::<f64>() / total);
    let r2: f64 = on
        .iter()
        .map(|&p| {
            let d: [f64; 3] = std::array::from_fn(|k| rest[p][k] - centre[k]);
            masses[p] * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        })
        .sum();
    (r2 / total).sqrt()
}

/// The share of the mass (0 to 1) in fragments of a different size between two runs: half the
/// sum of the differences of their large fragments' shares, matched largest to largest (a
/// fragment one run lacks counts as a share of 0).
pub fn share_distance(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().max(b.len());
    let at = |v: &[f64], k: usize| v.get(k).copied().unwrap_or(0.0);
    0.5 * (0..n).map(|k| (at(a, k) - at(b, k)).abs()).sum::<f64>()
}

/// How far a scene's runs with one key stray from its middle resolution's: the largest relative
/// difference in the number of large fragments, the largest [`share_distance`] (a share of the
/// mass) and the largest relative difference in the damaged zone's radius. `runs` are coarse
/// to fine.
pub fn spread(runs: &[&PreviewRun]) -> (f64, f64, f64) {
    let Some(mid) = runs.get(runs.len() / 2) else {
        return (0.0, 0.0, 0.0);
    };
    let rel = |a: f64, b: f64| if b == 0.0 { 0.0 } else { (a - b).abs() / b };
    let mut out = (0.0f64, 0.0f64, 0.0f64);
    for r in runs {
        out.0 = out
            .0
            .max(rel(r.shares.len() as f64, mid.shares.len() as f64));
        out.1 = out.1.max(share_distance(&r.shares, &mid.shares));
        out.2 = out.2.max(rel(r.radius, mid.radius));
    }
    out
}

/// The runs as a table, and each scene and key's spread.
pub fn report(runs: &[PreviewRun]) -> (Table, Table) {
    let mut t = Table::new(&[
        "scene",
        "resolution",
        "key",
        "particles",
        "s_crit",
        "wall (s)",
        "fragments over 1%",
        "their shares (%)",
        "damaged radius (mm)",
        "damaged mass (%)",
    ]);
    for r in runs {
        let shares: Vec<String> = r
            .shares
            .iter()
            .map(|s| format!("{:.1}", 100.0 * s))
            .collect();
        t.push(vec![
            r.scene.into(),
            r.resolution.clone(),
            r.key.clone(),
            r.particles.to_string(),
            format!("{:.4e}", r.s_crit),
            format!("{:.1}", r.wall),
            r.shares.len().to_string(),
            shares.join(", "),
            format!("{:.1}", 1e3 * r.radius),
            format!("{:.1}", 100.0 * r.damaged),
        ]);
    }
    let mut s = Table::new(&[
        "scene",
        "key",
        "fragments over 1%: largest relative difference",
        "mass in fragments of another size: largest",
        "damaged radius: largest relative difference",
    ]);
    let mut groups: Vec<(&str, &str)> = Vec::new();
    for r in runs {
        let k = (r.scene, r.key.split('=').next().unwrap_or("").trim());
        if !groups.contains(&k) {
            groups.push(k);
        }
    }
    for (scene, key) in groups {
        let group: Vec<&PreviewRun> = runs
            .iter()
            .filter(|r| r.scene == scene && r.key.split('=').next().unwrap_or("").trim() == key)
            .collect();
        let (count, shares, radius) = spread(&group);
        s.push(vec![
            scene.into(),
            key.into(),
            format!("{:.0}%", 100.0 * count),
            format!("{:.0}%", 100.0 * shares),
            format!("{:.0}%", 100.0 * radius),
        ]);
    }
    (t, s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_keep_large_pieces_largest_first() {
        // pieces 0..3 of masses 1, 97, 2, 0.5 (of 100.5): shares 0.995%, 96.5%, 1.99%, 0.5%
        let piece = [0, 1, 1, 2, 3];
        let masses = [1.0, 90.0, 7.0, 2.0, 0.5];
        let s = large_shares(&piece, 4, &masses);
        assert_eq!(s.len(), 2);
        assert!((s[0] - 97.0 / 100.5).abs() < 1e-12);
        assert!((s[1] - 2.0 / 100.5).abs() < 1e-12);
    }

    #[test]
    fn share_distance_counts_the_mass_that_differs() {
        // 60/40 against 50/30/20: 10 + 10 + 20 over 2 = 20% of the mass
        assert!((share_distance(&[0.6, 0.4], &[0.5, 0.3, 0.2]) - 0.2).abs() < 1e-12);
        assert_eq!(share_distance(&[0.7, 0.3], &[0.7, 0.3]), 0.0);
    }

    #[test]
    fn radius_of_a_damaged_ring() {
        // four damaged particles on a circle of 2 m about (1, 1, 0), one undamaged far away
        let rest = [
            [3.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [1.0, 3.0, 0.0],
            [1.0, -1.0, 0.0],
            [50.0, 0.0, 0.0],
        ];
        let damage = [0.5, 0.5, 0.5, 0.5, 0.0];
        let r = damaged_radius(&rest, &damage, &[1.0; 5]);
        assert!((r - 2.0).abs() < 1e-12);
        assert_eq!(damaged_radius(&rest, &[0.0; 5], &[1.0; 5]), 0.0);
    }
}
