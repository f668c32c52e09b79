//! Measured small-strain moduli of Xu's model with the linear basis against the input Young's
//! modulus and Poisson's ratio, for the paper's conversion and the consistent one, with
//! refinement (a bar in uniaxial tension, damped to rest; see `support::tension`).

mod support;

use perifrac_physics::{Curve, XuMaterial, XuModel, XuModuli, XuOptions};
use support::block;

const YOUNG: f64 = 1e6;
const RHO: f64 = 1000.0;

/// Measured (E / E0, nu) of a 5:1:1 bar `cells` with horizon factor `k`.
fn tension(cells: [usize; 3], k: f64, nu: f64, rule: XuModuli) -> (f64, f64) {
    let h = 0.02 / cells[1] as f64;
    let size = cells.map(|c| c as f64 * h);
    let (disc, _, _) = block(size, cells, k);
    let mat =
        XuMaterial::from_young_poisson(YOUNG, nu, RHO, Curve::Linear, Curve::Linear, rule).unwrap();
    // the normalised weights, on which docs/DECISIONS.md's table of the two conversions was
    // measured (the fitted dilatation's moduli: tests/xu_fitted.rs)
    let options = XuOptions {
        fitted_dilatation: false,
        ..XuOptions::default()
    };
    let m = XuModel::new(disc, &[mat], options).unwrap();
    support::tension(m, size, nu, YOUNG, RHO)
}

#[test]
#[ignore = "study: about a minute in release"]
fn xu_moduli_study() {
    for rule in [XuModuli::Paper, XuModuli::Consistent] {
        for nu in [0.1, 0.25, 0.4] {
            for cells in [[16, 4, 4], [24, 6, 6], [32, 8, 8]] {
                let (e, n) = tension(cells, 1.5, nu, rule);
                eprintln!("{rule:?} nu0 {nu}: {cells:?}: E/E0 {e:.4}, nu {n:.4}");
            }
        }
    }
}

#[test]
fn the_consistent_conversion_beats_the_papers() {
    // nu0 = 0.25, k = 1.5, 16 x 4 x 4 cells (a bar two horizons across). Measured: the paper's
    // conversion gives E / E0 = 1.277 and nu = 0.380, the consistent one 1.179 and 0.279
    // (0.264 at 32 x 8 x 8, see the study). Bounds: those values plus a margin, and the
    // consistent Poisson's ratio four times closer.
    let (ep, np) = tension([16, 4, 4], 1.5, 0.25, XuModuli::Paper);
    let (ec, nc) = tension([16, 4, 4], 1.5, 0.25, XuModuli::Consistent);
    eprintln!("paper: E/E0 {ep:.4}, nu {np:.4}; consistent: E/E0 {ec:.4}, nu {nc:.4}");
    assert!((ec - 1.0).abs() < 0.25 && (nc - 0.25).abs() < 0.05);
    assert!((nc - 0.25).abs() * 4.0 < (np - 0.25).abs());
    assert!((ec - 1.0).abs() < (ep - 1.0).abs());
}
