//! Twist a rubber bar through a full turn with Xu's hyperelastic model from code, once with the
//! implicit quasi-Newton step (one step per 1/24 s frame) and once with explicit velocity
//! Verlet, and compare what each cost and where the bar ended: the two integrators drive the
//! same model through the same `Solver` interface the scene driver uses.
//!
//! Run: `cargo run --release --example twist_implicit`.

use std::f64::consts::PI;
use std::time::Instant;

use perifrac_physics::math::Vec3;
use perifrac_physics::{
    AnchorMotion, Curve, Discretization, Explicit, ExplicitConfig, Implicit, ImplicitConfig, Loads,
    NoEnvironment, Solver, XuMaterial, XuModel, XuModuli, XuOptions,
};
use perifrac_topology::primitives;

/// Mean rotation (degrees) about the x axis of the particles within 1 cm of mid-span.
fn mid_span_turn(rest: &[Vec3], y: &[Vec3]) -> f64 {
    let picked: Vec<f64> = rest
        .iter()
        .zip(y)
        .filter(|(x, _)| (x[0] - 0.25).abs() < 0.01)
        .map(|(x, y)| (y[2].atan2(y[1]) - x[2].atan2(x[1])).rem_euclid(2.0 * PI))
        .collect();
    picked.iter().sum::<f64>() / picked.len() as f64 * 180.0 / PI
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A 0.5 x 0.05 x 0.05 m bar on the x axis, 20 x 2 x 2 cells (480 particles).
    let mesh = primitives::box_mesh([0.0, -0.025, -0.025], [0.5, 0.05, 0.05], [20, 2, 2]);
    let rest = mesh.rest_barycentres();
    let horizon = 1.5 * mesh.mean_edge_length();
    let (disc, report) =
        Discretization::from_tets(&rest, &mesh.rest_volumes(), mesh.neighbours(), horizon)?;
    println!("{} particles, {} bonds", rest.len(), report.bonds);
    let rubber = XuMaterial::from_young_poisson(
        1e6,
        0.3,
        1000.0,
        Curve::NeoHookean,
        Curve::NeoHookean,
        XuModuli::Consistent,
    )?;
    let model = XuModel::new(disc, &[rubber], XuOptions::default())?;

    // The left end turns half a turn per second about the x axis; the right end is held.
    let mut loads = Loads::new(rest.len());
    let pick = |f: &dyn Fn(f64) -> bool| -> Vec<u32> {
        (0..rest.len() as u32)
            .filter(|&i| f(rest[i as usize][0]))
            .collect()
    };
    let turning = AnchorMotion {
        velocity: [0.0; 3],
        angular: [PI, 0.0, 0.0],
        center: [0.0; 3],
    };
    loads.anchor_motion(&pick(&|x| x < 0.025), turning)?;
    loads.anchor(&pick(&|x| x > 0.475), [0.0; 3])?;

    let duration = 2.0; // s: a full turn
    let implicit = Implicit::new(
        model.clone(),
        &rest,
        loads.clone(),
        ImplicitConfig::with_dt(1.0 / 24.0),
    )?;
    let explicit = Explicit::new(model, &rest, horizon, loads, ExplicitConfig::default())?;
    let mut solvers: Vec<(&str, Box<dyn Solver>)> = vec![
        ("implicit", Box::new(implicit)),
        ("explicit", Box::new(explicit)),
    ];
    for (name, solver) in solvers.iter_mut() {
        let started = Instant::now();
        let steps = (duration / solver.dt()).round() as u64;
        for _ in 0..steps {
            solver.step(&mut NoEnvironment)?;
        }
        let stats = solver.stats();
        println!(
            "{name}: {steps} steps of {:.2e} s in {:.2} s, {} iterations; mid-span turned \
             {:.1} degrees, elastic energy {:.3} J",
            solver.dt(),
            started.elapsed().as_secs_f64(),
            stats.iterations,
            mid_span_turn(&rest, solver.positions()),
            solver.elastic_energy()
        );
    }
    Ok(())
}
