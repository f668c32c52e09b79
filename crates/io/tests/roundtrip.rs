//! Write-then-read round trips for every tet format, and the real Medit files.

mod common;

use common::{assert_same, mesh_dir, small_mesh};
use perifrac_io::{read_tet_mesh, write_tet_mesh, TetFormat, TetMeshData};

const FORMATS: [(TetFormat, &str); 5] = [
    (TetFormat::TetGen, "m.node"),
    (TetFormat::Medit, "m.mesh"),
    (TetFormat::Gmsh22, "m22.msh"),
    (TetFormat::Gmsh41, "m41.msh"),
    (TetFormat::Vtk, "m.vtk"),
];

fn round_trip_all(mesh: &TetMeshData, what: &str) {
    let dir = tempfile::tempdir().unwrap();
    for (format, name) in FORMATS {
        let path = dir.path().join(name);
        write_tet_mesh(&path, mesh, format).unwrap();
        let back = read_tet_mesh(&path).unwrap();
        assert_same(mesh, &back, &format!("{what} via {format:?}"));
        assert!(back.skipped.is_empty(), "{format:?}: {:?}", back.skipped);
    }
}

#[test]
fn every_reader_records_the_line_of_each_tet() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = small_mesh();
    for (format, name) in FORMATS {
        let path = dir.path().join(name);
        write_tet_mesh(&path, &mesh, format).unwrap();
        let back = read_tet_mesh(&path).unwrap();
        assert_eq!(back.tet_lines.len(), back.tets.len(), "{format:?}");
        // Each tet's line of the file the lines count in (the .ele for TetGen) lists its
        // corners, as written: 1-based in every format but VTK and TetGen's 0-based files.
        let text = std::fs::read_to_string(perifrac_io::tet_lines_file(&path)).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (t, &line) in back.tet_lines.iter().enumerate() {
            let numbers: Vec<u64> = lines[line - 1]
                .split_whitespace()
                .filter_map(|w| w.parse().ok())
                .collect();
            let corners = mesh.tets[t];
            let listed = |base: u64| {
                numbers.windows(4).any(|w| {
                    w.iter()
                        .zip(corners)
                        .all(|(&a, c)| a == u64::from(c) + base)
                })
            };
            assert!(
                listed(0) || listed(1),
                "{format:?}: tet {t} line {line}: {}",
                lines[line - 1]
            );
        }
    }
}

#[test]
fn small_mesh_round_trips_bit_exactly() {
    round_trip_all(&small_mesh(), "small");
}

#[test]
fn mesh_without_faces_or_labels_round_trips() {
    let mut m = small_mesh();
    m.boundary_faces.clear();
    m.tet_labels = vec![0, 0];
    round_trip_all(&m, "plain");
}

#[test]
fn tetgen_reads_from_ele_path_too() {
    let dir = tempfile::tempdir().unwrap();
    let m = small_mesh();
    write_tet_mesh(&dir.path().join("x.ele"), &m, TetFormat::TetGen).unwrap();
    assert!(dir.path().join("x.node").is_file() && dir.path().join("x.face").is_file());
    assert_same(
        &m,
        &read_tet_mesh(&dir.path().join("x.ele")).unwrap(),
        "x.ele",
    );
    // Rewriting without faces removes the stale .face so the round trip still holds.
    let mut plain = m.clone();
    plain.boundary_faces.clear();
    write_tet_mesh(&dir.path().join("x.node"), &plain, TetFormat::TetGen).unwrap();
    assert_same(
        &plain,
        &read_tet_mesh(&dir.path().join("x.node")).unwrap(),
        "x.node",
    );
}

#[test]
fn real_medit_files() {
    let Some(dir) = mesh_dir() else { return };
    // Counts from the files' own Vertices/Tetrahedra headers (and the brief).
    for (name, nv, nt) in [
        ("bunny.mesh", 5_433, 34_055),
        ("octopus-low.mesh", 452, 1_140),
    ] {
        let m = read_tet_mesh(&dir.join(name)).unwrap();
        assert_eq!((m.vertices.len(), m.tets.len()), (nv, nt), "{name}");
        assert_eq!(m.tet_labels.len(), nt);
        round_trip_all(&m, name);
    }
}
