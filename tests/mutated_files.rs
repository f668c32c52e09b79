//! Mutated mesh files never make the reader or the topology build panic: they load or they
//! give an error. (The io crate fuzzes each reader alone; this adds topology validation.)

mod common;

use std::path::Path;

use perifrac_topology::TetMesh;
use proptest::prelude::*;

fn load_bytes(dir: &Path, name: &str, bytes: &[u8]) {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    if let Ok(data) = perifrac_io::read_tet_mesh(&path) {
        if let Ok((mesh, _)) = TetMesh::new(data.vertices, data.tets) {
            // Everything downstream of a successful load must hold up too.
            let _ = mesh.quality();
            let _ = mesh.surface();
            let _ = mesh.pieces();
        }
    }
}

fn octopus() -> Option<Vec<u8>> {
    common::shared_mesh("octopus-low.mesh").map(|p| std::fs::read(p).unwrap())
}

/// A small box mesh in each writer's format, so the test does not need ../shared.
fn samples(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let (vertices, tets) = perifrac_topology::primitives::box_data([0.0; 3], [1.0; 3], [2, 2, 1]);
    let data = perifrac_io::TetMeshData {
        tet_labels: vec![1; tets.len()],
        vertices,
        tets,
        boundary_faces: Vec::new(),
        skipped: Vec::new(),
        tet_lines: Vec::new(),
    };
    let mut out = Vec::new();
    for (name, format) in [
        ("s.mesh", perifrac_io::TetFormat::Medit),
        ("s.msh", perifrac_io::TetFormat::Gmsh41),
        ("s22.msh", perifrac_io::TetFormat::Gmsh22),
        ("s.vtk", perifrac_io::TetFormat::Vtk),
    ] {
        let p = dir.join(name);
        perifrac_io::write_tet_mesh(&p, &data, format).unwrap();
        out.push((name.to_string(), std::fs::read(&p).unwrap()));
    }
    out
}

#[derive(Debug, Clone)]
enum Mutation {
    Truncate(usize),
    Replace(usize, u8),
    DeleteLine(usize),
    DuplicateLine(usize),
}

fn apply(bytes: &[u8], m: &Mutation) -> Vec<u8> {
    let mut lines: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
    match *m {
        Mutation::Truncate(at) => bytes[..at % (bytes.len() + 1)].to_vec(),
        Mutation::Replace(at, b) => {
            let mut v = bytes.to_vec();
            if !v.is_empty() {
                let i = at % v.len();
                v[i] = b;
            }
            v
        }
        Mutation::DeleteLine(at) => {
            lines.remove(at % lines.len());
            lines.join(&b'\n')
        }
        Mutation::DuplicateLine(at) => {
            let i = at % lines.len();
            lines.insert(i, lines[i]);
            lines.join(&b'\n')
        }
    }
}

fn mutation() -> impl Strategy<Value = Mutation> {
    // Replacement bytes lean towards the ones that change meaning: digits, signs, separators.
    let byte = prop::sample::select(b"0123456789-.eE \nnaifx#\t".to_vec());
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), byte).prop_map(|(a, b)| Mutation::Replace(a, b)),
        any::<usize>().prop_map(Mutation::DeleteLine),
        any::<usize>().prop_map(Mutation::DuplicateLine),
    ]
}

proptest! {
    // 256 cases x 4 small files runs in about a second.
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn mutated_small_meshes_never_panic(ms in prop::collection::vec(mutation(), 1..4)) {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in samples(dir.path()) {
            let mut b = bytes;
            for m in &ms {
                b = apply(&b, m);
            }
            load_bytes(dir.path(), &name, &b);
        }
    }
}

proptest! {
    // The real octopus mesh (45 kB) is read whole per case; 64 cases keep this under a second.
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn mutated_octopus_never_panics(ms in prop::collection::vec(mutation(), 1..4)) {
        let Some(bytes) = octopus() else { return Ok(()) };
        let dir = tempfile::tempdir().unwrap();
        let mut b = bytes;
        for m in &ms {
            b = apply(&b, m);
        }
        load_bytes(dir.path(), "o.mesh", &b);
    }
}
