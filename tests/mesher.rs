//! End-to-end tests of the built-in tet mesher (`perifrac_topology::mesher`) and of
//! `perifrac mesh SURFACE`: volume, angle and orientation guarantees on the shared models,
//! refusal of a flat model, and round trips through every tet format.

mod common;

use common::perifrac;
use std::path::Path;

use perifrac_io::TetFormat;
use perifrac_topology::mesher::{mesh_surface, MesherError, MesherOptions, MesherOutput};
use perifrac_topology::TetMesh;

/// The snap guard's bound (`mesher::snap::MIN_DIHEDRAL_DEG`), which the issue asks for.
const MIN_DIHEDRAL_DEG: f64 = 10.0;

/// Volume agreement the issue asks for (2%) against the surface's (capped) enclosed volume.
const VOLUME_TOLERANCE: f64 = 0.02;

/// Unit cube surface with outward faces.
fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    perifrac_topology::mesher::cube_surface([0.0; 3], [1.0; 3])
}

/// Checks the guarantees and returns the mesh built from the output.
fn check(name: &str, out: &MesherOutput) -> TetMesh {
    let r = &out.report;
    let rel = (r.mesh_volume / r.surface_volume - 1.0).abs();
    assert!(rel < VOLUME_TOLERANCE, "{name}: volume off by {rel}: {r:?}");
    assert!(r.min_dihedral_deg >= MIN_DIHEDRAL_DEG, "{name}: {r:?}");
    let (mesh, build) = TetMesh::new(out.vertices.clone(), out.tets.clone()).unwrap();
    assert_eq!(build.inverted_fixed, 0, "{name}: inverted tets");
    let q = mesh.quality();
    assert!(q.min_dihedral_deg >= MIN_DIHEDRAL_DEG, "{name}: {q:?}");
    // Every test model is one solid; loose fragments must have been dropped.
    assert_eq!(mesh.pieces().count, 1, "{name}: {:?}", r.fragments);
    // TetMesh sums the same tets: agreement to rounding (1e-9 relative).
    assert!((mesh.total_rest_volume() - r.mesh_volume).abs() <= 1e-9 * r.mesh_volume);
    eprintln!(
        "{name}: {} tets, volume {:+.3}%, min dihedral {:.2}, histogram {:?}",
        r.tets,
        100.0 * (r.mesh_volume / r.surface_volume - 1.0),
        q.min_dihedral_deg,
        q.dihedral_histogram
    );
    mesh
}

#[test]
fn cube_is_filled_and_snapped() {
    let (v, f) = cube();
    let opts = MesherOptions {
        resolution: Some(8),
        ..Default::default()
    };
    let out = mesh_surface(&v, &f, &opts).unwrap();
    check("cube", &out);
    // Enclosed volume of the unit cube, exactly (divergence theorem on 12 triangles).
    assert!((out.report.surface_volume - 1.0).abs() < 1e-12);
    assert!(out.report.problems.is_watertight());
    assert!(!out.report.used_winding_on_open_surface);
}

#[test]
fn inward_faces_are_reversed_and_open_surfaces_use_winding() {
    let (v, mut f) = cube();
    for t in &mut f {
        t.swap(1, 2);
    }
    let opts = MesherOptions {
        resolution: Some(6),
        ..Default::default()
    };
    let out = mesh_surface(&v, &f, &opts).unwrap();
    assert!(out.report.reoriented);
    check("inward cube", &out);
    // Remove two triangles (one face of the cube): still meshed, by winding number.
    let (v, mut f) = cube();
    f.truncate(10);
    let out = mesh_surface(&v, &f, &opts).unwrap();
    assert!(out.report.used_winding_on_open_surface);
    assert_eq!(out.report.problems.open_edges, 4);
    check("open cube", &out);
}

#[test]
fn flat_surfaces_and_bad_options_are_refused() {
    // A square sheet (two triangles) encloses nothing.
    let v = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let f = [[0, 1, 2], [0, 2, 3]];
    let err = mesh_surface(&v, &f, &MesherOptions::default()).unwrap_err();
    assert!(matches!(err, MesherError::EnclosesNoVolume { .. }), "{err}");
    let (v, f) = cube();
    let both = MesherOptions {
        edge_length: Some(0.1),
        resolution: Some(10),
    };
    assert!(matches!(
        mesh_surface(&v, &f, &both),
        Err(MesherError::BadSizing(_))
    ));
    let negative = MesherOptions {
        edge_length: Some(-1.0),
        resolution: None,
    };
    assert!(mesh_surface(&v, &f, &negative).is_err());
    let tiny = MesherOptions {
        edge_length: Some(1e-5),
        resolution: None,
    };
    assert!(matches!(
        mesh_surface(&v, &f, &tiny),
        Err(MesherError::TooFine { .. })
    ));
    let err = mesh_surface(&v, &[[0, 1, 99]], &MesherOptions::default()).unwrap_err();
    assert!(err.to_string().contains("99"), "{err}");
}

/// Meshes a shared model at `resolution` cells across its longest side.
fn mesh_shared(name: &str, resolution: usize) -> Option<(MesherOutput, TetMesh)> {
    let path = common::shared_mesh(name)?;
    let s = perifrac_io::read_surface(&path).unwrap();
    let opts = MesherOptions {
        resolution: Some(resolution),
        ..Default::default()
    };
    let out = mesh_surface(&s.vertices, &s.faces, &opts).unwrap();
    let mesh = check(name, &out);
    Some((out, mesh))
}

// Resolutions: coarse enough for CI (5k-25k tets); at these the volume error measured 0.1-1.2%.

#[test]
fn bunny_off_closed() {
    if let Some((out, _)) = mesh_shared("bunny.off", 16) {
        assert!(out.report.problems.is_watertight());
    }
}

#[test]
fn spot_closed_after_merging() {
    if let Some((out, _)) = mesh_shared("spot.obj", 16) {
        assert!(out.report.problems.is_watertight());
    }
}

#[test]
fn stanford_bunny_open_scan_by_winding_number() {
    if let Some((out, _)) = mesh_shared("stanford-bunny.obj", 16) {
        assert!(out.report.problems.open_edges > 0);
        assert!(out.report.used_winding_on_open_surface);
    }
}

#[test]
fn armadillo_closed() {
    mesh_shared("armadillo.obj", 30);
}

#[test]
fn generated_mesh_round_trips_through_every_format() {
    let Some((out, mesh)) = mesh_shared("bunny.off", 12) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.mesh", "b.vtk", "c.msh", "d.node"] {
        let path = dir.path().join(name);
        let data = perifrac_io::TetMeshData {
            vertices: mesh.positions().to_vec(),
            tets: mesh.tets().to_vec(),
            tet_labels: vec![0; mesh.num_tets()],
            boundary_faces: Vec::new(),
            skipped: Default::default(),
            tet_lines: Vec::new(),
        };
        perifrac_io::write_tet_mesh(&path, &data, TetFormat::from_path(&path).unwrap()).unwrap();
        let back = perifrac_io::read_tet_mesh(&path).unwrap();
        assert_eq!(back.tets.len(), out.tets.len(), "{name}");
        let (m, build) = TetMesh::new(back.vertices, back.tets).unwrap();
        assert_eq!(build.inverted_fixed, 0, "{name}");
        // Text formats round to 17 significant digits or fewer: 1e-9 relative covers them.
        let rel = (m.total_rest_volume() / out.report.mesh_volume - 1.0).abs();
        assert!(rel < 1e-9, "{name}: {rel}");
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn cli_meshes_a_surface_and_reports() {
    let Some(bunny) = common::shared_mesh("bunny.off") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bunny.mesh");
    let o = perifrac(&["mesh", s(&bunny), "--resolution", "12", "-o", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("open edges") && err.contains("min dihedral"),
        "{err}"
    );
    assert!(perifrac_io::read_tet_mesh(&out).unwrap().tets.len() > 1000);
}

#[test]
fn cli_refuses_woody() {
    let Some(woody) = common::shared_mesh("woody.obj") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("woody.mesh");
    let o = perifrac(&["mesh", s(&woody), "-o", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("encloses no volume"), "{err}");
    assert!(!out.exists());
}

#[test]
fn cli_tetgen_runs_or_says_it_is_missing() {
    let Some(bunny) = common::shared_mesh("bunny.off") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bunny.vtk");
    let o = perifrac(&["mesh", s(&bunny), "--tetgen", "-o", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    if common::have_program("tetgen") {
        assert!(o.status.success(), "{err}");
        let (m, build) = {
            let d = perifrac_io::read_tet_mesh(&out).unwrap();
            TetMesh::new(d.vertices, d.tets).unwrap()
        };
        assert_eq!(build.inverted_fixed, 0);
        assert!(m.num_tets() > 1000);
    } else {
        assert!(!o.status.success());
        assert!(err.contains("not on the PATH"), "{err}");
    }
}

#[test]
fn cli_meshes_round_primitives_through_the_mesher() {
    let dir = tempfile::tempdir().unwrap();
    for (spec, exact) in [
        // 4/3 pi r^3 and pi r^2 h; the faceted surfaces (64 segments) fall short by < 0.2%.
        ("sphere:0.5", 4.0 / 3.0 * std::f64::consts::PI * 0.125),
        ("cylinder:0.2x1", std::f64::consts::PI * 0.04),
    ] {
        let out = dir.path().join("round.mesh");
        let o = perifrac(&["mesh", spec, "--resolution", "12", "-o", s(&out)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let d = perifrac_io::read_tet_mesh(&out).unwrap();
        let (m, build) = TetMesh::new(d.vertices, d.tets).unwrap();
        assert_eq!(build.inverted_fixed, 0, "{spec}");
        assert!(m.quality().min_dihedral_deg >= MIN_DIHEDRAL_DEG, "{spec}");
        let rel = (m.total_rest_volume() / exact - 1.0).abs();
        assert!(rel < VOLUME_TOLERANCE, "{spec}: volume off by {rel}");
    }
}
