//! Cut a box along a plane that no lattice direction follows, so the crack is the lattice's
//! staircase, then relax its crack faces towards their local plane as `perifrac run` does for
//! every frame (`[output] smooth_cracks`), and write both surfaces as PLY with the crack flag.
//!
//! Run: `cargo run --release --example smooth_crack -- [OUT_DIR]` (default `out/smooth_crack`).

use std::path::PathBuf;

use perifrac_io::{write_ply, PlyEncoding, SurfaceRef};
use perifrac_topology::{primitives, CrackSmoothing, Surface};

/// Area-weighted mean angle (degrees) between the crack faces' normals and `n`.
fn lean(s: &Surface, n: [f64; 3]) -> f64 {
    let (mut sum, mut area) = (0.0, 0.0);
    for (face, _) in s.faces.iter().zip(&s.crack).filter(|(_, &c)| c == 1) {
        let [a, b, c] = face.map(|k| s.vertices[k as usize]);
        let (u, v) = (
            [0, 1, 2].map(|k| b[k] - a[k]),
            [0, 1, 2].map(|k| c[k] - a[k]),
        );
        let m = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let l = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
        let cos = ((m[0] * n[0] + m[1] * n[1] + m[2] * n[2]) / l)
            .abs()
            .min(1.0);
        sum += l * cos.acos().to_degrees();
        area += l;
    }
    sum / area
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "out/smooth_crack".into()),
    );
    std::fs::create_dir_all(&out)?;

    // A 1 m cube of 12 x 12 x 12 cells, cut through its centre across the plane with normal n:
    // every face between two tets whose barycentres lie on either side cracks.
    let n = {
        let v = [1.0f64, 0.5, 0.2];
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|c| c / l)
    };
    let mut mesh = primitives::box_mesh([0.0; 3], [1.0; 3], [12, 12, 12]);
    let centres = mesh.rest_barycentres();
    let side = |p: [f64; 3]| (0..3).map(|k| (p[k] - 0.5) * n[k]).sum::<f64>() > 0.0;
    let mut broken = Vec::new();
    for (t, nbrs) in mesh.neighbours().iter().enumerate() {
        for &o in nbrs {
            if o != perifrac_topology::NO_TET
                && (o as usize) > t
                && side(centres[t]) != side(centres[o as usize])
            {
                broken.push((t as u32, o));
            }
        }
    }
    mesh.crack_bonds(&broken);
    mesh.split();

    let cut = mesh.surface();
    let mut smoothed = cut.clone();
    let report = smoothed.smooth_cracks(&CrackSmoothing::default());
    for (name, s) in [("as_cut", &cut), ("smoothed", &smoothed)] {
        let view = SurfaceRef {
            vertices: &s.vertices,
            faces: &s.faces,
            crack: Some(&s.crack),
            ..Default::default()
        };
        let path = out.join(format!("{name}.ply"));
        write_ply(&path, &view, PlyEncoding::BinaryLittleEndian)?;
        println!(
            "{}: crack faces lean {:.1} degrees from the plane on average",
            path.display(),
            lean(s, n)
        );
    }
    println!(
        "{} vertices moved ({} held back in some pass to keep faces from folding)",
        report.moved, report.held
    );
    Ok(())
}
