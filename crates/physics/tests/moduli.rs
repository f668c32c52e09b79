//! Measured elastic constants: Young's modulus and Poisson's ratio from a bar in uniaxial
//! tension (damped to rest), and the speed of a pulse along a bar against sqrt(E / rho).

mod support;

use perifrac_physics::{
    ChenMaterial, ChenModel, ChenOptions, Explicit, ExplicitConfig, Loads, TimeStep,
};
use support::{block, SCALAR};

/// Young's modulus (Pa) and density (kg/m^3) of the bars: steel-like.
const YOUNG: f64 = 200e9;
const RHO: f64 = 7800.0;

/// A bar of `cells` cubes of side `h` (m) with horizon factor `k`: the model, its rest
/// positions, its horizon (m) and its size (m).
fn bar(
    cells: [usize; 3],
    h: f64,
    k: f64,
    nu: f64,
    opts: ChenOptions,
) -> (ChenModel, Vec<[f64; 3]>, f64, [f64; 3]) {
    let size = cells.map(|c| c as f64 * h);
    let (disc, _, _) = block(size, cells, k);
    let x = disc.rest_positions().to_vec();
    let delta = disc.horizon();
    let mat = ChenMaterial::from_young_poisson(YOUNG, nu, RHO).unwrap();
    let m = ChenModel::with_options(disc, &[mat], opts).unwrap();
    (m, x, delta, size)
}

/// Measured (E / E_nominal, nu) of a bar `cells` (cube cells of 5 mm) with horizon factor `k`
/// (see [`support::tension`]).
fn tension(cells: [usize; 3], k: f64, nu: f64, opts: ChenOptions) -> (f64, f64) {
    let (m, _, _, size) = bar(cells, 0.02 / cells[1] as f64, k, nu, opts);
    support::tension(m, size, nu, YOUNG, RHO)
}

const MODEL_MD: ChenOptions = ChenOptions {
    energy_consistent: true,
    calibrated: false,
    fitted_dilatation: false,
};

#[test]
fn uniaxial_tension_moduli_improve_with_refinement() {
    // The default model (the fitted dilatation), nu = 0.25, k = 1.5. Bars of a 0.02 m section
    // are only two to four horizons across, so the cut families near the surface dominate:
    // measured E / E0 = 1.0626 and nu = 0.2146 at [16, 4, 4], 1.0214 and 0.2290 at [24, 6, 6]
    // (the scalar calibration: 1.1617 and 0.2750, 1.0864 and 0.2655; 1.0501 and 0.2631 at
    // [32, 8, 8], see the ignored study). Bounds: the measured errors plus a margin of about
    // half, and strictly smaller errors on the finer bar.
    let (e1, n1) = tension([16, 4, 4], 1.5, 0.25, ChenOptions::default());
    let (e2, n2) = tension([24, 6, 6], 1.5, 0.25, ChenOptions::default());
    eprintln!("[16, 4, 4]: E/E0 {e1:.4}, nu {n1:.4}; [24, 6, 6]: E/E0 {e2:.4}, nu {n2:.4}");
    assert!((e1 - 1.0).abs() < 0.1 && (n1 - 0.25).abs() < 0.05);
    assert!((e2 - 1.0).abs() < 0.035 && (n2 - 0.25).abs() < 0.03);
    assert!((e2 - 1.0).abs() < (e1 - 1.0).abs() && (n2 - 0.25).abs() < (n1 - 0.25).abs());
}

#[test]
fn uniaxial_tension_with_model_md_constants_is_soft_near_surfaces() {
    // docs/model.md's uniform constants keep nu (cut families soften bulk and shear alike) but the
    // bar is soft: measured E / E0 = 0.7872, nu = 0.2492 at [16, 4, 4], k = 1.5.
    let (e, n) = tension([16, 4, 4], 1.5, 0.25, MODEL_MD);
    eprintln!("docs/model.md constants [16, 4, 4]: E/E0 {e:.4}, nu {n:.4}");
    assert!((0.75..0.85).contains(&e) && (n - 0.25).abs() < 0.02);
}

#[test]
#[ignore = "slow (~2.5 min on 2 cores): convergence study of the measured moduli"]
fn moduli_convergence_study() {
    // Measured (E / E0, nu) for nu0 = 0.1 / 0.25 / 0.4, the scalar calibration (the fitted
    // dilatation, the default: tests/fitted.rs's study):
    //   k 1.0: [16,4,4] 1.134 0.087 / 1.158 0.256 / 1.188 0.430
    //          [24,6,6] 1.070 0.093 / 1.083 0.251 / 1.102 0.410
    //          [32,8,8] 1.047 0.098 / 1.056 0.253 / 1.071 0.408
    //   k 1.5: [16,4,4] 1.136 0.101 / 1.162 0.275 / 1.196 0.458
    //          [24,6,6] 1.073 0.104 / 1.086 0.266 / 1.106 0.431
    //          [32,8,8] 1.042 0.107 / 1.050 0.263 / 1.063 0.421
    // docs/model.md constants:
    //   k 1.0: [16,4,4] 0.781 0.079 / 0.785 0.235 / 0.808 0.414
    //          [32,8,8] 0.795 0.081 / 0.798 0.233 / 0.814 0.396
    //   k 1.5: [16,4,4] 0.783 0.094 / 0.787 0.249 / 0.812 0.435
    //          [24,6,6] 0.836 0.099 / 0.838 0.252 / 0.853 0.418
    //          [32,8,8] 0.862 0.104 / 0.862 0.254 / 0.873 0.412
    for k in [1.0, 1.5] {
        for nu in [0.1, 0.25, 0.4] {
            let mut errors = Vec::new();
            for cells in [[16, 4, 4], [24, 6, 6], [32, 8, 8]] {
                let (e, n) = tension(cells, k, nu, SCALAR);
                let (m_e, m_n) = tension(cells, k, nu, MODEL_MD);
                eprintln!(
                    "{cells:?} k {k} nu0 {nu}: calibrated E/E0 {e:.4} nu {n:.4}; docs/model.md E/E0 {m_e:.4} nu {m_n:.4}"
                );
                errors.push(((e - 1.0).abs(), (n - nu).abs()));
            }
            let (e_fine, n_fine) = errors[2];
            assert!(e_fine < 0.08 && n_fine < 0.025, "finest: {errors:?}");
            assert!(errors[2].0 < errors[1].0 && errors[1].0 < errors[0].0);
        }
    }
}

/// Speed of the leading edge of a smooth pulse along a free bar of `cells` 5 mm cubes, from the
/// half-peak arrival times at 30% and 70% of its length, over sqrt(E / rho).
fn pulse_speed(cells: [usize; 3], k: f64, nu: f64, opts: ChenOptions) -> f64 {
    let h = 0.005;
    let (m, x, delta, size) = bar(cells, h, k, nu, opts);
    let c = (YOUNG / RHO).sqrt();
    let cfg = ExplicitConfig {
        dt: TimeStep::Auto { safety: 0.8 },
        guard_fraction: 0.5,
    };
    let mut s = Explicit::new(m, &x, delta, Loads::new(x.len()), cfg).unwrap();
    // a half-Gaussian velocity at the free end, sigma = 4 delta: its wavelengths are mostly above
    // 12 delta, where the model's dispersion stays below 1% (docs/model.md section 2)
    let w = 4.0 * delta;
    for (v, p) in s.velocities_mut().iter_mut().zip(&x) {
        v[0] = (-0.5 * (p[0] / w).powi(2)).exp();
    }
    let len = size[0];
    let probe = |at: f64| -> Vec<usize> {
        (0..x.len())
            .filter(|&i| (x[i][0] - at * len).abs() < 0.5 * h)
            .collect()
    };
    let (p1, p2) = (probe(0.3), probe(0.7));
    let mean_v = |s: &Explicit<ChenModel>, set: &[usize]| {
        set.iter().map(|&i| s.velocities()[i][0]).sum::<f64>() / set.len() as f64
    };
    let steps = (0.85 * len / c / s.dt()).ceil() as usize;
    let (mut h1, mut h2) = (vec![0.0], vec![mean_v(&s, &p2)]);
    h1[0] = mean_v(&s, &p1);
    for _ in 0..steps {
        s.step().unwrap();
        h1.push(mean_v(&s, &p1));
        h2.push(mean_v(&s, &p2));
    }
    // leading-edge time where the signal first reaches half its peak (linear interpolation)
    let arrival = |hist: &[f64]| -> f64 {
        let peak = hist.iter().cloned().fold(f64::MIN, f64::max);
        let k = hist
            .iter()
            .position(|&v| v >= 0.5 * peak)
            .expect("pulse arrives");
        let (a, b) = (hist[k - 1], hist[k]);
        (k as f64 - 1.0 + (0.5 * peak - a) / (b - a)) * s.dt()
    };
    0.4 * len / (arrival(&h2) - arrival(&h1)) / c
}

#[test]
#[ignore = "documents the thin-bar surface effect on the wave speed"]
fn pulse_speed_in_a_thin_bar() {
    // A 3 x 3 cell section is 1.5 horizons across, so every particle is a surface particle and
    // with the scalar calibration the bar is as stiff as its calibrated surface (E_eff ~ 1.2
    // E0): measured c / sqrt(E/rho) = 1.1000 (k = 1, nu = 0.25). The 5% check is on the
    // thicker bar below.
    let r = pulse_speed([160, 3, 3], 1.0, 0.25, SCALAR);
    eprintln!("[160, 3, 3] k 1: c / sqrt(E/rho) = {r:.4}");
    assert!((r - 1.0).abs() < 0.12);
}

#[test]
fn pulse_speed_within_five_percent() {
    // A 1 m bar with a 4 x 4 cm section (76,800 particles, ~12 s here). Measured c / sqrt(E/rho)
    // (nu = 0.25): [200,8,8] k 1.0: 1.0105 (the default, fitted), 1.0280 (the scalar
    // calibration); thinner bars are stiffer from their calibrated surface (scalar:
    // [160,4,4] k 1.5: 1.0743, [160,3,3] k 1.0: 1.1000). With docs/model.md's uniform constants the
    // thin bars are soft: 0.881 and 0.867.
    let r = pulse_speed([200, 8, 8], 1.0, 0.25, ChenOptions::default());
    eprintln!("[200, 8, 8] k 1: c / sqrt(E/rho) = {r:.4}");
    assert!((r - 1.0).abs() < 0.05);
}
