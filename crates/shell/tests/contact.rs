//! Shells against the contact crate's colliders.

use perifrac_contact::{BallDesc, BallMotion, Colliders, ContactParams, GroundDesc};
use perifrac_shell::generate::sheet;
use perifrac_shell::*;

fn steel_sheet() -> ShellDynamics {
    // A 4 x 4 cm steel sheet, 1 mm thick, 2 mm above the ground.
    let s = sheet(0.04, 0.04, 8, 8).unwrap();
    let v: Vec<_> = s.vertices.iter().map(|p| [p[0], p[1], 0.002]).collect();
    let mesh = ShellMesh::new(v, s.triangles).unwrap();
    let steel = ShellMaterial::new(200e9, 0.3, 7800.0, 1e-3).unwrap();
    ShellDynamics::new(ShellModel::new(mesh, steel).unwrap()).unwrap()
}

fn ground() -> GroundDesc {
    GroundDesc {
        point: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
        params: ContactParams::from_material(200e9, 5e-4, 1.0, 0.1, 0.5),
    }
}

#[test]
fn a_sheet_dropped_on_the_ground_comes_to_rest_on_it() {
    // Dropped flat from 2 mm (the vertices' spheres 1.5 mm clear), damped at 100/s: it must
    // end at rest on the ground,
    // its vertices' spheres (radius h / 2 = 0.5 mm) pressed in by its weight alone: 7800 kg/m^3
    // x 1 mm x 9.81 m/s^2 = 77 Pa over 0.25 cm^2 a vertex on springs of 1e8 N/m, about 1e-11
    // m; 1e-7 m allows for the damped ring-down not being quite over (measured: at 5e-4 m to
    // 1e-11, 8e-12 m/s).
    let mut shell = steel_sheet();
    shell.set_gravity([0.0, 0.0, -9.81]);
    shell.set_damping(100.0).unwrap();
    let c = Colliders::new(vec![ground()], vec![], [0.0, 0.0, -9.81]).unwrap();
    shell.set_colliders(c, 5e-4).unwrap();
    let dt = 0.5 * shell.stable_step().unwrap();
    let mut touched = false;
    for _ in 0..((0.1 / dt) as usize) {
        shell.step(dt).unwrap();
        touched |= shell.contact_stats().contacts > 0;
    }
    let lowest = shell
        .positions()
        .iter()
        .map(|p| p[2])
        .fold(f64::INFINITY, f64::min);
    let fastest = shell
        .velocities()
        .iter()
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .fold(0.0, f64::max);
    eprintln!("lowest vertex at {lowest:.3e} m, fastest {fastest:.2e} m/s");
    assert!(touched);
    assert!((lowest - 5e-4).abs() < 1e-7, "{lowest}");
    assert!(fastest < 1e-3, "{fastest}");
}

#[test]
fn a_vertex_inside_a_collider_at_the_start_is_refused() {
    let mut shell = steel_sheet();
    let ball = BallDesc {
        center: [0.02, 0.02, 0.002],
        radius: 0.005,
        motion: BallMotion::Kinematic { velocity: [0.0; 3] },
        params: ContactParams::from_material(200e9, 5e-4, 1.0, 0.1, 0.5),
    };
    let c = Colliders::new(vec![], vec![ball], [0.0; 3]).unwrap();
    let err = shell.set_colliders(c, 5e-4).unwrap_err();
    assert!(err.to_string().contains("ball 0"), "{err}");
}

#[test]
fn fracture_adds_vertices_that_contact_follows() {
    // A glass sheet over a ground, pulled apart at its ends until it breaks: the vertices
    // fracture adds get contact radii too, and stepping on with the colliders works.
    let s = sheet(0.1, 0.05, 20, 10).unwrap();
    let v: Vec<_> = s.vertices.iter().map(|p| [p[0], p[1], 0.01]).collect();
    let mesh = ShellMesh::new(v.clone(), s.triangles).unwrap();
    let glass = ShellMaterial::new(70e9, 0.22, 2500.0, 1e-3).unwrap();
    let model = ShellModel::new(mesh, glass)
        .unwrap()
        .with_fracture(ShellFracture::new(1e-3, 1e-3, 0.25, 1.0).unwrap());
    let mut shell = ShellDynamics::new(model).unwrap();
    for (i, p) in v.iter().enumerate() {
        if p[0] < 1e-9 {
            shell.drive(i, [-1.0, 0.0, 0.0]);
        } else if p[0] > 0.1 - 1e-9 {
            shell.drive(i, [1.0, 0.0, 0.0]);
        }
    }
    let c = Colliders::new(vec![ground()], vec![], [0.0; 3]).unwrap();
    shell.set_colliders(c, 5e-4).unwrap();
    let n0 = shell.positions().len();
    let omega2 = shell.collider_omega2();
    let dt = 0.25 * shell.stable_step().unwrap();
    for _ in 0..2000 {
        shell.step(dt).unwrap();
        shell.fracture().unwrap();
    }
    assert!(shell.positions().len() > n0);
    // A vertex's contact stiffness shrinks with its mass when fracture divides it, so the
    // colliders ring no faster on the split mesh than on the whole one (with one stiffness
    // for every vertex, the lightest new vertex set the pace: 21 times the square here).
    let after = shell.collider_omega2();
    assert!(after <= omega2, "{after} against {omega2}");
}
