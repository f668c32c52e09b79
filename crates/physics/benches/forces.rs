//! Force-loop benchmark (not a test): a box of >= 300,000 particles with about 100 bonds each.
//! Reports bond updates per second per core for the elastic, elastoplastic and fracturing paths,
//! seconds per step, family build time, bytes per bond, and 1 against 2 threads.
//!
//! Run: `cargo bench -p perifrac-physics --bench forces` (env `PERIFRAC_BENCH_CELLS=n` for an
//! n x n x n box of 6 n^3 particles, default 37; `PERIFRAC_BENCH_K` horizon factor, default 1.3 for ~100 bonds; `PERIFRAC_BENCH_EVALS`
//! timed repetitions, default 8, the fastest reported).

use perifrac_physics::{
    ChenMaterial, ChenModel, Discretization, Explicit, ExplicitConfig, ForceModel, FractureParams,
    Loads, TimeStep, Vec3, YieldParams,
};
use perifrac_topology::primitives::box_data;
use perifrac_topology::TetMesh;
use std::time::Instant;

fn env(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Fastest of `n` timed runs of `f` (s).
fn fastest(n: usize, mut f: impl FnMut()) -> f64 {
    (0..n)
        .map(|_| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let n = env("PERIFRAC_BENCH_CELLS", 37.0) as usize;
    let k = env("PERIFRAC_BENCH_K", 1.3);
    let evals = env("PERIFRAC_BENCH_EVALS", 8.0) as usize;
    let h = 0.01;
    let (v, t) = box_data([0.0; 3], [n as f64 * h; 3], [n; 3]);
    let (mesh, _) = TetMesh::new(v, t).expect("box");
    let x = mesh.rest_barycentres();
    let vol = mesh.rest_volumes();
    let delta = k * mesh.mean_edge_length();
    let t0 = Instant::now();
    let (disc, report) =
        Discretization::from_tets(&x, &vol, mesh.neighbours(), delta).expect("disc");
    let build = t0.elapsed().as_secs_f64();
    let np = disc.len();
    let nb = disc.family().num_bonds();
    println!(
        "box {n}^3 cells: {np} particles, {nb} directed bonds ({:.1} per particle, {}..{}), k = {k}",
        nb as f64 / np as f64,
        report.min_bonds,
        report.max_bonds
    );
    println!(
        "family build {build:.3} s ({} threads); family {:.1} bytes per bond",
        rayon::current_num_threads(),
        disc.family().memory_bytes() as f64 / nb as f64
    );
    let steel = ChenMaterial::from_young_poisson(200e9, 0.25, 7800.0).expect("steel");
    let b = 15.0 * steel.shear_modulus / (2.0 * std::f64::consts::PI * delta.powi(5));
    let a_y = 2.0 * delta * b * 5e-4;
    let mut plastic = steel.clone();
    plastic.plasticity = Some(YieldParams {
        psi0: 0.5 * a_y * a_y,
        gamma_ratio: 0.05,
        from_strain: false,
    });
    let mut brittle = steel.clone();
    brittle.fracture = Some(FractureParams {
        s_crit: 1e-2,
        alpha: 0.0,
    });
    // a smooth non-uniform 0.1% strain
    let l = n as f64 * h;
    let y: Vec<Vec3> = x
        .iter()
        .map(|p| {
            let (u, w) = (p[0] / l, p[2] / l);
            [
                p[0] * 1.001 + 1e-3 * l * u * w,
                p[1] * 0.9995,
                p[2] + 5e-4 * l * u * u,
            ]
        })
        .collect();
    for (name, mat) in [
        ("elastic", steel),
        ("elastoplastic", plastic),
        ("fracturing", brittle),
    ] {
        let model = ChenModel::new(disc.clone(), &[mat]).expect("model");
        println!(
            "{name}: model {:.1} bytes per bond (all arrays / directed bonds)",
            model.memory_bytes() as f64 / nb as f64
        );
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            pool.install(|| {
                let mut m = model.clone();
                let mut f = vec![[0.0; 3]; np];
                m.update_forces(&y, &mut f); // warm-up
                let per_eval = fastest(evals, || m.update_forces(&y, &mut f));
                let rate = nb as f64 / per_eval / threads as f64;
                // a whole step: kicks, drift, fracture check, forces
                let cfg = ExplicitConfig { dt: TimeStep::Fixed(1e-7), guard_fraction: 0.5 };
                let mut s = Explicit::new(m, &y, delta, Loads::new(np), cfg).expect("solver");
                s.step().expect("step");
                let per_step = fastest(evals, || {
                    s.step().expect("step");
                });
                println!(
                    "  {threads} thread(s): force evaluation {per_eval:.3} s = {:.1} M bond updates/s/core; step {per_step:.3} s",
                    rate / 1e6
                );
            });
        }
    }
}
