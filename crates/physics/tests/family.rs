//! Families: horizon-bounded face walks, symmetry, gaps, and the errors for bad input.

mod support;

use perifrac_physics::math::{norm, sub};
use perifrac_physics::{Discretization, PhysicsError, NO_NEIGHBOUR};
use support::block;

#[test]
fn families_are_symmetric_sorted_and_inside_the_horizon() {
    let (disc, report, lambda) = block([0.06, 0.04, 0.04], [6, 4, 4], 1.5);
    let fam = disc.family();
    let x = disc.rest_positions();
    assert_eq!(report.bonds, fam.num_bonds());
    assert!(report.isolated.is_empty());
    for i in 0..fam.len() {
        let row = fam.row(i);
        assert!(
            row.windows(2).all(|w| w[0] < w[1]),
            "row {i} sorted, no duplicates"
        );
        for (k, &j) in fam.range(i).zip(row) {
            assert_ne!(j as usize, i);
            assert!(
                fam.row(j as usize).binary_search(&(i as u32)).is_ok(),
                "{i}->{j} has its reverse"
            );
            let r = norm(sub(x[j as usize], x[i]));
            assert_eq!(fam.rest_lengths()[k], r);
            assert!(r < 1.5 * lambda);
        }
    }
    let rev = fam.reverse_index();
    for i in 0..fam.len() {
        for k in fam.range(i) {
            let back = rev[k] as usize;
            assert_eq!(fam.neighbours()[back] as usize, i);
            assert_eq!(rev[back] as usize, k);
        }
    }
    eprintln!(
        "k=1.5: {} bonds, {} added by symmetry ({:.2}%), bonds per particle {}..{}",
        report.bonds,
        report.added_by_symmetry,
        100.0 * report.added_by_symmetry as f64 / report.bonds as f64,
        report.min_bonds,
        report.max_bonds
    );
}

#[test]
fn walk_finds_every_particle_in_the_ball_of_a_convex_block() {
    // In a convex block of Kuhn tets the face graph restricted to the ball is connected for these
    // horizons, so the walk finds exactly the brute-force ball (checked, not assumed).
    let (disc, _, lambda) = block([0.04, 0.04, 0.04], [4, 4, 4], 1.2);
    let x = disc.rest_positions();
    let delta = 1.2 * lambda;
    let mut missing = 0;
    for i in 0..x.len() {
        let brute = (0..x.len())
            .filter(|&j| j != i && norm(sub(x[j], x[i])) < delta)
            .count();
        missing += brute - disc.family().row(i).len();
    }
    assert_eq!(missing, 0);
}

#[test]
fn bonds_do_not_jump_a_gap_that_is_not_face_connected() {
    // Two blocks 0.2 lambda apart with no face adjacency between them: the horizon ball reaches
    // across, the walk must not.
    let (a, _, lambda) = block([0.03, 0.03, 0.03], [3, 3, 3], 1.5);
    let n = a.len();
    let gap = 0.03 + 0.2 * lambda;
    let mut x = a.rest_positions().to_vec();
    x.extend(a.rest_positions().iter().map(|p| [p[0] + gap, p[1], p[2]]));
    let mut vol = a.volumes().to_vec();
    vol.extend_from_slice(a.volumes());
    // rebuild adjacency of block a from its family-free mesh: use the topology crate
    let (v, t) = perifrac_topology::primitives::box_data([0.0; 3], [0.03; 3], [3, 3, 3]);
    let (mesh, _) = perifrac_topology::TetMesh::new(v, t).unwrap();
    let mut adj = mesh.neighbours().to_vec();
    adj.extend(
        mesh.neighbours()
            .iter()
            .map(|f| f.map(|u| if u == NO_NEIGHBOUR { u } else { u + n as u32 })),
    );
    let (two, _) = Discretization::from_tets(&x, &vol, &adj, 1.5 * lambda).unwrap();
    let fam = two.family();
    let crossing = (0..2 * n)
        .flat_map(|i| {
            fam.row(i)
                .iter()
                .map(move |&j| (i < n) != ((j as usize) < n))
        })
        .filter(|&c| c)
        .count();
    assert_eq!(crossing, 0);
    // ... while a brute-force ball would have bonded across
    let close = (0..n).any(|i| (n..2 * n).any(|j| norm(sub(x[j], x[i])) < 1.5 * lambda));
    assert!(close);
}

#[test]
fn bad_input_gives_errors_or_warnings_not_panics() {
    let x = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 0.0, 0.0]];
    let v = vec![1.0, 1.0, 1.0];
    let adj = vec![
        [1, NO_NEIGHBOUR, NO_NEIGHBOUR, NO_NEIGHBOUR],
        [0, NO_NEIGHBOUR, NO_NEIGHBOUR, NO_NEIGHBOUR],
        [NO_NEIGHBOUR; 4],
    ];
    assert!(matches!(
        Discretization::from_tets(&x, &v, &adj, 0.5),
        Err(PhysicsError::HorizonTooSmall { .. })
    ));
    // particle 2 has no face neighbour: a warning in the report
    let (_, report) = Discretization::from_tets(&x, &v, &adj, 2.0).unwrap();
    assert_eq!(report.isolated, vec![2]);
    assert!(matches!(
        Discretization::from_tets(&x, &v, &adj, -1.0),
        Err(PhysicsError::BadHorizon(_))
    ));
    assert!(matches!(
        Discretization::from_tets(&x, &v, &adj, f64::NAN),
        Err(PhysicsError::BadHorizon(_))
    ));
    assert!(matches!(
        Discretization::from_tets(&x, &v[..2], &adj, 2.0),
        Err(PhysicsError::LengthMismatch { .. })
    ));
    assert!(matches!(
        Discretization::from_tets(&x, &[1.0, 0.0, 1.0], &adj, 2.0),
        Err(PhysicsError::BadParticle { particle: 1, .. })
    ));
    let mut bad = adj.clone();
    bad[2][3] = 7;
    assert!(matches!(
        Discretization::from_tets(&x, &v, &bad, 2.0),
        Err(PhysicsError::BadAdjacency {
            tet: 2,
            face: 3,
            neighbour: 7
        })
    ));
    let (mut d, _) = Discretization::from_tets(&x, &v, &adj, 2.0).unwrap();
    d.set_materials(&[0, 1, 0]).unwrap();
    let e = perifrac_physics::ChenModel::new(d, &[support::steel()]).unwrap_err();
    assert!(matches!(
        e,
        PhysicsError::UnknownMaterial { particle: 1, .. }
    ));
}

/// A U-shaped block: an 8 x 8 x 3 cell box with a slot one cell wide cut halfway in, so that
/// walks from the two sides of the slot explore different balls.
fn slotted() -> (Discretization, perifrac_physics::FamilyReport) {
    let h = 0.01;
    let (v, t) =
        perifrac_topology::primitives::box_data([0.0; 3], [8.0 * h, 8.0 * h, 3.0 * h], [8, 8, 3]);
    let keep: Vec<[u32; 4]> = t
        .into_iter()
        .filter(|tet| {
            let c = tet.iter().fold([0.0; 3], |a, &i| {
                let p = v[i as usize];
                [a[0] + p[0] / 4.0, a[1] + p[1] / 4.0, a[2] + p[2] / 4.0]
            });
            !((3.5 * h..4.5 * h).contains(&c[0]) && c[1] < 5.0 * h)
        })
        .collect();
    let (mesh, _) = perifrac_topology::TetMesh::new(v, keep).unwrap();
    let delta = 1.5 * mesh.mean_edge_length();
    Discretization::from_tets(
        &mesh.rest_barycentres(),
        &mesh.rest_volumes(),
        mesh.neighbours(),
        delta,
    )
    .unwrap()
}

#[test]
fn asymmetric_walks_are_symmetrised_and_forces_balance() {
    let (disc, report) = slotted();
    eprintln!(
        "slotted block: {} of {} directed bonds added by symmetry ({:.2}%)",
        report.added_by_symmetry,
        report.bonds,
        100.0 * report.added_by_symmetry as f64 / report.bonds as f64
    );
    // the walks around the slot end differ: measured 126 of 108,818 directed bonds (0.12%)
    assert!(report.added_by_symmetry > 0);
    let fam = disc.family();
    for i in 0..fam.len() {
        for &j in fam.row(i) {
            assert!(fam.row(j as usize).binary_search(&(i as u32)).is_ok());
        }
    }
    let x = disc.rest_positions().to_vec();
    let mut m = perifrac_physics::ChenModel::new(disc, &[support::steel()]).unwrap();
    let y = support::nonuniform(&x, 0.01, 0.08);
    let mut f = vec![[0.0; 3]; x.len()];
    perifrac_physics::ForceModel::trial_forces(&mut m, &y, &mut f);
    let net = f
        .iter()
        .fold([0.0; 3], |a, b| perifrac_physics::math::add(a, *b));
    let scale: f64 = f.iter().map(|v| norm(*v)).sum();
    eprintln!(
        "slotted block: net force {:e} of sum |f| {scale:e}",
        norm(net)
    );
    // bitwise antisymmetric pair terms; summation order only
    assert!(norm(net) < 1e-13 * scale);
}

#[test]
fn families_do_not_depend_on_the_order_of_the_tets() {
    // The walk sorts a row by reading back the bits of its finds where their indices lie close
    // together (a lattice's order), and by comparison elsewhere: shuffled indices take the
    // second way (rows of 24 to 86 here against 158 words of bits: both ways are taken), and
    // the bonds must be the same pairs with the same rest lengths.
    let (v, t) = perifrac_topology::primitives::box_data([0.0; 3], [0.14, 0.12, 0.1], [14, 12, 10]);
    let (mesh, _) = perifrac_topology::TetMesh::new(v, t).expect("box mesh");
    let (x, vol, adj) = (
        mesh.rest_barycentres(),
        mesh.rest_volumes(),
        mesh.neighbours(),
    );
    let delta = 1.2 * mesh.mean_edge_length();
    let n = x.len();
    // a fixed shuffle (Fisher-Yates on a 64-bit LCG): new index `to[t]` of tet `t`
    let mut to: Vec<usize> = (0..n).collect();
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    for k in (1..n).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        to.swap(k, (state >> 33) as usize % (k + 1));
    }
    let (mut xs, mut vs, mut adjs) = (vec![[0.0; 3]; n], vec![0.0; n], vec![[0u32; 4]; n]);
    for t in 0..n {
        xs[to[t]] = x[t];
        vs[to[t]] = vol[t];
        adjs[to[t]] = adj[t].map(|u| {
            if u == NO_NEIGHBOUR {
                u
            } else {
                to[u as usize] as u32
            }
        });
    }
    let (plain, _) = Discretization::from_tets(&x, &vol, adj, delta).expect("plain");
    let (shuffled, _) = Discretization::from_tets(&xs, &vs, &adjs, delta).expect("shuffled");
    let (a, b) = (plain.family(), shuffled.family());
    let mut from = vec![0u32; n];
    for (t, &u) in to.iter().enumerate() {
        from[u] = t as u32;
    }
    assert_eq!(a.num_bonds(), b.num_bonds());
    for (i, &ti) in to.iter().enumerate() {
        let row = b.row(ti);
        assert!(row.windows(2).all(|w| w[0] < w[1]), "row {i} sorted");
        // the shuffled row's pairs, named in the plain order, with their rest lengths
        let mut back: Vec<(u32, f64)> = b
            .range(ti)
            .map(|k| (from[b.neighbours()[k] as usize], b.rest_lengths()[k]))
            .collect();
        back.sort_by_key(|&(j, _)| j);
        let want: Vec<(u32, f64)> = a
            .range(i)
            .map(|k| (a.neighbours()[k], a.rest_lengths()[k]))
            .collect();
        assert_eq!(back, want, "particle {i}");
    }
    let lens = (0..n).map(|i| a.row(i).len());
    eprintln!(
        "{n} tets, rows of {} to {}, {} words of bits",
        lens.clone().min().unwrap_or(0),
        lens.max().unwrap_or(0),
        n.div_ceil(64)
    );
}
