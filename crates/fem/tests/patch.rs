//! Patch tests on an irregular (jittered) box: an affine displacement imposed on the boundary
//! is reproduced inside for P1 and P2, and P2 reproduces a quadratic field under the body
//! force that equilibrates it.

mod common;

use common::{jittered_box, on_unit_cube_boundary, Rng};
use perifrac_fem::{static_linear, ElasticForces, Kinematics, Material, Mesh, Problem, Vec3};

/// Random affine map X -> A X + b with entries of size `size`.
fn affine(seed: u64, size: f64) -> impl Fn(Vec3) -> Vec3 + Copy + Send + Sync + 'static {
    let mut rng = Rng(seed);
    let a: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| size * rng.signed()));
    let b: Vec3 = std::array::from_fn(|_| size * rng.signed());
    move |x: Vec3| std::array::from_fn(|i| a[i][0] * x[0] + a[i][1] * x[1] + a[i][2] * x[2] + b[i])
}

fn material() -> Material {
    Material::new(2.0e9, 0.31, 1200.0).unwrap()
}

fn meshes() -> [Mesh; 2] {
    let (v, t) = jittered_box(3, 0.2, 7);
    [
        Mesh::linear(v.clone(), t.clone()).unwrap(),
        Mesh::quadratic(v, t).unwrap(),
    ]
}

#[test]
fn affine_displacement_is_reproduced_inside() {
    let u = affine(11, 1e-3);
    for mesh in meshes() {
        let mut problem = Problem::new(mesh, material()).unwrap();
        let held = problem.prescribe_where(on_unit_cube_boundary, move |x, _| {
            let d = u(x);
            [x[0] + d[0], x[1] + d[1], x[2] + d[2]]
        });
        assert!(held < problem.mesh().node_count());
        let solution = static_linear(&problem).unwrap();
        let mut worst = 0.0f64;
        for (x, got) in problem.mesh().nodes().iter().zip(&solution.displacements) {
            let want = u(*x);
            for d in 0..3 {
                worst = worst.max((got[d] - want[d]).abs());
            }
        }
        eprintln!(
            "{:?}: affine patch error {worst:e} m (field size 1e-3 m)",
            problem.mesh().order()
        );
        // Rounding: measured 1.1e-16 m for P1 and P2 (a tenth of a part per 1e12 of the field).
        assert!(worst < 1e-15, "{worst}");
    }
}

#[test]
fn affine_displacement_gives_zero_interior_force_in_the_kernel() {
    let u = affine(5, 1e-3);
    for mesh in meshes() {
        let m = material();
        let x: Vec<Vec3> = mesh
            .nodes()
            .iter()
            .map(|&p| {
                let d = u(p);
                [p[0] + d[0], p[1] + d[1], p[2] + d[2]]
            })
            .collect();
        let mut f = vec![[0.0; 3]; mesh.node_count()];
        for kin in [Kinematics::Linear, Kinematics::Corotated] {
            ElasticForces::new(&mesh, &m, kin)
                .compute(&x, &mut f)
                .unwrap();
            let interior: Vec<Vec3> = mesh
                .nodes()
                .iter()
                .zip(&f)
                .filter(|(p, _)| !on_unit_cube_boundary(**p))
                .map(|(_, f)| *f)
                .collect();
            let boundary = common::max_abs(&f);
            let worst = common::max_abs(&interior);
            eprintln!(
                "{:?} {kin:?}: interior force {worst:e} N, boundary up to {boundary:e} N",
                mesh.order()
            );
            // Boundary forces ~ stress * area ~ 2e6 Pa * 0.01 m^2; interior cancels to rounding.
            assert!(worst < 1e-9 * boundary, "{worst} vs {boundary}");
        }
    }
}

/// u_i = sum_jk Q_ijk X_j X_k (Q symmetric in j, k) has constant div sigma = (lambda + mu)
/// grad(div u) + mu lap(u); with the body force rho g = -div sigma it is the exact solution,
/// and it lies in the P2 space, so P2 with the consistent load reproduces it exactly.
#[test]
fn quadratic_tets_reproduce_a_quadratic_field_under_its_body_force() {
    let m = material();
    let (lambda, mu) = (m.lambda(), m.mu());
    let mut rng = Rng(3);
    let mut q = [[[0.0f64; 3]; 3]; 3];
    for qi in &mut q {
        let upper: [[f64; 3]; 3] =
            std::array::from_fn(|_| std::array::from_fn(|_| 1e-3 * rng.signed()));
        *qi = std::array::from_fn(|j| std::array::from_fn(|k| upper[j.min(k)][j.max(k)]));
    }
    let u = move |x: Vec3| -> Vec3 {
        std::array::from_fn(|i| {
            let mut s = 0.0;
            for j in 0..3 {
                for k in 0..3 {
                    s += q[i][j][k] * x[j] * x[k];
                }
            }
            s
        })
    };
    // grad(div u)_i = d_i sum_j d_j u_j = 2 sum_j Q_jji; lap(u)_i = 2 sum_j Q_ijj.
    let div_sigma: Vec3 = std::array::from_fn(|i| {
        let grad_div: f64 = (0..3).map(|j| 2.0 * q[j][j][i]).sum();
        let lap: f64 = (0..3).map(|j| 2.0 * q[i][j][j]).sum();
        (lambda + mu) * grad_div + mu * lap
    });
    let g = div_sigma.map(|c| -c / m.density);
    let (v, t) = jittered_box(3, 0.2, 9);
    let mut problem = Problem::new(Mesh::quadratic(v, t).unwrap(), m)
        .unwrap()
        .with_gravity(g);
    problem.prescribe_where(on_unit_cube_boundary, move |x, _| {
        let d = u(x);
        [x[0] + d[0], x[1] + d[1], x[2] + d[2]]
    });
    let solution = static_linear(&problem).unwrap();
    let worst = problem
        .mesh()
        .nodes()
        .iter()
        .zip(&solution.displacements)
        .map(|(x, got)| {
            (0..3)
                .map(|d| (got[d] - u(*x)[d]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    eprintln!(
        "P2 quadratic patch error {worst:e} m (field size 1e-3 m, |g| = {:e})",
        g.iter().map(|c| c * c).sum::<f64>().sqrt()
    );
    // Measured 1.1e-16 m; P1 misses the same field by 1.1e-5 m.
    assert!(worst < 1e-15, "{worst}");

    // P1 cannot: the same problem on linear tets misses by far more than rounding.
    let (v, t) = jittered_box(3, 0.2, 9);
    let mut p1 = Problem::new(Mesh::linear(v, t).unwrap(), m)
        .unwrap()
        .with_gravity(g);
    p1.prescribe_where(on_unit_cube_boundary, move |x, _| {
        let d = u(x);
        [x[0] + d[0], x[1] + d[1], x[2] + d[2]]
    });
    let s1 = static_linear(&p1).unwrap();
    let miss = p1
        .mesh()
        .nodes()
        .iter()
        .zip(&s1.displacements)
        .map(|(x, got)| {
            (0..3)
                .map(|d| (got[d] - u(*x)[d]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    eprintln!("P1 on the quadratic field misses by {miss:e} m");
    assert!(miss > 1e-7, "{miss}");
}
