//! Vertex advection from particle velocities, and placement from particle displacements.

mod common;

use common::interior_faces;
use perifrac_topology::primitives;

#[test]
fn uniform_velocity_moves_every_vertex_by_dt_v() {
    let mut m = primitives::box_mesh([0.0; 3], [1.0; 3], [3, 2, 2]);
    // Cut something first so copies are advected too.
    for (t, f) in interior_faces(&m).into_iter().take(40) {
        m.crack_face(t, f).unwrap();
    }
    m.split();
    let before = m.positions().to_vec();
    let n = m.num_tets();
    let mass: Vec<f64> = (0..n).map(|t| 1.0 + t as f64).collect();
    m.advect(0.25, &mass, &vec![[2.0, -1.0, 0.5]; n]);
    let step = [0.5, -0.25, 0.125];
    for (a, b) in before.iter().zip(m.positions()) {
        for i in 0..3 {
            // The weighted mean of equal vectors with unequal masses is exact up to a few ulps of
            // the velocity (2 ulp ~ 4e-16 here), scaled by dt.
            assert!((b[i] - a[i] - step[i]).abs() < 1e-15);
        }
    }
}

#[test]
fn rigid_rotation_field_gives_the_mass_weighted_mean_velocity() {
    let mut m = primitives::box_mesh([-1.0; 3], [1.0; 3], [2, 2, 2]);
    let n = m.num_tets();
    let omega = [0.3, -0.2, 0.7];
    let bary = m.rest_barycentres();
    let vel: Vec<[f64; 3]> = bary
        .iter()
        .map(|x| {
            [
                omega[1] * x[2] - omega[2] * x[1],
                omega[2] * x[0] - omega[0] * x[2],
                omega[0] * x[1] - omega[1] * x[0],
            ]
        })
        .collect();
    let mass: Vec<f64> = (0..n).map(|t| 1.0 + (t % 5) as f64).collect();
    let before = m.positions().to_vec();
    let dt = 1e-3;
    m.advect(dt, &mass, &vel);
    // A linear field: the weighted mean of omega x X_p is omega x (weighted mean barycentre).
    for (v, (a, b)) in before.iter().zip(m.positions()).enumerate() {
        let (mut w, mut c) = (0.0, [0.0; 3]);
        for (t, tet) in m.tets().iter().enumerate() {
            if tet.contains(&(v as u32)) {
                w += mass[t];
                for i in 0..3 {
                    c[i] += mass[t] * bary[t][i];
                }
            }
        }
        let c = c.map(|x| x / w);
        let expect = [
            omega[1] * c[2] - omega[2] * c[1],
            omega[2] * c[0] - omega[0] * c[2],
            omega[0] * c[1] - omega[1] * c[0],
        ];
        for i in 0..3 {
            // dt * |v| ~ 1e-3; 1e-15 is rounding of that product and of the weighted sums.
            assert!((b[i] - a[i] - dt * expect[i]).abs() < 1e-15, "vertex {v}");
        }
    }
}

#[test]
fn equal_masses_give_the_plain_mean() {
    let mut m = primitives::box_mesh([0.0; 3], [1.0; 3], [1, 1, 1]);
    let n = m.num_tets();
    let vel: Vec<[f64; 3]> = (0..n).map(|t| [t as f64, 0.0, 0.0]).collect();
    let before = m.positions().to_vec();
    m.advect(1.0, &vec![3.0; n], &vel);
    for (v, (a, b)) in before.iter().zip(m.positions()).enumerate() {
        let users: Vec<f64> = (0..n)
            .filter(|&t| m.tets()[t].contains(&(v as u32)))
            .map(|t| t as f64)
            .collect();
        let mean = users.iter().sum::<f64>() / users.len() as f64;
        // Means of small integers: exact up to one rounding.
        assert!((b[0] - a[0] - mean).abs() < 1e-15);
    }
}

#[test]
fn place_from_particles_translates_exactly() {
    let mut m = primitives::box_mesh([0.0; 3], [1.0; 3], [2, 3, 2]);
    let n = m.num_tets();
    m.advect(1.0, &vec![1.0; n], &vec![[9.0, 9.0, 9.0]; n]);
    m.place_from_particles(&vec![2.0; n], &vec![[0.5, -0.25, 1.0]; n]);
    for (v, x) in m.positions().iter().enumerate() {
        let r = m.rest_positions()[m.vertex_origin()[v] as usize];
        // Equal masses and displacements that are powers of two: the mean is exact, so the
        // translation is too (the earlier advect leaves no trace).
        assert_eq!(*x, [r[0] + 0.5, r[1] - 0.25, r[2] + 1.0]);
    }
}
