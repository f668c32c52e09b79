//! The fitted dilatation (`ChenOptions::fitted_dilatation`, issue 18): homogeneous strains give
//! `theta = tr(eps)` on every particle, shear gives none; forces stay the exact gradient of the
//! energy and objective; the moduli it gives.

mod support;

use perifrac_physics::math::{mat_vec, rotation, Vec3};
use perifrac_physics::{ChenMaterial, ChenModel, ChenOptions};
use support::{
    affine, block, diff_all, forces, gradient_mismatch, nonuniform, norm_all, steel, tension,
};

fn fitted() -> ChenOptions {
    ChenOptions {
        fitted_dilatation: true,
        ..ChenOptions::default()
    }
}

/// The largest `|theta_i - tr(eps)|` over all particles of a block under the homogeneous
/// strain `eps` (symmetric, small), over `|eps|`.
fn dilatation_error(m: &mut ChenModel, eps: [[f64; 3]; 3]) -> f64 {
    let x = m.discretization().rest_positions().to_vec();
    let f = [
        [1.0 + eps[0][0], eps[0][1], eps[0][2]],
        [eps[1][0], 1.0 + eps[1][1], eps[1][2]],
        [eps[2][0], eps[2][1], 1.0 + eps[2][2]],
    ];
    let _ = forces(m, &affine(&x, &f, [0.0; 3]));
    let tr = eps[0][0] + eps[1][1] + eps[2][2];
    let size = eps.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    m.dilatations()
        .iter()
        .map(|t| (t - tr).abs())
        .fold(0.0, f64::max)
        / size
}

#[test]
fn fitted_dilatation_reads_every_homogeneous_strain_on_every_particle() {
    let e = 1e-6;
    let shear = [[0.0, e, 0.0], [e, 0.0, 0.0], [0.0, 0.0, 0.0]];
    let pull = [[e, 0.0, 0.0], [0.0, -0.3 * e, 0.0], [0.0, 0.0, -0.3 * e]];
    let twist = [[0.0, 0.0, e], [0.0, 0.5 * e, -e], [e, -e, -0.5 * e]];
    for (cells, k) in [([4, 3, 2], 1.5), ([6, 6, 6], 1.0), ([3, 3, 3], 2.0)] {
        let (disc, _, _) = block([0.04, 0.03, 0.02], cells, k);
        let mut fit = ChenModel::with_options(disc.clone(), &[steel()], fitted()).unwrap();
        let mut scalar = ChenModel::with_options(disc, &[steel()], support::SCALAR).unwrap();
        for (name, eps) in [("shear", shear), ("pull", pull), ("twist", twist)] {
            let (a, b) = (
                dilatation_error(&mut fit, eps),
                dilatation_error(&mut scalar, eps),
            );
            eprintln!(
                "{cells:?} k {k} {name}: |theta - tr eps| / |eps| fitted {a:.2e}, scalar {b:.2e}"
            );
            // The strain gives extensions of ~1e-6 r: the fit reproduces them up to the
            // linearisation of |F X| (relative ~1e-6) and the rounding of lengths of ~1e-2 m
            // (1e-18 m against 1e-8 m extensions): measured up to 1.1e-6.
            assert!(a < 2e-5, "{name}: {a}");
            // the scalar calibration reads corners' shear as volume change: measured 0.48 to 0.92
            assert!(b > 0.1, "{name}: {b}");
        }
    }
}

#[test]
fn fitted_force_is_the_gradient_and_objective() {
    // isotropic (the fitted weights beside `delta / r`) and anisotropic (beside stored
    // per-bond weights and the reverse index): the two weight layouts the loops take
    let mut aniso = steel();
    aniso.anisotropy = Some([[2.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]]);
    for (name, mat) in [("isotropic", steel()), ("anisotropic", aniso)] {
        let (disc, _, _) = block([0.03, 0.03, 0.02], [3, 3, 2], 1.5);
        let mut m = ChenModel::with_options(disc, &[mat], fitted()).unwrap();
        let x = m.discretization().rest_positions().to_vec();
        let y = nonuniform(&x, 0.01, 0.03);
        let f = forces(&mut m, &y);
        let worst = gradient_mismatch(&mut m, &y, &f, 1e-7 * 0.01, 7);
        eprintln!("fitted {name}: max |f + dE/dy| / max |f| = {worst:e}");
        // central differences of step 1e-9 m on energies of ~1e2 J: the same bound as the
        // scalar-calibrated model's test (tests/elastic.rs)
        assert!(worst < 1e-5, "{name}: {worst}");
        let r = rotation([1.0, 2.0, 0.5], 1.0);
        let fr = forces(&mut m, &affine(&y, &r, [0.3, -1.2, 0.7]));
        let rf: Vec<Vec3> = f.iter().map(|v| mat_vec(&r, *v)).collect();
        let err = diff_all(&fr, &rf) / norm_all(&f);
        eprintln!("fitted {name}: rotated force error {err:e}");
        // as tests/elastic.rs: rounding of rotated lengths against 1% strains
        assert!(err < 1e-9, "{name}: {err}");
    }
}

#[test]
#[ignore = "study: moduli with the fitted dilatation"]
fn fitted_moduli_study() {
    // (E / E0, nu) of a steel bar of section `cells` at horizon factor `k`, fitted
    let measure = |cells: [usize; 3], k: f64, nu: f64| {
        let size = cells.map(|c| c as f64 * 0.02 / cells[1] as f64);
        let (disc, _, _) = block(size, cells, k);
        let mat = ChenMaterial::from_young_poisson(200e9, nu, 7800.0).unwrap();
        let m = ChenModel::with_options(disc, &[mat], fitted()).unwrap();
        tension(m, size, nu, 200e9, 7800.0)
    };
    for cells in [[16, 4, 4], [24, 6, 6], [32, 8, 8]] {
        for nu in [0.1, 0.25, 0.4] {
            let (e, n) = measure(cells, 1.5, nu);
            eprintln!("{cells:?} nu0 {nu}: fitted E/E0 {e:.4} nu {n:.4}");
            if cells[1] == 8 {
                // issue 18's targets at 8 cells across: E within 3%, nu within 0.02 (measured
                // E/E0 1.0009 / 1.0020 / 1.0042, nu 0.088 / 0.237 / 0.389)
                assert!((e - 1.0).abs() < 0.03 && (n - nu).abs() < 0.02, "{e} {n}");
            }
        }
    }
    // The beams of `data/scenes/beam_stretch_*.toml`: 6 cells across at k = 1 (measured E/E0
    // 1.0305 / 1.0346 / 1.0395, nu 0.0683 / 0.1717 / 0.2757; the scalar calibration 1.0695 /
    // 1.0780 / 1.0877, nu 0.0910 / 0.1981 / 0.3049)
    for nu in [0.098, 0.2, 0.301] {
        let (e, n) = measure([24, 6, 6], 1.0, nu);
        eprintln!("[24, 6, 6] k 1 nu0 {nu}: fitted E/E0 {e:.4} nu {n:.4}");
    }
}
