//! Mutated valid files never make a reader panic: each returns Ok or Err.

mod common;

use perifrac_io::{
    read_ply_crack, read_surface, read_tet_mesh, write_ply, write_tet_mesh, PlyEncoding,
    SurfaceRef, TetFormat,
};
use proptest::prelude::*;
use std::path::Path;

/// Valid seed files, one per reader, as (file name, bytes).
fn seeds() -> Vec<(String, Vec<u8>)> {
    let dir = tempfile::tempdir().unwrap();
    let mesh = common::small_mesh();
    let mut out = Vec::new();
    for (format, name) in [
        (TetFormat::Medit, "s.mesh"),
        (TetFormat::Gmsh22, "s22.msh"),
        (TetFormat::Gmsh41, "s41.msh"),
        (TetFormat::Vtk, "s.vtk"),
        (TetFormat::TetGen, "s.node"),
    ] {
        write_tet_mesh(&dir.path().join(name), &mesh, format).unwrap();
    }
    for name in [
        "s.mesh", "s22.msh", "s41.msh", "s.vtk", "s.node", "s.ele", "s.face",
    ] {
        out.push((
            name.to_string(),
            std::fs::read(dir.path().join(name)).unwrap(),
        ));
    }
    let crack = [0u8, 1];
    let colors = [[1u8, 2, 3]; 5];
    let surf = SurfaceRef {
        vertices: &mesh.vertices,
        faces: &mesh.boundary_faces,
        crack: Some(&crack),
        colors: Some(&colors),
        ..Default::default()
    };
    for (enc, name) in [
        (PlyEncoding::Ascii, "a.ply"),
        (PlyEncoding::BinaryLittleEndian, "b.ply"),
    ] {
        write_ply(&dir.path().join(name), &surf, enc).unwrap();
        out.push((
            name.to_string(),
            std::fs::read(dir.path().join(name)).unwrap(),
        ));
    }
    out.push((
        "s.off".into(),
        b"OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n4 0 1 2 3 1 1 1\n".to_vec(),
    ));
    out.push((
        "s.obj".into(),
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 3 4\n".to_vec(),
    ));
    out
}

#[derive(Debug, Clone)]
enum Mutation {
    Truncate(usize),
    Replace(usize, u8),
    DeleteLine(usize),
    InsertLine(usize, String),
    SwapTokens(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (
            any::<usize>(),
            prop_oneof![
                Just(b'9'),
                Just(b' '),
                Just(b'\n'),
                Just(b'-'),
                Just(b'#'),
                Just(b'$'),
                Just(0xff),
                any::<u8>()
            ]
        )
            .prop_map(|(i, b)| Mutation::Replace(i, b)),
        any::<usize>().prop_map(Mutation::DeleteLine),
        (
            any::<usize>(),
            prop_oneof![
                Just("0".to_string()),
                Just("4294967295 1 2 3 4".to_string()),
                Just("nan".to_string()),
                Just("$EndNodes".to_string()),
                Just("99999999999999999999".to_string()),
                "[ -~]{0,20}"
            ]
        )
            .prop_map(|(i, s)| Mutation::InsertLine(i, s)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapTokens(a, b)),
    ]
}

fn apply(data: &[u8], m: &Mutation) -> Vec<u8> {
    let len = data.len().max(1);
    match m {
        Mutation::Truncate(i) => data[..i % len.min(data.len() + 1)].to_vec(),
        Mutation::Replace(i, b) => {
            let mut d = data.to_vec();
            if !d.is_empty() {
                d[i % len] = *b;
            }
            d
        }
        Mutation::DeleteLine(i) | Mutation::InsertLine(i, _) => {
            let mut lines: Vec<Vec<u8>> = data.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
            let k = i % lines.len();
            match m {
                Mutation::InsertLine(_, s) => lines.insert(k, s.as_bytes().to_vec()),
                _ => {
                    lines.remove(k);
                }
            }
            lines.join(&b'\n')
        }
        Mutation::SwapTokens(a, b) => {
            let text = String::from_utf8_lossy(data).into_owned();
            let mut toks: Vec<&str> = text.split(' ').collect();
            let (x, y) = (a % toks.len(), b % toks.len());
            toks.swap(x, y);
            toks.join(" ").into_bytes()
        }
    }
}

fn read_any(path: &Path) {
    let name = path.to_string_lossy();
    if name.ends_with(".ply") {
        let _ = read_ply_crack(path);
    } else if name.ends_with(".off") || name.ends_with(".obj") {
        let _ = read_surface(path);
    } else {
        let _ = read_tet_mesh(path);
    }
}

proptest! {
    // A few hundred cases keeps this to seconds (the brief's budget); each case reads one file.
    #![proptest_config(ProptestConfig { cases: 400, .. ProptestConfig::default() })]
    #[test]
    fn mutated_files_never_panic(which in any::<usize>(), muts in proptest::collection::vec(mutation(), 1..4)) {
        let seeds = seeds();
        let (name, data) = &seeds[which % seeds.len()];
        let dir = tempfile::tempdir().unwrap();
        // TetGen needs all siblings present; mutate only the chosen one.
        for (other, d) in &seeds {
            std::fs::write(dir.path().join(other), d).unwrap();
        }
        let mut bytes = data.clone();
        for m in &muts {
            bytes = apply(&bytes, m);
        }
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        read_any(&path);
    }
}
