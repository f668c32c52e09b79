//! Sampling at arbitrary rest points: linear fields exactly for P1 and P2, quadratic fields
//! exactly for P2, points a hair outside snap, points far outside are refused.

mod common;

use common::{jittered_box, Rng};
use perifrac_fem::{FemError, Mesh, Sampler, Vec3};

fn linear_field(x: Vec3) -> Vec3 {
    [
        0.3 + 1.2 * x[0] - 0.7 * x[1] + 0.1 * x[2],
        -2.0 * x[2] + 0.4,
        x[0] + x[1] + x[2],
    ]
}

fn quadratic_field(x: Vec3) -> Vec3 {
    [
        x[0] * x[1] - 0.5 * x[2] * x[2],
        1.0 + x[0] * x[0] - x[1] * x[2],
        0.2 * x[1] * x[1] + x[0],
    ]
}

/// Random points inside the unit cube, plus the barycentres of another (coarser, unjittered)
/// mesh of it, as the peridynamic particles will be.
fn points() -> Vec<Vec3> {
    let mut rng = Rng(17);
    let mut p: Vec<Vec3> = (0..500)
        .map(|_| [rng.uniform(), rng.uniform(), rng.uniform()])
        .collect();
    let (v, t) = perifrac_topology::primitives::box_data([0.0; 3], [1.0; 3], [3, 3, 3]);
    p.extend(t.iter().map(|tet| {
        std::array::from_fn(|d| tet.iter().map(|&i| v[i as usize][d]).sum::<f64>() / 4.0)
    }));
    // Corners and points on faces, where several elements touch.
    p.extend([[0.0; 3], [1.0; 3], [1.0, 0.5, 0.0], [0.5, 0.5, 1.0]]);
    p
}

fn worst_error(mesh: &Mesh, field: fn(Vec3) -> Vec3, pts: &[Vec3]) -> f64 {
    let sampler = Sampler::new(mesh, pts).unwrap();
    let nodal: Vec<Vec3> = mesh.nodes().iter().map(|&x| field(x)).collect();
    let got = sampler.interpolate(&nodal);
    got.iter()
        .zip(pts)
        .map(|(g, &p)| {
            (0..3)
                .map(|d| (g[d] - field(p)[d]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

#[test]
fn fields_in_the_element_space_are_interpolated_exactly() {
    let (v, t) = jittered_box(4, 0.2, 13);
    let p1 = Mesh::linear(v.clone(), t.clone()).unwrap();
    let p2 = Mesh::quadratic(v, t).unwrap();
    let pts = points();
    let e1 = worst_error(&p1, linear_field, &pts);
    let e2 = worst_error(&p2, linear_field, &pts);
    let q2 = worst_error(&p2, quadratic_field, &pts);
    let q1 = worst_error(&p1, quadratic_field, &pts);
    eprintln!("linear field: P1 {e1:e}, P2 {e2:e}; quadratic field: P2 {q2:e}, P1 {q1:e}");
    // Rounding (measured about 1e-15 for all three).
    assert!(e1 < 1e-13 && e2 < 1e-13 && q2 < 1e-13, "{e1} {e2} {q2}");
    // P1 cannot hold a quadratic field: its error is of order h^2 / 8.
    assert!(q1 > 1e-3, "{q1}");
}

#[test]
fn points_a_hair_outside_snap_and_far_ones_are_refused() {
    let (v, t) = jittered_box(2, 0.1, 3);
    let mesh = Mesh::quadratic(v, t).unwrap();
    let hair = [1.0 + 1e-12, 0.3, 0.4];
    let sampler = Sampler::new(&mesh, &[hair]).unwrap();
    let nodal: Vec<Vec3> = mesh.nodes().iter().map(|&x| linear_field(x)).collect();
    let got = sampler.interpolate(&nodal)[0];
    let want = linear_field([1.0, 0.3, 0.4]);
    assert!(
        (0..3).all(|d| (got[d] - want[d]).abs() < 1e-10),
        "{got:?} {want:?}"
    );
    match Sampler::new(&mesh, &[[0.5, 0.5, 0.5], [1.01, 0.5, 0.5]]) {
        Err(FemError::PointOutside {
            index: 1, distance, ..
        }) => {
            assert!((distance - 0.01).abs() < 1e-9, "{distance}")
        }
        other => panic!("{other:?}"),
    }
    // A generous tolerance accepts it, at the nearest boundary point.
    let far = Sampler::with_tolerance(&mesh, &[[1.01, 0.5, 0.5]], 0.02).unwrap();
    let got = far.interpolate(&nodal)[0];
    let want = linear_field([1.0, 0.5, 0.5]);
    assert!(
        (0..3).all(|d| (got[d] - want[d]).abs() < 1e-10),
        "{got:?} {want:?}"
    );
}
