//! Property tests of docs/model.md section 3: random jittered box meshes, random crack-face sets
//! cracked in random order and random batches.

mod common;

use common::{canonical, check_invariants, interior_faces, jittered_box, Rng};
use perifrac_topology::TetMesh;
use proptest::prelude::*;

/// Cracks `faces` in `batches` consecutive batches, splitting after each; returns total copies.
fn crack_in_batches(m: &mut TetMesh, faces: &[(u32, u8)], batches: usize) -> usize {
    let mut copies = 0;
    let per = faces.len().div_ceil(batches.max(1)).max(1);
    for chunk in faces.chunks(per) {
        for &(t, f) in chunk {
            assert!(m.crack_face(t, f).expect("interior face"));
        }
        copies += m.split().copies_added;
    }
    copies
}

proptest! {
    // 1024 cases of up to 5x5x5 cells (750 tets) keep this file to about two seconds at
    // opt-level 2, while covering meshes from one cell to 125 and crack densities from none to
    // nearly every interior face.
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn split_invariants_hold_and_do_not_depend_on_order(
        nx in 1usize..=5, ny in 1usize..=5, nz in 1usize..=5,
        ex in 0.5f64..3.0, ey in 0.5f64..3.0, ez in 0.5f64..3.0,
        density in 0.0f64..1.0,
        batches in 1usize..6,
        seed in any::<u64>(),
    ) {
        let mut rng = Rng(seed);
        let mesh = jittered_box([nx, ny, nz], [ex, ey, ez], &mut rng);
        let rest_volume = mesh.total_rest_volume();
        let mut faces: Vec<_> = interior_faces(&mesh)
            .into_iter()
            .filter(|_| rng.unit() < density)
            .collect();

        // Reference: the sorted set, one batch.
        let mut reference = mesh.clone();
        let ref_copies = crack_in_batches(&mut reference, &faces, 1);
        check_invariants(&reference, rest_volume);
        prop_assert_eq!(ref_copies, reference.num_vertices() - reference.num_rest_vertices());

        // Random order, random batches.
        rng.shuffle(&mut faces);
        let mut shuffled = mesh.clone();
        crack_in_batches(&mut shuffled, &faces, batches);
        check_invariants(&shuffled, rest_volume);
        prop_assert_eq!(canonical(&shuffled), canonical(&reference));
        prop_assert_eq!(shuffled.num_vertices(), reference.num_vertices());

        // Reversed order, one face per batch, cracked from the other side of each face.
        faces.reverse();
        let mut one_by_one = mesh.clone();
        for &(t, f) in &faces {
            let n = one_by_one.neighbours()[t as usize][f as usize];
            let g = one_by_one.neighbours()[n as usize].iter().position(|&x| x == t).unwrap();
            prop_assert!(one_by_one.crack_face(n, g as u8).unwrap());
            prop_assert!(!one_by_one.crack_face(t, f).unwrap(), "second side is already cracked");
            one_by_one.split();
        }
        check_invariants(&one_by_one, rest_volume);
        prop_assert_eq!(canonical(&one_by_one), canonical(&reference));
    }
}
