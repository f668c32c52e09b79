//! An egg shell dropped on the ground cracks: the thin-shell model (crates/shell) with fracture,
//! contact with a ground plane and the paper's event search, its frames written as PLY (each
//! piece given the shell's thickness, crack walls flagged) and POV-Ray `mesh2` files.
//!
//! Run: `cargo run --release --example shell_egg -- [OUT_DIR] [SPEED_M_PER_S]` (default
//! `out/shell_egg`, 1 m/s; about a minute and a half). `docs/shell_egg.pov` renders a frame.

use std::path::PathBuf;

use perifrac_contact::{Colliders, ContactParams, GroundDesc};
use perifrac_io::{write_ply, write_povray_mesh2, PlyEncoding, SurfaceRef};
use perifrac_shell::{
    generate, SearchedShell, ShellDynamics, ShellFracture, ShellMaterial, ShellMesh, ShellModel,
    ShellSearch,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().unwrap_or("out/shell_egg".into()));
    let speed: f64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1.0);
    std::fs::create_dir_all(&out)?;
    // Half-axes 22 x 22 x 29 mm, 0.35 mm of shell (30 GPa), breaking at a strain of 2e-3.
    let h = 3.5e-4;
    let s = generate::ellipsoid([0.022, 0.022, 0.029], 4)?;
    let lift = 0.029 + 0.5 * h + 1e-4;
    let v: Vec<_> = s
        .vertices
        .iter()
        .map(|p| [p[0], p[1], p[2] + lift])
        .collect();
    let mesh = ShellMesh::new(v, s.triangles)?;
    let shellmat = ShellMaterial::new(30e9, 0.3, 2000.0, h)?;
    let model =
        ShellModel::new(mesh, shellmat)?.with_fracture(ShellFracture::new(2e-3, 2e-3, 0.25, 1.0)?);
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
    shell.set_colliders(
        Colliders::new(vec![ground], vec![], [0.0, 0.0, -9.81])?,
        0.5 * h,
    )?;
    let dt = 0.5 * shell.stable_step()?;
    let mut s = SearchedShell::new(shell, ShellSearch::default())?;
    let (frames, duration) = (10, 2e-3);
    let per_frame = (duration / frames as f64 / dt).ceil() as usize;
    for frame in 0..=frames {
        if frame > 0 {
            for _ in 0..per_frame {
                s.advance(dt)?;
            }
        }
        let model = s.shell().model();
        let m = model.frame(s.shell().positions(), s.shell().velocities(), Some(h));
        let surface = SurfaceRef {
            crack: Some(&m.crack),
            fragment: Some(&m.piece),
            normals: Some(&m.normals),
            velocities: Some(&m.velocities),
            ..SurfaceRef::new(&m.vertices, &m.triangles)
        };
        write_ply(
            &out.join(format!("egg_{frame:04}.ply")),
            &surface,
            PlyEncoding::BinaryLittleEndian,
        )?;
        write_povray_mesh2(&out.join(format!("egg_{frame:04}.inc")), &surface, "egg")?;
        let pieces = m.piece.iter().max().map_or(0, |p| p + 1);
        println!(
            "frame {frame:>2}: t = {:.3} ms, {} triangles broken so far, {pieces} pieces, {} sub-steps, {} discarded",
            1e3 * s.shell().time(),
            s.stats().events.len(),
            s.stats().substeps,
            s.stats().rejected
        );
    }
    println!("frames in {}", out.display());
    Ok(())
}
