//! Shape functions of the straight-sided linear (4-node) and quadratic (10-node) tets, in
//! barycentric coordinates, and the quadrature rules used with them.
//!
//! Node order (VTK's): corners 0..4, then the midpoints of edges (0,1), (1,2), (0,2), (0,3),
//! (1,3), (2,3).

use crate::math::Vec3;

/// Corner pairs of the six edges, in the order of the quadratic tet's nodes 4..10.
pub const EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]];

/// A quadrature point: barycentric coordinates and weight (fraction of the tet's volume; the
/// weights of a rule add up to 1).
pub(crate) type QuadPoint = ([f64; 4], f64);

/// 1-point rule, exact for degree 1.
pub(crate) const RULE_1: [QuadPoint; 1] = [([0.25; 4], 1.0)];

const A4: f64 = 0.585_410_196_624_968_5; // (5 + 3 sqrt 5) / 20
const B4: f64 = 0.138_196_601_125_010_5; // (5 - sqrt 5) / 20

/// 4-point rule, exact for degree 2: enough for the quadratic tet's stiffness (gradients are
/// linear, so the integrand is quadratic) and its consistent body load.
pub(crate) const RULE_4: [QuadPoint; 4] = [
    ([A4, B4, B4, B4], 0.25),
    ([B4, A4, B4, B4], 0.25),
    ([B4, B4, A4, B4], 0.25),
    ([B4, B4, B4, A4], 0.25),
];

const A14: f64 = 0.310_885_919_263_300_6;
const B14: f64 = 0.092_735_250_310_891_3;
const C14: f64 = 0.045_503_704_125_649_9;
const WA14: f64 = 0.112_687_925_718_015_6;
const WB14: f64 = 0.073_493_043_116_361_9;
const WC14: f64 = 0.042_546_020_777_081_5;
const D14: f64 = 1.0 - 3.0 * A14;
const E14: f64 = 1.0 - 3.0 * B14;
const F14: f64 = 0.5 - C14;

/// 14-point rule, exact for degree 5: two 4-point orbits `(a, a, a, 1 - 3a)` and one 6-point
/// orbit `(c, c, 1/2 - c, 1/2 - c)`, every point inside the tet and every weight positive (the
/// 11-point degree-4 rule has a negative weight, which can make a quadrature of a convex
/// energy non-convex). Used for the quadratic tet's non-polynomial hyperelastic energy; the
/// constants are checked against the exact moments in the tests below.
pub(crate) const RULE_14: [QuadPoint; 14] = [
    ([D14, A14, A14, A14], WA14),
    ([A14, D14, A14, A14], WA14),
    ([A14, A14, D14, A14], WA14),
    ([A14, A14, A14, D14], WA14),
    ([E14, B14, B14, B14], WB14),
    ([B14, E14, B14, B14], WB14),
    ([B14, B14, E14, B14], WB14),
    ([B14, B14, B14, E14], WB14),
    ([C14, C14, F14, F14], WC14),
    ([C14, F14, C14, F14], WC14),
    ([C14, F14, F14, C14], WC14),
    ([F14, C14, C14, F14], WC14),
    ([F14, C14, F14, C14], WC14),
    ([F14, F14, C14, C14], WC14),
];

/// Shape functions of one element type with `N` nodes.
pub(crate) trait Basis<const N: usize>: Send + Sync + 'static {
    /// The quadrature rule that integrates this element's stiffness exactly.
    const RULE: &'static [QuadPoint];
    /// Shape function values at barycentric coordinates `l`.
    fn values(l: [f64; 4]) -> [f64; N];
    /// Shape function gradients (1/m) at `l`, given the gradients of the barycentric
    /// coordinates (1/m, constant over a straight-sided tet).
    fn gradients(l: [f64; 4], grad_l: &[Vec3; 4]) -> [Vec3; N];
}

/// The linear 4-node tet.
pub(crate) struct P1;
/// The quadratic 10-node tet.
pub(crate) struct P2;

impl Basis<4> for P1 {
    const RULE: &'static [QuadPoint] = &RULE_1;

    #[inline]
    fn values(l: [f64; 4]) -> [f64; 4] {
        l
    }

    #[inline]
    fn gradients(_l: [f64; 4], grad_l: &[Vec3; 4]) -> [Vec3; 4] {
        *grad_l
    }
}

impl Basis<10> for P2 {
    const RULE: &'static [QuadPoint] = &RULE_4;

    #[inline]
    fn values(l: [f64; 4]) -> [f64; 10] {
        let mut n = [0.0; 10];
        for i in 0..4 {
            n[i] = l[i] * (2.0 * l[i] - 1.0);
        }
        for (k, [a, b]) in EDGES.into_iter().enumerate() {
            n[4 + k] = 4.0 * l[a] * l[b];
        }
        n
    }

    #[inline]
    fn gradients(l: [f64; 4], g: &[Vec3; 4]) -> [Vec3; 10] {
        let mut out = [[0.0; 3]; 10];
        for i in 0..4 {
            let s = 4.0 * l[i] - 1.0;
            out[i] = [s * g[i][0], s * g[i][1], s * g[i][2]];
        }
        for (k, [a, b]) in EDGES.into_iter().enumerate() {
            let (la, lb) = (4.0 * l[a], 4.0 * l[b]);
            out[4 + k] = [
                la * g[b][0] + lb * g[a][0],
                la * g[b][1] + lb * g[a][1],
                la * g[b][2] + lb * g[a][2],
            ];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact integral over the unit-volume-normalised tet of prod l_i^k_i:
    /// k0! k1! k2! k3! 3! / (sum k + 3)!.
    fn exact(k: [u32; 4]) -> f64 {
        let f = |n: u32| (1..=n).map(f64::from).product::<f64>();
        k.iter().map(|&n| f(n)).product::<f64>() * 6.0 / f(k.iter().sum::<u32>() + 3)
    }

    #[test]
    fn rules_integrate_their_degree_exactly() {
        for (rule, degree) in [(&RULE_1[..], 1), (&RULE_4[..], 2), (&RULE_14[..], 5)] {
            for a in 0..=degree {
                for b in 0..=degree - a {
                    for c in 0..=degree - a - b {
                        let k = [a, b, c, degree - a - b - c];
                        let q: f64 = rule
                            .iter()
                            .map(|(l, w)| {
                                w * (0..4).map(|i| l[i].powi(k[i] as i32)).product::<f64>()
                            })
                            .sum();
                        // The constants have 16 digits: a few rounding errors of the moments.
                        assert!((q - exact(k)).abs() < 2e-15, "{k:?}: {q} vs {}", exact(k));
                    }
                }
            }
        }
    }

    #[test]
    fn quadratic_shape_functions_partition_unity_and_are_nodal() {
        let nodes: Vec<[f64; 4]> = (0..4)
            .map(|i| {
                let mut l = [0.0; 4];
                l[i] = 1.0;
                l
            })
            .chain(EDGES.iter().map(|&[a, b]| {
                let mut l = [0.0; 4];
                l[a] = 0.5;
                l[b] = 0.5;
                l
            }))
            .collect();
        for (i, l) in nodes.iter().enumerate() {
            let n = P2::values(*l);
            for (j, v) in n.iter().enumerate() {
                assert!((v - f64::from(u8::from(i == j))).abs() < 1e-15);
            }
        }
        let n = P2::values([0.1, 0.2, 0.3, 0.4]);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }
}
