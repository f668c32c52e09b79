//! Cross-crate: physics breaks bonds, topology cuts the mesh along them and follows the
//! particles. A bar torn at a velocity jump must end as two closed pieces that separate.

use perifrac_physics::{
    ChenMaterial, ChenModel, Discretization, Explicit, ExplicitConfig, FractureParams, Loads,
};
use perifrac_topology::primitives;

const LENGTH: f64 = 0.2;

#[test]
fn torn_bar_mesh_splits_into_two_closed_pieces_that_separate() {
    let mut mesh = primitives::box_mesh([0.0; 3], [LENGTH, 0.02, 0.02], [20, 2, 2]);
    let rest = mesh.rest_barycentres();
    let volumes = mesh.rest_volumes();
    let horizon = 1.5 * mesh.mean_edge_length();
    let (disc, _) = Discretization::from_tets(&rest, &volumes, mesh.neighbours(), horizon).unwrap();
    let mut material = ChenMaterial::from_young_poisson(200e9, 0.25, 7800.0).unwrap();
    material.fracture = Some(FractureParams {
        s_crit: 1e-3,
        alpha: 0.0,
    });
    let masses: Vec<f64> = volumes.iter().map(|v| material.density * v).collect();
    let model = ChenModel::new(disc, &[material]).unwrap();
    let mut solver = Explicit::new(
        model,
        &rest,
        horizon,
        Loads::new(rest.len()),
        ExplicitConfig::default(),
    )
    .unwrap();
    // 5.5 m/s each way: the physics crate's fracture test measured this speed to give exactly
    // two pieces on this bar (4 and 5 m/s: one piece, 6 m/s: four).
    for (v, p) in solver.velocities_mut().iter_mut().zip(&rest) {
        v[0] = if p[0] < LENGTH / 2.0 { -5.5 } else { 5.5 };
    }
    let volume0 = mesh.total_rest_volume();
    let mut broken_total = 0;
    for _ in 0..300 {
        let broken = solver.step().unwrap();
        broken_total += broken.len();
        mesh.crack_bonds(broken);
        mesh.split();
        mesh.advect(solver.dt(), &masses, solver.velocities());
    }
    assert!(broken_total > 0);

    let pieces = mesh.pieces();
    assert_eq!(pieces.count, 2, "{broken_total} bonds broke");
    // The pieces are the two halves, split within the cell layer where the velocity jumped
    // (the crack runs between the tets of the two middle cells, as in the physics crate's
    // test: 240 tets each side, a tet of each middle cell on the other side).
    let left = pieces.piece_of_tet[0];
    let cell = LENGTH / 20.0;
    for (t, c) in rest.iter().enumerate() {
        if (c[0] - LENGTH / 2.0).abs() > cell {
            assert_eq!(
                pieces.piece_of_tet[t] == left,
                c[0] < LENGTH / 2.0,
                "tet {t}"
            );
        }
    }
    let on_left = pieces.piece_of_tet.iter().filter(|&&p| p == left).count();
    assert_eq!(2 * on_left, rest.len(), "the halves have {on_left} tets");
    // Splitting never changes the rest volume.
    assert!((mesh.total_rest_volume() - volume0).abs() < 1e-15 * volume0);
    // Each piece's surface (current positions) is closed and encloses about half the bar: the
    // halves ring with strains near the fracture stretch (1e-3), so volumes move by ~1e-3;
    // measured 1.6e-4 for both halves (5.7e-4 with the scalar calibration), bounded at 1%.
    let half = volume0 / 2.0;
    for s in mesh.piece_surfaces() {
        assert!(s.is_closed());
        let dev = (s.signed_volume() - half).abs() / half;
        eprintln!("piece volume deviation {dev:.2e}");
        assert!(dev < 0.01, "{}", s.signed_volume());
    }
    // The mesh followed the particles: each tet's vertex barycentre stays near its particle.
    // Advection moves a vertex with the mass-weighted mean velocity of its tets, so it drifts
    // only where the velocity varies across a vertex star.
    let pos = mesh.positions();
    let y = solver.positions();
    let lambda = mesh.mean_edge_length();
    let mut drift: f64 = 0.0;
    for (t, tet) in mesh.tets().iter().enumerate() {
        let mut d2 = 0.0;
        for k in 0..3 {
            let c: f64 = tet.iter().map(|&v| 0.25 * pos[v as usize][k]).sum();
            d2 += (c - y[t][k]).powi(2);
        }
        drift = drift.max(d2.sqrt());
    }
    eprintln!(
        "{broken_total} bonds broke; max tet drift {:.3e} lambda",
        drift / lambda
    );
    // Measured 1.76e-3 lambda after 300 steps (the halves ring after the break); a hundredth of
    // an edge is far below what shows in a frame, and 5x the measured value.
    assert!(drift < 1e-2 * lambda, "drift {drift}");
}
