//! Mesh a box as unstructured tets (as scenes do by default, `[mesh] structure`), as the Kuhn
//! lattice and as the mirrored lattice, print their counts and quality, and write each as a
//! Medit `.mesh` file.
//!
//! Run: `cargo run --release --example unstructured_box -- [OUT_DIR]` (default
//! `out/unstructured_box`).

use std::path::PathBuf;

use perifrac_io::{write_tet_mesh, TetFormat, TetMeshData};
use perifrac_topology::mesher::unstructured::unstructured_box;
use perifrac_topology::{dihedral_angles_deg, primitives};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or("out/unstructured_box".into()),
    );
    std::fs::create_dir_all(&out)?;
    let (lo, hi, cells) = ([0.0; 3], [0.6, 0.6, 0.06], [24, 24, 3]);
    let m = unstructured_box(lo, hi, cells, 1)?;
    let (kv, kt) = primitives::box_data(lo, hi, cells);
    let mirrored = primitives::Lattice::Mirrored;
    let (mv, mt) = primitives::lattice_box_data(lo, hi, cells, mirrored);
    for (name, v, t) in [
        ("unstructured", &m.vertices, &m.tets),
        ("lattice", &kv, &kt),
        ("mirrored", &mv, &mt),
    ] {
        let min = t
            .iter()
            .flat_map(|tet| dihedral_angles_deg(tet.map(|k| v[k as usize])))
            .fold(f64::INFINITY, f64::min);
        println!(
            "{name}: {} vertices, {} tets, smallest dihedral angle {min:.1} degrees",
            v.len(),
            t.len()
        );
        let data = TetMeshData {
            vertices: v.clone(),
            tets: t.clone(),
            tet_labels: vec![0; t.len()],
            ..TetMeshData::default()
        };
        write_tet_mesh(&out.join(format!("{name}.mesh")), &data, TetFormat::Medit)?;
    }
    Ok(())
}
