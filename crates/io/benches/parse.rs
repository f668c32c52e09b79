//! Read throughput per tet format on a synthetic ~1M-tet lattice.
//!
//! Run: `cargo bench -p perifrac-io --bench parse`. Writes the lattice in every format to a
//! temporary directory, then reads each file three times and prints the best MB/s (file bytes
//! divided by wall time of `read_tet_mesh`, which includes reading the file from the page cache).

use perifrac_io::{read_tet_mesh, write_tet_mesh, TetFormat, TetMeshData};
use std::path::Path;
use std::time::Instant;

/// Cubes per side: 55^3 cubes * 6 tets = 998,250 tets.
const N: usize = 55;

fn lattice() -> TetMeshData {
    let side = N + 1;
    let id = |i: usize, j: usize, k: usize| (i + side * (j + side * k)) as u32;
    let mut mesh = TetMeshData::default();
    for k in 0..side {
        for j in 0..side {
            for i in 0..side {
                // Irregular spacing so coordinates print with many digits, like real meshes.
                let f = |x: usize| x as f64 * 0.0137 + (x as f64 * 0.7).sin() * 1e-4;
                mesh.vertices.push([f(i), f(j), f(k)]);
            }
        }
    }
    // Kuhn subdivision: 6 tets around the main diagonal of every cube.
    let paths = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                for (p, axes) in paths.iter().enumerate() {
                    let mut c = [i, j, k];
                    let mut tet = [id(i, j, k); 4];
                    for (slot, &a) in tet.iter_mut().skip(1).zip(axes) {
                        c[a] += 1;
                        *slot = id(c[0], c[1], c[2]);
                    }
                    mesh.tets.push(tet);
                    mesh.tet_labels.push(1 + (p as i32 % 2));
                }
            }
        }
    }
    mesh
}

fn size(paths: &[&Path]) -> u64 {
    paths
        .iter()
        .map(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0))
        .sum()
}

fn main() {
    let mesh = lattice();
    let dir = tempfile::tempdir().expect("temp dir");
    println!(
        "lattice: {} vertices, {} tets; best of 3 reads",
        mesh.vertices.len(),
        mesh.tets.len()
    );
    let cases = [
        ("medit .mesh", TetFormat::Medit, "l.mesh", vec!["l.mesh"]),
        (
            "tetgen .node/.ele",
            TetFormat::TetGen,
            "l.node",
            vec!["l.node", "l.ele"],
        ),
        (
            "gmsh 4.1 .msh",
            TetFormat::Gmsh41,
            "l41.msh",
            vec!["l41.msh"],
        ),
        (
            "gmsh 2.2 .msh",
            TetFormat::Gmsh22,
            "l22.msh",
            vec!["l22.msh"],
        ),
        ("vtk legacy .vtk", TetFormat::Vtk, "l.vtk", vec!["l.vtk"]),
    ];
    for (label, format, name, files) in cases {
        let path = dir.path().join(name);
        let t0 = Instant::now();
        write_tet_mesh(&path, &mesh, format).expect("write");
        let write_s = t0.elapsed().as_secs_f64();
        let files: Vec<_> = files.iter().map(|f| dir.path().join(f)).collect();
        let refs: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
        let bytes = size(&refs) as f64;
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            let t = Instant::now();
            let back = read_tet_mesh(&path).expect("read");
            best = best.min(t.elapsed().as_secs_f64());
            assert_eq!(back.tets.len(), mesh.tets.len());
        }
        println!(
            "{label:<20} {:>7.1} MB  read {:>6.3} s  {:>6.1} MB/s   (write {:.2} s, {:.1} MB/s)",
            bytes / 1e6,
            best,
            bytes / 1e6 / best,
            write_s,
            bytes / 1e6 / write_s
        );
    }
}
