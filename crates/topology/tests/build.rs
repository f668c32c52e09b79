//! Mesh construction: validation errors, reorientation, adjacency, edge length, quality.

use perifrac_topology::faces::signed_volume;
use perifrac_topology::{primitives, TetMesh, TopologyError, NO_TET};

fn unit_tet() -> Vec<[f64; 3]> {
    vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ]
}

#[test]
fn inverted_tet_is_reoriented_and_counted() {
    let (v, mut t) = primitives::box_data([0.0; 3], [1.0; 3], [2, 1, 1]);
    t[7].swap(0, 1);
    let (m, report) = TetMesh::new(v, t).unwrap();
    assert_eq!(report.inverted_fixed, 1);
    assert!((0..m.num_tets()).all(|t| m.tet_rest_volume(t) > 0.0));
    assert!((m.total_rest_volume() - 1.0).abs() < 1e-15);
}

#[test]
fn flat_and_repeated_corner_tets_are_named() {
    let mut v = unit_tet();
    v.push([1.0, 1.0, 0.0]);
    // Tet 1 is flat: four points in the plane z = 0.
    let e = TetMesh::new(v.clone(), vec![[0, 1, 2, 3], [0, 1, 2, 4]]).unwrap_err();
    assert!(
        matches!(e, TopologyError::Degenerate { tet: 1, .. }),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(
        msg.starts_with("tet 1 has volume") && msg.contains("fix or remove"),
        "{msg}"
    );
    let e = TetMesh::new(v.clone(), vec![[0, 1, 2, 3], [0, 1, 1, 4]]).unwrap_err();
    assert!(
        matches!(e, TopologyError::RepeatedCorner { tet: 1, .. }),
        "{e:?}"
    );
    let e = TetMesh::new(v.clone(), vec![[0, 1, 2, 9]]).unwrap_err();
    assert!(matches!(
        e,
        TopologyError::VertexOutOfRange {
            tet: 0,
            vertex: 9,
            ..
        }
    ));
    let mut bad = v.clone();
    bad[2][1] = f64::NAN;
    assert!(matches!(
        TetMesh::new(bad, vec![[0, 1, 2, 3]]).unwrap_err(),
        TopologyError::NonFiniteVertex { vertex: 2, .. }
    ));
    assert_eq!(TetMesh::new(v, vec![]).unwrap_err(), TopologyError::Empty);
}

#[test]
fn a_nearly_flat_tet_passes_just_above_the_tolerance() {
    // Height 1e-9 over a unit right triangle: volume 1.7e-10, far above 1e-12 * lambda^3.
    let v = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.3, 0.3, 1e-9],
    ];
    assert!(TetMesh::new(v, vec![[0, 1, 2, 3]]).is_ok());
}

#[test]
fn three_tets_on_one_face_are_non_manifold() {
    let mut v = unit_tet();
    v.push([0.0, 0.0, -1.0]);
    v.push([0.2, 0.2, 2.0]);
    let e = TetMesh::new(v, vec![[0, 1, 2, 3], [0, 2, 1, 4], [0, 1, 2, 5]]).unwrap_err();
    match e {
        TopologyError::NonManifoldFace { face, tets } => {
            assert_eq!(face, [0, 1, 2]);
            assert_eq!(tets, [0, 1, 2]);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn duplicated_tet_is_named() {
    // The same tet twice, the second in the other orientation (it is reoriented first).
    let e = TetMesh::new(unit_tet(), vec![[0, 1, 2, 3], [1, 0, 2, 3]]).unwrap_err();
    assert_eq!(e, TopologyError::DuplicateTet { tet: 1, other: 0 });
}

#[test]
fn adjacency_is_symmetric_and_counts_boundary() {
    let m = primitives::box_mesh([0.0; 3], [3.0, 2.0, 1.0], [3, 2, 1]);
    for (t, nb) in m.neighbours().iter().enumerate() {
        for &n in nb {
            if n != NO_TET {
                assert!(m.neighbours()[n as usize].contains(&(t as u32)));
            }
        }
    }
    // Surface of a 3 x 2 x 1 cell box: 2 * (3*2 + 3*1 + 2*1) squares, two triangles each.
    assert_eq!(m.boundary_face_count(), 2 * 2 * (6 + 3 + 2));
    assert_eq!(m.num_tets(), 36);
    assert!(m.tets().iter().all(|t| {
        let [a, b, c, d] = t.map(|v| m.positions()[v as usize]);
        signed_volume(a, b, c, d) > 0.0
    }));
}

#[test]
fn mean_edge_length_of_a_kuhn_cube() {
    let m = primitives::box_mesh([0.0; 3], [1.0; 3], [1, 1, 1]);
    // 12 cube edges of 1, 6 face diagonals of sqrt 2, 1 body diagonal of sqrt 3: 19 edges.
    let expect = (12.0 + 6.0 * 2f64.sqrt() + 3f64.sqrt()) / 19.0;
    assert!((m.mean_edge_length() - expect).abs() < 1e-15);
}

#[test]
fn kuhn_box_quality_matches_hand_values() {
    let m = primitives::box_mesh([0.0; 3], [2.0; 3], [2, 2, 2]);
    let q = m.quality();
    // (A second cell size, 0.05, is checked in tests/cli.rs through `perifrac info`.)
    // A Kuhn tet (0,0,0),(1,0,0),(1,1,0),(1,1,1) has face planes x=1, x=y, y=z, z=0, giving
    // dihedral angles {45, 45, 60, 90, 90, 90} degrees.
    assert!((q.min_dihedral_deg - 45.0).abs() < 1e-9);
    assert!((q.max_dihedral_deg - 90.0).abs() < 1e-9);
    let n = m.num_tets();
    assert_eq!(q.dihedral_histogram[4], 2 * n);
    assert_eq!(q.dihedral_histogram[6], n);
    // Angles on a bin edge (60, 90) count in the upper bin.
    assert_eq!(q.dihedral_histogram[9], 3 * n);
    assert_eq!(q.dihedral_histogram.iter().sum::<usize>(), 6 * n);
    // Inradius 3V/A = 0.5 / (1 + sqrt 2) (areas 1/2, 1/2, sqrt2/2, sqrt2/2); circumradius
    // sqrt3/2 (the body diagonal is a diameter): ratio 3 r / R = sqrt 3 / (1 + sqrt 2).
    let rr = 3f64.sqrt() / (1.0 + 2f64.sqrt());
    assert!((q.min_radius_ratio - rr).abs() < 1e-12);
    assert!((q.mean_radius_ratio - rr).abs() < 1e-12);
    // Cells of edge 1: every tet has volume 1/6.
    assert!((q.min_volume - 1.0 / 6.0).abs() < 1e-15 && (q.max_volume - 1.0 / 6.0).abs() < 1e-15);
}

#[test]
fn regular_tet_has_radius_ratio_one() {
    let p = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let (v, t) = (p.to_vec(), vec![[0, 1, 2, 3]]);
    let (m, _) = TetMesh::new(v, t).unwrap();
    let q = m.quality();
    assert!((q.min_radius_ratio - 1.0).abs() < 1e-12);
    // The regular tet's dihedral angle is acos(1/3) = 70.53 degrees.
    assert!((q.min_dihedral_deg - (1.0f64 / 3.0).acos().to_degrees()).abs() < 1e-9);
}

#[test]
fn bar_cells_are_roughly_cubic_and_memory_is_small() {
    let m = primitives::bar_mesh(4.0, [1.0, 0.5], 8);
    // h = 0.5: 8 cells along, 2 across y, 1 across z.
    assert_eq!(m.num_tets(), 8 * 2 * 6);
    assert!((m.total_rest_volume() - 2.0).abs() < 1e-12);
    let big = primitives::box_mesh([0.0; 3], [1.0; 3], [10, 10, 10]);
    // The target budget of the crate is 100 bytes per tet.
    assert!(
        big.memory_bytes() < 100 * big.num_tets(),
        "{}",
        big.memory_bytes()
    );
    assert!(primitives::try_box_mesh([0.0; 3], [1.0, 0.0, 1.0], [1, 1, 1]).is_err());
}
