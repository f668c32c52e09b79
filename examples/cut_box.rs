//! Cut a box in two along a plane, pull the halves apart by advecting the mesh with particle
//! velocities, and export the crack surface as PLY (with the per-face `crack` flag Blender can
//! use for a second material) and as a POV-Ray `mesh2` include.
//!
//! Run: `cargo run --release --example cut_box -- [OUT_DIR]` (default `out/cut_box`).

use std::path::PathBuf;

use perifrac_io::{write_ply, write_povray_mesh2, PlyEncoding, SurfaceRef};
use perifrac_topology::primitives;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "out/cut_box".into()),
    );
    std::fs::create_dir_all(&out)?;

    // A 1 x 0.5 x 0.5 m block, 20 x 10 x 10 cells of 6 tets.
    let mut mesh = primitives::box_mesh([0.0; 3], [1.0, 0.5, 0.5], [20, 10, 10]);
    let centres = mesh.rest_barycentres();

    // Physics would report broken bonds; here every face-adjacent pair straddling x = 0.5 breaks.
    let mut broken = Vec::new();
    for (t, nbrs) in mesh.neighbours().iter().enumerate() {
        for &n in nbrs {
            let n_ok = n != perifrac_topology::NO_TET && (n as usize) > t;
            if n_ok && (centres[t][0] < 0.5) != (centres[n as usize][0] < 0.5) {
                broken.push((t as u32, n));
            }
        }
    }
    let cracked = mesh.crack_bonds(&broken);
    let split = mesh.split();
    println!(
        "{} broken bonds -> {cracked} crack faces; {} vertices split into {} new copies; {} pieces",
        broken.len(),
        split.vertices_split,
        split.copies_added,
        mesh.pieces().count
    );

    // Particles (one per tet) fly apart at 1 m/s each way; vertices follow by mass-weighted
    // advection over 10 steps of 10 ms.
    let masses: Vec<f64> = mesh.rest_volumes().iter().map(|v| 1000.0 * v).collect();
    let velocities: Vec<[f64; 3]> = centres
        .iter()
        .map(|c| [if c[0] < 0.5 { -1.0 } else { 1.0 }, 0.0, 0.0])
        .collect();
    for _ in 0..10 {
        mesh.advect(0.01, &masses, &velocities);
    }

    let surface = mesh.surface();
    // Colour each piece so the split is visible in any viewer.
    let palette = [[200, 90, 60], [60, 120, 200]];
    let mut colors = vec![[128u8; 3]; surface.vertices.len()];
    for (face, &piece) in surface.faces.iter().zip(&surface.piece) {
        for &v in face {
            colors[v as usize] = palette[piece as usize % palette.len()];
        }
    }
    let view = SurfaceRef {
        vertices: &surface.vertices,
        faces: &surface.faces,
        crack: Some(&surface.crack),
        colors: Some(&colors),
        ..Default::default()
    };
    write_ply(
        &out.join("cut_box.ply"),
        &view,
        PlyEncoding::BinaryLittleEndian,
    )?;
    write_povray_mesh2(&out.join("cut_box.inc"), &view, "cut_box")?;
    let crack_faces = surface.crack.iter().filter(|&&c| c == 1).count();
    println!(
        "wrote {}/cut_box.ply and cut_box.inc: {} triangles, {crack_faces} of them crack faces",
        out.display(),
        surface.faces.len()
    );
    Ok(())
}
