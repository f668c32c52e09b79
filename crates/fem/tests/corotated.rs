//! Corotated kinematics: zero force under rigid rotation (where linear kinematics is badly
//! wrong), objectivity, and the force is the exact gradient of the energy.

mod common;

use common::{apply, jittered_box, max_abs, rotation, Rng};
use perifrac_fem::{ElasticForces, Kinematics, Material, Mesh, Vec3};

fn material() -> Material {
    common::cantilever_material()
}

fn meshes() -> [Mesh; 2] {
    let (v, t) = jittered_box(2, 0.15, 21);
    [
        Mesh::linear(v.clone(), t.clone()).unwrap(),
        Mesh::quadratic(v, t).unwrap(),
    ]
}

fn forces(mesh: &Mesh, kin: Kinematics, x: &[Vec3]) -> Vec<Vec3> {
    let mut f = vec![[0.0; 3]; mesh.node_count()];
    ElasticForces::new(mesh, &material(), kin)
        .compute(x, &mut f)
        .unwrap();
    f
}

/// Force scale of the mesh: stress E * 1e-3 on a face of the unit cube's cells.
fn scale(mesh: &Mesh) -> f64 {
    let m = material();
    let strained: Vec<Vec3> = mesh
        .nodes()
        .iter()
        .map(|p| [p[0] * 1.001, p[1], p[2]])
        .collect();
    max_abs(&forces(mesh, Kinematics::Linear, &strained)).max(m.young * 1e-12)
}

#[test]
fn rigid_rotation_gives_no_corotated_force() {
    for mesh in meshes() {
        let typical = scale(&mesh);
        for (axis, angle) in [
            ([0.0, 0.0, 1.0], 90f64.to_radians()),
            ([1.0, 2.0, -0.5], 2.5),
        ] {
            let r = rotation(axis, angle);
            let x: Vec<Vec3> = mesh.nodes().iter().map(|&p| apply(&r, p)).collect();
            let corot = max_abs(&forces(&mesh, Kinematics::Corotated, &x));
            let linear = max_abs(&forces(&mesh, Kinematics::Linear, &x));
            let energy = ElasticForces::new(&mesh, &material(), Kinematics::Corotated)
                .energy(&x)
                .unwrap();
            eprintln!(
                "{:?} rotation {angle:.3} rad: corotated {corot:e} N, linear {linear:e} N (0.1 % stretch gives {typical:e} N), corotated energy {energy:e} J",
                mesh.order()
            );
            // Rounding: measured <= 3e-8 N (energy 1e-22 J) against 1e4 N for a 0.1 % stretch.
            assert!(corot < 1e-10 * typical, "{corot}");
            assert!(energy.abs() < 1e-12, "{energy}");
            // Linear kinematics reads the rotation as a strain of order 1: a thousand times
            // the force of a 0.1 % stretch.
            assert!(linear > 100.0 * typical, "{linear}");
        }
    }
}

#[test]
fn corotated_force_is_objective() {
    let mut rng = Rng(99);
    for mesh in meshes() {
        // A strained body: random node displacements of 2 % of the cell size plus a shear.
        let x: Vec<Vec3> = mesh
            .nodes()
            .iter()
            .map(|p| {
                [
                    p[0] + 0.2 * p[1] + 0.01 * rng.signed(),
                    p[1] + 0.01 * rng.signed(),
                    p[2] + 0.01 * rng.signed(),
                ]
            })
            .collect();
        let f = forces(&mesh, Kinematics::Corotated, &x);
        let r = rotation([0.3, -1.0, 0.7], 1.9);
        let rx: Vec<Vec3> = x.iter().map(|&p| apply(&r, p)).collect();
        let frx = forces(&mesh, Kinematics::Corotated, &rx);
        let worst = f
            .iter()
            .zip(&frx)
            .map(|(a, b)| {
                let ra = apply(&r, *a);
                (0..3).map(|d| (ra[d] - b[d]).abs()).fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        eprintln!(
            "{:?}: |f(Rx) - R f(x)| = {worst:e} N of {:e} N",
            mesh.order(),
            max_abs(&f)
        );
        assert!(worst < 1e-10 * max_abs(&f), "{worst}");
    }
}

/// Central differences of the energy against the force, for both kinematics, at a strongly
/// deformed state (rotation plus 5 % random strain).
#[test]
fn force_is_minus_the_energy_gradient() {
    let mut rng = Rng(5);
    for mesh in meshes() {
        let r = rotation([1.0, 1.0, 0.0], 0.8);
        let x: Vec<Vec3> = mesh
            .nodes()
            .iter()
            .map(|&p| {
                let q = apply(&r, p);
                [
                    q[0] + 0.02 * rng.signed(),
                    q[1] + 0.02 * rng.signed(),
                    q[2] + 0.02 * rng.signed(),
                ]
            })
            .collect();
        for kin in [Kinematics::Linear, Kinematics::Corotated] {
            let kernel = ElasticForces::new(&mesh, &material(), kin);
            let f = forces(&mesh, kin, &x);
            let h = 1e-6;
            let mut worst = 0.0f64;
            for node in (0..mesh.node_count()).step_by(7) {
                for d in 0..3 {
                    let mut xp = x.clone();
                    xp[node][d] += h;
                    let mut xm = x.clone();
                    xm[node][d] -= h;
                    let de =
                        (kernel.energy(&xp).unwrap() - kernel.energy(&xm).unwrap()) / (2.0 * h);
                    worst = worst.max((f[node][d] + de).abs());
                }
            }
            eprintln!(
                "{:?} {kin:?}: |f + dE/dx| <= {worst:e} N of {:e} N",
                mesh.order(),
                max_abs(&f)
            );
            assert!(worst < 1e-5 * max_abs(&f), "{worst}");
        }
    }
}
