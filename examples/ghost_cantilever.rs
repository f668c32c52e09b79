//! Complete the families a bar's faces cut with ghost particles (`perifrac_physics::ghost`,
//! issue 18) and sag it as a cantilever under its own weight: the fitted default, then affine
//! and quadratic ghosts, each clamped by the bar's mirror image across x = 0 (a clamped ghost
//! face, so no particle is held). Prints each ghost layer's report and the tip against the
//! converged answer of `perifrac bench accuracy`'s quadratic tets.
//!
//! Run: `cargo run --release --example ghost_cantilever -- [CELLS_ALONG]` (default 20: a
//! 1 x 0.1 x 0.1 m bar of 20 x 2 x 2 cells, unstructured tets, 30 s or so on two cores).

use perifrac_physics::{
    ChenMaterial, ChenOptions, Discretization, Explicit, ExplicitConfig, FaceKind, ForceModel,
    GhostFit, GhostPlane, Ghosted, Loads, TimeStep,
};
use perifrac_topology::mesher::unstructured::unstructured_box;
use perifrac_topology::TetMesh;

/// The converged tip deflection (m): quadratic tets at 80 x 8 x 8 cells.
const P2_TIP: f64 = 1.472777e-2;

/// The bar's side faces (free) and its root x = 0 (clamped).
fn faces() -> Vec<GhostPlane> {
    let faces = GhostPlane::box_faces([0.0, -0.05, -0.05], [1.0, 0.05, 0.05]);
    let mut planes = faces[2..].to_vec();
    planes.push(GhostPlane {
        kind: FaceKind::Clamped,
        ..faces[0]
    });
    planes
}

/// Relaxes `model` under gravity with critical damping of the first bending mode and returns
/// the deflection (m) of the free end, from a line through the last two cells' particles.
fn sag(model: impl ForceModel, cell: f64) -> Result<f64, Box<dyn std::error::Error>> {
    let rest = model.discretization().rest_positions().to_vec();
    let horizon = model.discretization().horizon();
    // Euler-Bernoulli's first bending frequency of the clamped bar (E = 1e8 Pa, rho = 1000)
    let w1 = 1.875104f64.powi(2) * (1e8 * 0.1f64.powi(2) / 12.0 / 1000.0).sqrt();
    let loads = Loads::new(rest.len())
        .with_gravity([0.0, 0.0, -9.81])
        .with_damping(2.0 * w1)?;
    let config = ExplicitConfig {
        dt: TimeStep::Auto { safety: 0.8 },
        guard_fraction: 0.5,
    };
    let mut sim = Explicit::new(model, &rest, horizon, loads, config)?;
    let steps = (12.0 / w1 / sim.dt()).ceil() as u64;
    for _ in 0..steps {
        sim.step()?;
    }
    // the deflection along the last two cells, fitted by a line and read at the end, x = 1 m
    let tip: Vec<usize> = (0..rest.len())
        .filter(|&i| rest[i][0] > 1.0 - 2.0 * cell)
        .collect();
    let y = sim.positions();
    let n = tip.len() as f64;
    let mx = tip.iter().map(|&i| rest[i][0]).sum::<f64>() / n;
    let mu = tip.iter().map(|&i| y[i][2] - rest[i][2]).sum::<f64>() / n;
    let (mut sxu, mut sxx) = (0.0, 0.0);
    for &i in &tip {
        let dx = rest[i][0] - mx;
        sxu += dx * (y[i][2] - rest[i][2] - mu);
        sxx += dx * dx;
    }
    Ok(-(mu + sxu / sxx * (1.0 - mx)))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let nx: usize = std::env::args().nth(1).map_or(Ok(20), |a| a.parse())?;
    let n = (nx / 10).max(1);
    let mesh = unstructured_box([0.0, -0.05, -0.05], [1.0, 0.05, 0.05], [nx, n, n], 1)?;
    let (mesh, _) = TetMesh::new(mesh.vertices, mesh.tets)?;
    let horizon = 1.5 * mesh.mean_edge_length();
    let (disc, _) = Discretization::from_tets(
        &mesh.rest_barycentres(),
        &mesh.rest_volumes(),
        mesh.neighbours(),
        horizon,
    )?;
    println!("{nx} x {n} x {n} cells, {} particles", disc.len());
    let soft = ChenMaterial::from_young_poisson(1e8, 0.3, 1000.0)?;
    let m = std::slice::from_ref(&soft);
    let cell = 1.0 / nx as f64;
    let clamp_only: Vec<GhostPlane> = faces()
        .into_iter()
        .filter(|p| p.kind == FaceKind::Clamped)
        .collect();
    let runs = [
        ("fitted, mirror clamp", clamp_only, GhostFit::Affine),
        ("affine ghosts, mirror clamp", faces(), GhostFit::Affine),
        (
            "quadratic ghosts, mirror clamp",
            faces(),
            GhostFit::Quadratic,
        ),
    ];
    for (name, planes, fit) in runs {
        let model = Ghosted::chen(disc.clone(), m, ChenOptions::default(), &planes, fit)?;
        let r = model.layer().report().clone();
        let tip = sag(model, cell)?;
        println!(
            "{name}: {} ghosts, gain median {:.1} largest {:.1}; tip {tip:.4e} m, {:+.2}% against P2",
            r.ghosts,
            r.gain.median,
            r.gain.max,
            100.0 * (tip / P2_TIP - 1.0)
        );
    }
    Ok(())
}
