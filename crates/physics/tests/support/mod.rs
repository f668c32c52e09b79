//! Shared test helpers: tet blocks from the topology crate's primitives, deformations, norms.
#![allow(dead_code)]

use perifrac_physics::math::{add, mat_vec, norm, sub, Mat3, Vec3};
use perifrac_physics::{
    ChenMaterial, ChenModel, ChenOptions, Discretization, FamilyReport, ForceModel, YieldParams,
};
use perifrac_topology::primitives::box_data;
use perifrac_topology::TetMesh;

/// A block `[0, size]` cut into `cells` cuboids (6 Kuhn tets each), horizon `k * lambda`.
/// Returns the discretisation, the family report and `lambda` (mean edge length).
pub fn block(size: [f64; 3], cells: [usize; 3], k: f64) -> (Discretization, FamilyReport, f64) {
    let (v, t) = box_data([0.0; 3], size, cells);
    let (mesh, _) = TetMesh::new(v, t).expect("box mesh");
    let lambda = mesh.mean_edge_length();
    let (disc, report) = Discretization::from_tets(
        &mesh.rest_barycentres(),
        &mesh.rest_volumes(),
        mesh.neighbours(),
        k * lambda,
    )
    .expect("discretisation");
    (disc, report, lambda)
}

/// Steel-like test material: E = 200 GPa, nu = 0.25, rho = 7800 kg/m^3.
pub fn steel() -> ChenMaterial {
    ChenMaterial::from_young_poisson(200e9, 0.25, 7800.0).expect("valid")
}

/// The scalar calibration alone (`correction = "calibrated"`, the default before issue 18):
/// the fitted dilatation off.
pub const SCALAR: ChenOptions = ChenOptions {
    energy_consistent: true,
    calibrated: true,
    fitted_dilatation: false,
};

/// An elastic Chen model on a block, with the scalar calibration ([`SCALAR`]): the model the
/// tests that use it measured their figures on.
pub fn scalar_block(cells: [usize; 3], k: f64) -> ChenModel {
    let size = cells.map(|c| c as f64 * 0.01);
    let (disc, _, _) = block(size, cells, k);
    ChenModel::with_options(disc, &[steel()], SCALAR).expect("model")
}

/// An elastic Chen model on a block.
pub fn elastic_block(cells: [usize; 3], k: f64) -> ChenModel {
    let size = [
        cells[0] as f64 * 0.01,
        cells[1] as f64 * 0.01,
        cells[2] as f64 * 0.01,
    ];
    let (disc, _, _) = block(size, cells, k);
    ChenModel::new(disc, &[steel()]).expect("model")
}

/// `y_i = F X_i + c`.
pub fn affine(x: &[Vec3], f: &Mat3, c: Vec3) -> Vec<Vec3> {
    x.iter().map(|&p| add(mat_vec(f, p), c)).collect()
}

/// Root of the sum of squared norms.
pub fn norm_all(v: &[Vec3]) -> f64 {
    v.iter()
        .map(|a| a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
        .sum::<f64>()
        .sqrt()
}

/// Root of the sum of squared differences.
pub fn diff_all(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| norm(sub(*p, *q)).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Particles at least `margin` from every face of the box `[0, size]`.
pub fn interior(x: &[Vec3], size: [f64; 3], margin: f64) -> Vec<usize> {
    (0..x.len())
        .filter(|&i| (0..3).all(|d| x[i][d] > margin && x[i][d] < size[d] - margin))
        .collect()
}

/// A smooth, non-uniform deformation of amplitude `amp` (dimensionless strain scale) on a body of
/// size `l`: quadratic terms make the strain vary in space.
pub fn nonuniform(x: &[Vec3], amp: f64, l: f64) -> Vec<Vec3> {
    x.iter()
        .map(|p| {
            let (u, v, w) = (p[0] / l, p[1] / l, p[2] / l);
            [
                p[0] + amp * l * (0.7 * u + 0.3 * v * v - 0.2 * u * w),
                p[1] + amp * l * (-0.4 * v + 0.5 * u * w + 0.1 * w),
                p[2] + amp * l * (0.6 * w * w - 0.3 * u + 0.25 * u * v),
            ]
        })
        .collect()
}

/// Forces at `y` without touching the model's state (no return map).
pub fn forces<M: ForceModel + ?Sized>(m: &mut M, y: &[Vec3]) -> Vec<Vec3> {
    let mut f = vec![[0.0; 3]; y.len()];
    m.trial_forces(y, &mut f);
    f
}

/// Largest `|f + dE/dy|` over `max |f|`, with `dE/dy` by central differences of step `h` (m) on
/// every `stride`-th particle, where `f` are the forces at `y`.
pub fn gradient_mismatch<M: ForceModel + ?Sized>(
    m: &mut M,
    y: &[Vec3],
    f: &[Vec3],
    h: f64,
    stride: usize,
) -> f64 {
    let fmax = f.iter().map(|v| norm(*v)).fold(0.0, f64::max);
    let mut worst: f64 = 0.0;
    for i in (0..y.len()).step_by(stride) {
        for d in 0..3 {
            let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
            yp[i][d] += h;
            ym[i][d] -= h;
            let g = (m.elastic_energy(&yp) - m.elastic_energy(&ym)) / (2.0 * h);
            worst = worst.max((f[i][d] + g).abs() / fmax);
        }
    }
    worst
}

/// Least-squares slope of `v` against `u`.
pub fn slope(u: &[f64], v: &[f64]) -> f64 {
    let n = u.len() as f64;
    let (mu, mv) = (u.iter().sum::<f64>() / n, v.iter().sum::<f64>() / n);
    let cov: f64 = u.iter().zip(v).map(|(a, b)| (a - mu) * (b - mv)).sum();
    let var: f64 = u.iter().map(|a| (a - mu) * (a - mu)).sum();
    cov / var
}

/// Measured (E / `young`, nu) of the bar `m` of extent `size` (m, along x) with nominal
/// Poisson's ratio `nu`, wave speed `sqrt(young / rho)`: both ends anchored (one fixed, one
/// pulled to 0.1% strain), damped to rest. Strains are fitted over the middle third; the stress
/// is the anchor reaction over the nominal cross-section.
pub fn tension<M: ForceModel>(m: M, size: [f64; 3], nu: f64, young: f64, rho: f64) -> (f64, f64) {
    use perifrac_physics::{Explicit, ExplicitConfig, Loads, TimeStep};
    let x = m.discretization().rest_positions().to_vec();
    let delta = m.discretization().horizon();
    let len = size[0];
    // the ends: particles within one horizon of them, so no free family is cut by an anchor
    let left: Vec<u32> = (0..x.len() as u32)
        .filter(|&i| x[i as usize][0] < delta)
        .collect();
    let right: Vec<u32> = (0..x.len() as u32)
        .filter(|&i| x[i as usize][0] > len - delta)
        .collect();
    let c = (young / rho).sqrt();
    let omega1 = std::f64::consts::PI * c / len;
    let mut loads = Loads::new(x.len()).with_damping(2.0 * omega1).unwrap();
    loads.anchor(&left, [0.0; 3]).unwrap();
    loads.anchor(&right, [0.0; 3]).unwrap();
    let cfg = ExplicitConfig {
        dt: TimeStep::Auto { safety: 0.8 },
        guard_fraction: 0.5,
    };
    let mut s = Explicit::new(m, &x, delta, loads, cfg).unwrap();
    // start from the affine guess with the nominal Poisson contraction
    let eps = 1e-3;
    let (cy, cz) = (size[1] / 2.0, size[2] / 2.0);
    let guess: Vec<[f64; 3]> = x
        .iter()
        .map(|p| {
            let ex = eps * p[0].clamp(delta, len - delta);
            [
                p[0] + ex,
                p[1] - nu * eps * (p[1] - cy),
                p[2] - nu * eps * (p[2] - cz),
            ]
        })
        .collect();
    s.set_positions(&guess);
    let steps = (40.0 / omega1 / s.dt()).ceil() as usize;
    for _ in 0..steps {
        s.step().unwrap();
    }
    let y = s.positions();
    let mid: Vec<usize> = (0..x.len())
        .filter(|&i| (x[i][0] - len / 2.0).abs() < len / 6.0)
        .collect();
    let ux: Vec<f64> = mid.iter().map(|&i| y[i][0] - x[i][0]).collect();
    let uy: Vec<f64> = mid.iter().map(|&i| y[i][1] - x[i][1]).collect();
    let uz: Vec<f64> = mid.iter().map(|&i| y[i][2] - x[i][2]).collect();
    let px: Vec<f64> = mid.iter().map(|&i| x[i][0]).collect();
    let py: Vec<f64> = mid.iter().map(|&i| x[i][1]).collect();
    let pz: Vec<f64> = mid.iter().map(|&i| x[i][2]).collect();
    let exx = slope(&px, &ux);
    let eyy = 0.5 * (slope(&py, &uy) + slope(&pz, &uz));
    let reaction: f64 = right
        .iter()
        .map(|&i| s.forces()[i as usize][0])
        .sum::<f64>();
    let stress = -reaction / (size[1] * size[2]);
    (stress / exx / young, -eyy / exx)
}

/// `mesh` as particles at horizon factor `k` (times the mean edge length).
pub fn mesh_disc(mesh: &TetMesh, k: f64) -> Discretization {
    Discretization::from_tets(
        &mesh.rest_barycentres(),
        &mesh.rest_volumes(),
        mesh.neighbours(),
        k * mesh.mean_edge_length(),
    )
    .expect("discretisation")
    .0
}

/// Steel of Poisson's ratio `nu` whose bonds yield at the deviatoric strain `eps_y` (the
/// scene's `yield_strain`, converted with docs/model.md's `b` at horizon `delta` (m) and rescaled
/// per particle), extensions capped at 0.2 of a bond.
pub fn yielding_steel(nu: f64, eps_y: f64, delta: f64) -> ChenMaterial {
    let mut mat = ChenMaterial::from_young_poisson(200e9, nu, 7800.0).unwrap();
    let b = 15.0 * mat.shear_modulus / (2.0 * std::f64::consts::PI * delta.powi(5));
    let a_y = 4.0 * delta * b * eps_y;
    mat.plasticity = Some(YieldParams {
        psi0: 0.5 * a_y * a_y,
        gamma_ratio: 0.2,
        from_strain: true,
    });
    mat
}

/// `x` with every point past `x = at` (m) moved by `gap` (m) along x: a body pulled apart
/// across that plane.
pub fn pulled_apart(x: &[Vec3], at: f64, gap: f64) -> Vec<Vec3> {
    x.iter()
        .map(|p| {
            if p[0] > at {
                add(*p, [gap, 0.0, 0.0])
            } else {
                *p
            }
        })
        .collect()
}
