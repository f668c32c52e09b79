//! Deterministic cuts: one plane gives two pieces, three planes through one vertex give eight.

mod common;

use common::{check_invariants, interior_faces};
use perifrac_topology::faces::FACE_CORNERS;
use perifrac_topology::{primitives, TetMesh};

/// Cracks every interior face whose three rest vertices satisfy `on_plane`; returns the count.
fn crack_plane(m: &mut TetMesh, on_plane: impl Fn([f64; 3]) -> bool) -> usize {
    let mut n = 0;
    for (t, f) in interior_faces(m) {
        let tet = m.tets()[t as usize];
        let all_on = FACE_CORNERS[f as usize].iter().all(|&k| {
            let r = m.vertex_origin()[tet[k] as usize];
            on_plane(m.rest_positions()[r as usize])
        });
        if all_on && m.crack_face(t, f).unwrap() {
            n += 1;
        }
    }
    n
}

// Exact comparisons against 1.0 below are safe: grid coordinates i * 2 / 4 are exact in binary.
#[test]
fn one_plane_gives_two_closed_halves() {
    let mut m = primitives::box_mesh([0.0; 3], [2.0; 3], [4, 4, 4]);
    let total = m.total_rest_volume();
    let cracked = crack_plane(&mut m, |p| p[0] == 1.0);
    // The plane x = 1 crosses 4 x 4 square cell faces, each cut into 2 triangles.
    assert_eq!(cracked, 32);
    let report = m.split();
    // The 5 x 5 grid vertices of the plane each split in two; the boundary ones too, because
    // the two halves only touch through the crack.
    assert_eq!(report.vertices_split, 25);
    assert_eq!(report.copies_added, 25);
    let pieces = m.pieces();
    assert_eq!(pieces.count, 2);
    let surfaces = m.piece_surfaces();
    for s in &surfaces {
        assert!(s.is_closed());
        // Half of the 2 x 2 x 2 box, to rounding of a few hundred tet volumes.
        assert!((s.signed_volume() - 4.0).abs() < 1e-12);
        // 32 crack triangles per side.
        assert_eq!(s.crack.iter().filter(|&&c| c == 1).count(), 32);
    }
    check_invariants(&m, total);
}

#[test]
fn three_planes_split_the_centre_vertex_eight_ways() {
    let mut m = primitives::box_mesh([0.0; 3], [2.0; 3], [4, 4, 4]);
    let total = m.total_rest_volume();
    let cracked = crack_plane(&mut m, |p| p[0] == 1.0)
        + crack_plane(&mut m, |p| p[1] == 1.0)
        + crack_plane(&mut m, |p| p[2] == 1.0);
    assert_eq!(cracked, 3 * 32);
    m.split();
    assert_eq!(m.pieces().count, 8);
    // Centre vertex (2, 2, 2) of the 5 x 5 x 5 grid.
    let centre = (2 + 5 * (2 + 5 * 2)) as u32;
    let copies = m.vertex_origin().iter().filter(|&&o| o == centre).count();
    assert_eq!(copies, 8, "one copy per octant: the original plus 7 new");
    for s in m.piece_surfaces() {
        assert!(s.is_closed());
        // One octant, a unit cube.
        assert!((s.signed_volume() - 1.0).abs() < 1e-12);
    }
    check_invariants(&m, total);
}

#[test]
fn a_lone_crack_face_changes_no_vertex_and_no_surface() {
    let mut m = primitives::box_mesh([0.0; 3], [1.0; 3], [3, 3, 3]);
    let before = m.surface();
    let (t, f) = interior_faces(&m)[0];
    assert!(m.crack_face(t, f).unwrap());
    assert_eq!(m.split().copies_added, 0);
    assert_eq!(m.pieces().count, 1);
    // The face is cracked but both sides still share its vertices, so it is not output.
    assert_eq!(m.surface(), before);
}

#[test]
fn crack_bonds_cracks_only_face_adjacent_pairs() {
    let mut m = primitives::box_mesh([0.0; 3], [1.0; 3], [2, 2, 2]);
    let (t, f) = interior_faces(&m)[0];
    let n = m.neighbours()[t as usize][f as usize];
    // Find a tet sharing no face with t.
    let far = (0..m.num_tets() as u32)
        .find(|&u| u != t && !m.neighbours()[t as usize].contains(&u))
        .unwrap();
    assert_eq!(m.crack_bonds(&[(t, far)]), 0);
    assert!((0..4).all(|g| !m.is_cracked(t, g)));
    assert_eq!(m.crack_bonds(&[(n, t), (t, n), (far, 9999)]), 1);
    assert!(m.is_cracked(t, f));
    let g = m.neighbours()[n as usize]
        .iter()
        .position(|&x| x == t)
        .unwrap();
    assert!(m.is_cracked(n, g as u8));
}

#[test]
fn crack_face_rejects_boundary_and_out_of_range() {
    let mut m = primitives::box_mesh([0.0; 3], [1.0; 3], [1, 1, 1]);
    let (t, f) = (0..6u32)
        .flat_map(|t| (0..4u8).map(move |f| (t, f)))
        .find(|&(t, f)| m.neighbours()[t as usize][f as usize] == perifrac_topology::NO_TET)
        .unwrap();
    let e = m.crack_face(t, f).unwrap_err().to_string();
    assert!(
        e.contains(&format!("tet {t}")) && e.contains("boundary"),
        "{e}"
    );
    assert!(m.crack_face(6, 0).is_err());
    assert!(m.crack_face(0, 4).is_err());
}
