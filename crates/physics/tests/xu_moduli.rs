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
    let m = XuModel::new(disc, &[mat], XuOptions::default()).unwrap();
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
