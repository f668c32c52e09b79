//! Benchmark of crack + split cost per crack face, mesh build, surface extraction and memory.
//!
//! Run: `cargo bench -p perifrac-topology --bench split`. Prints figures; asserts nothing.

use perifrac_topology::faces::FACE_CORNERS;
use perifrac_topology::{primitives, TetMesh, NO_TET};
use std::hint::black_box;
use std::time::Instant;

/// Interior faces whose three rest vertices lie on the plane x = 0.5.
fn plane_faces(m: &TetMesh) -> Vec<(u32, u8)> {
    let mut out = Vec::new();
    for (t, nb) in m.neighbours().iter().enumerate() {
        for (f, &n) in nb.iter().enumerate() {
            if n == NO_TET || (n as usize) < t {
                continue;
            }
            let tet = m.tets()[t];
            if FACE_CORNERS[f]
                .iter()
                .all(|&k| m.rest_positions()[tet[k] as usize][0] == 0.5)
            {
                out.push((t as u32, f as u8));
            }
        }
    }
    out
}

fn run(cells: usize) {
    let t0 = Instant::now();
    let (v, t) = primitives::box_data([0.0; 3], [1.0; 3], [cells; 3]);
    let data_s = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let (mesh, _) = TetMesh::new(v, t).expect("box is valid");
    let build_s = t0.elapsed().as_secs_f64();
    let faces = plane_faces(&mesh);
    let mut best = f64::INFINITY;
    let mut cut = mesh.clone();
    for _ in 0..5 {
        let mut m = mesh.clone();
        let t0 = Instant::now();
        for &(t, f) in &faces {
            black_box(m.crack_face(t, f).expect("interior face"));
        }
        let report = black_box(m.split());
        best = best.min(t0.elapsed().as_secs_f64());
        assert!(report.copies_added > 0);
        cut = m;
    }
    let t0 = Instant::now();
    let surface = black_box(cut.surface());
    let surface_s = t0.elapsed().as_secs_f64();
    let pieces = cut.pieces().count;
    let n = mesh.num_tets() as f64;
    println!(
        "{cells}^3 cells, {} tets: build {:.1} ms (+ {:.1} ms box data), crack+split {} faces \
         best {:.3} ms = {:.3} us/face, surface {} tris in {:.1} ms, {} pieces, memory {:.1} \
         B/tet fresh, {:.1} B/tet cut",
        mesh.num_tets(),
        build_s * 1e3,
        data_s * 1e3,
        faces.len(),
        best * 1e3,
        best * 1e6 / faces.len() as f64,
        surface.faces.len(),
        surface_s * 1e3,
        pieces,
        mesh.memory_bytes() as f64 / n,
        cut.memory_bytes() as f64 / n,
    );
}

fn main() {
    // 30^3 * 6 = 162k tets and 56^3 * 6 = 1.05M tets.
    for cells in [30, 56] {
        run(cells);
    }
}
