//! Tear a brittle bar in two from code: the physics crate breaks bonds, the topology crate cuts
//! the embedded tet mesh along the broken faces and advects it, the io crate writes PLY frames
//! (crack faces flagged). This is the step loop the scene driver will run.
//!
//! Run: `cargo run --release --example tear_bar -- [OUT_DIR]` (default `out/tear_bar`).

use std::path::PathBuf;

use perifrac_io::{write_ply, PlyEncoding, SurfaceRef};
use perifrac_physics::{
    ChenMaterial, ChenModel, Discretization, Explicit, ExplicitConfig, FractureParams, Loads,
};
use perifrac_topology::primitives;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "out/tear_bar".into()),
    );
    std::fs::create_dir_all(&out)?;

    // A 0.2 x 0.02 x 0.02 m steel-like bar, 20 x 2 x 2 cells (480 tets = 480 particles).
    let length = 0.2;
    let mut mesh = primitives::box_mesh([0.0; 3], [length, 0.02, 0.02], [20, 2, 2]);
    let rest = mesh.rest_barycentres();
    let volumes = mesh.rest_volumes();
    let horizon = 1.5 * mesh.mean_edge_length();
    let (disc, report) = Discretization::from_tets(&rest, &volumes, mesh.neighbours(), horizon)?;
    println!("{} particles, {} bonds", rest.len(), report.bonds);

    let mut material = ChenMaterial::from_young_poisson(200e9, 0.25, 7800.0)?;
    material.fracture = Some(FractureParams {
        s_crit: 1e-3,
        alpha: 0.0,
    });
    let masses: Vec<f64> = volumes.iter().map(|v| material.density * v).collect();
    let model = ChenModel::new(disc, &[material])?;
    let mut solver = Explicit::new(
        model,
        &rest,
        horizon,
        Loads::new(rest.len()),
        ExplicitConfig::default(),
    )?;
    // The halves fly apart at 5.5 m/s each: the tensile wave exceeds the critical stretch.
    for (v, p) in solver.velocities_mut().iter_mut().zip(&rest) {
        v[0] = if p[0] < length / 2.0 { -5.5 } else { 5.5 };
    }

    let steps_per_frame = 30;
    for frame in 0..10 {
        for _ in 0..steps_per_frame {
            let broken = solver.step()?;
            mesh.crack_bonds(broken);
            mesh.split();
            mesh.advect(solver.dt(), &masses, solver.velocities());
        }
        let surface = mesh.surface();
        let view = SurfaceRef {
            vertices: &surface.vertices,
            faces: &surface.faces,
            crack: Some(&surface.crack),
            colors: None,
            ..Default::default()
        };
        let path = out.join(format!("frame_{frame:04}.ply"));
        write_ply(&path, &view, PlyEncoding::BinaryLittleEndian)?;
        println!(
            "t = {:.3e} s: {} pieces, {} crack triangles -> {}",
            solver.time(),
            mesh.pieces().count,
            surface.crack.iter().filter(|&&c| c == 1).count(),
            path.display()
        );
    }
    Ok(())
}
