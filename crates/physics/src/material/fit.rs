//! The fitted dilatation (issue 18): per-bond dilatation weights `d_ij = omega_ij (n n : L_i)`,
//! with one symmetric tensor `L_i` per particle chosen so that
//! `sum_j d_ij r_ij (n n) V_j = I` over the particle's own rest family. Then every homogeneous
//! small strain `eps` (bond extensions `r n . eps . n`) gives `theta_i = tr(eps)` exactly on
//! every particle, cut families at surfaces, edges and corners included: a pure shear gives no
//! dilatation and a pure dilatation no deviatoric extension. A scalar per particle (the
//! calibration `c_i = 3 / sum omega r V`) can only match the trace of that moment, so on a
//! family cut unevenly it reads shear as volume change.
//!
//! An anisotropic material (`omega = delta / |G xi|`) reads a strain through the moment of its
//! weights, so the continuum's dilatation is `A : eps` with `A = 3 M / tr M`,
//! `M = int_S2 n n / |G n| dn` (the radial integral is common to every direction), not
//! `tr(eps)`: the target is then `A` in place of `I` ([`anisotropic_target`]), which keeps the
//! material's directional stiffness in the dilatation where the scalar calibration kept it
//! (an interior family's `c_i sum omega r (n n) V` is `A` to the lattice's accuracy).
//!
//! The six conditions are linear in `L_i` (Mandel components `q(n)`:
//! `sum_j omega r V q q^T L = (1, 1, 1, 0, 0, 0)`), a 6 x 6 symmetric positive semi-definite
//! system per particle, solved by Cholesky with a small ridge towards the scalar calibration
//! (which is the answer for a family that is symmetric enough and stands in where the
//! family's directions do not span the six modes).

// Small dense factorisations: index loops read as the formulas do.
#![allow(clippy::needless_range_loop)]

use crate::family::Family;
use crate::math::{sub, Vec3};
use crate::par::{for_rows_mut, map_particles};

use super::lanes::wide;

/// Mandel components of `n n` (`n` unit): `n n : L = q(n) . l` with `l` the Mandel vector of
/// `L`.
#[inline]
fn mandel(n: Vec3) -> [f64; 6] {
    let s = std::f64::consts::SQRT_2;
    [
        n[0] * n[0],
        n[1] * n[1],
        n[2] * n[2],
        s * n[1] * n[2],
        s * n[0] * n[2],
        s * n[0] * n[1],
    ]
}

/// The rest direction of bond `k` from particle `i` (unit).
#[inline]
fn rest_direction(fam: &Family, x: &[Vec3], i: usize, k: usize) -> Vec3 {
    let (j, r) = (fam.neighbours()[k] as usize, fam.rest_lengths()[k]);
    sub(x[j], x[i]).map(|c| c / r)
}

/// Solves `a x = b` for a symmetric positive definite 6 x 6 `a` by Cholesky; `None` when a
/// pivot is not positive.
#[inline]
fn cholesky_solve(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    for c in 0..6 {
        let mut d = a[c][c];
        for k in 0..c {
            d -= a[c][k] * a[c][k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        let d = d.sqrt();
        a[c][c] = d;
        for r in c + 1..6 {
            let mut s = a[r][c];
            for k in 0..c {
                s -= a[r][k] * a[c][k];
            }
            a[r][c] = s / d;
        }
    }
    for r in 0..6 {
        for k in 0..r {
            b[r] -= a[r][k] * b[k];
        }
        b[r] /= a[r][r];
    }
    for r in (0..6).rev() {
        for k in r + 1..6 {
            b[r] -= a[k][r] * b[k];
        }
        b[r] /= a[r][r];
    }
    Some(b)
}

/// Mandel vector of the identity, the target of an isotropic material.
pub(crate) const ISOTROPIC_TARGET: [f64; 6] = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0];

/// Gauss-Legendre nodes and weights on [-1, 1] (`N` points; Newton on `P_N` from the
/// Chebyshev guesses, to round-off).
fn gauss_legendre<const N: usize>() -> ([f64; N], [f64; N]) {
    let (mut nodes, mut weights) = ([0.0; N], [0.0; N]);
    for i in 0..N {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_N(z) and P_{N-1}(z) by the three-term recurrence
            let (mut p0, mut p1) = (1.0, z);
            for n in 2..=N {
                let p2 = ((2 * n - 1) as f64 * z * p1 - (n - 1) as f64 * p0) / n as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = N as f64 * (z * p1 - p0) / (z * z - 1.0);
            let step = p1 / dp;
            z -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        nodes[i] = z;
        weights[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (nodes, weights)
}

/// Mandel vector of `A = 3 M / tr M`, `M = int_S2 n n / |G n| dn`: the dilatation the
/// continuum of the anisotropic weight `omega = delta / |G xi|` reads from a uniform strain
/// `eps` is `A : eps`. Gauss-Legendre in `cos(polar)` (32 points) by the trapezoid rule in the
/// azimuth (64): exact for `G = I` (`A = I` to round-off) and converged to round-off for the
/// smooth `1 / |G n|` of the anisotropies scenes use (tested).
pub(crate) fn anisotropic_target(g: &[[f64; 3]; 3]) -> [f64; 6] {
    const AZIMUTHS: usize = 64;
    let (mu, wmu) = gauss_legendre::<32>();
    let mut m = [[0.0; 3]; 3];
    for (&c, &wc) in mu.iter().zip(&wmu) {
        let s = (1.0 - c * c).sqrt();
        for a in 0..AZIMUTHS {
            let phi = 2.0 * std::f64::consts::PI * a as f64 / AZIMUTHS as f64;
            let n = [s * phi.cos(), s * phi.sin(), c];
            let gn: Vec3 = std::array::from_fn(|r| (0..3).map(|t| g[r][t] * n[t]).sum());
            let f = wc / (gn[0] * gn[0] + gn[1] * gn[1] + gn[2] * gn[2]).sqrt();
            for r in 0..3 {
                for t in 0..3 {
                    m[r][t] += f * n[r] * n[t];
                }
            }
        }
    }
    let tr = m[0][0] + m[1][1] + m[2][2];
    let a = |r: usize, t: usize| 3.0 * m[r][t] / tr;
    let s = std::f64::consts::SQRT_2;
    [
        a(0, 0),
        a(1, 1),
        a(2, 2),
        s * a(1, 2),
        s * a(0, 2),
        s * a(0, 1),
    ]
}

/// The weight `omega` of bond `k`: `w[k]`, or `delta / r` without per-bond weights.
#[inline]
fn omega(w: Option<&[f64]>, delta: f64, rl: &[f64], k: usize) -> f64 {
    w.map_or_else(|| delta / rl[k], |w| w[k])
}

/// The Mandel vector `l_i` of every particle's fitted tensor `L_i`: the family's moment
/// `A_i = sum_j omega_ij r_ij V_j q q^T` (rest directions `n = (X_j - X_i) / r`, deviatoric
/// weights `w` or, without them, `delta / r`), ridged by `ridge` times its mean diagonal towards
/// `c_i I` (the scalar calibration, `c`), then solved for the target of the particle's material
/// (`targets[material[i]]`: [`ISOTROPIC_TARGET`] or [`anisotropic_target`]). A particle whose
/// system has no positive pivot (no bonds) keeps `c_i I`.
// The family, its geometry and weights, the scalars, the targets and the ridge are each the
// fit's own input.
#[allow(clippy::too_many_arguments)]
pub(crate) fn fit_tensors(
    fam: &Family,
    x: &[Vec3],
    vol: &[f64],
    w: Option<&[f64]>,
    delta: f64,
    c: &[f64],
    (targets, material): (&[[f64; 6]], &[u16]),
    ridge: f64,
) -> Vec<[f64; 6]> {
    let mut out = vec![[0.0; 6]; fam.len()];
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    map_particles(&mut out, |i| {
        wide(
            #[inline(always)]
            || {
                let scalar = [c[i], c[i], c[i], 0.0, 0.0, 0.0];
                let mut a = [[0.0; 6]; 6];
                for k in fam.range(i) {
                    let q = mandel(rest_direction(fam, x, i, k));
                    let s = omega(w, delta, rl, k) * rl[k] * vol[nb[k] as usize];
                    for p in 0..6 {
                        for t in 0..=p {
                            a[p][t] += s * q[p] * q[t];
                        }
                    }
                }
                for p in 0..6 {
                    for t in 0..p {
                        a[t][p] = a[p][t];
                    }
                }
                let tau = ridge * (0..6).map(|p| a[p][p]).sum::<f64>() / 6.0;
                let mut b = targets[material[i] as usize];
                for p in 0..6 {
                    a[p][p] += tau;
                    b[p] += tau * scalar[p];
                }
                cholesky_solve(a, b).unwrap_or(scalar)
            },
        )
    });
    out
}

/// Per-bond dilatation weights over the scalar calibration, `d_ij / c_i = w_ij g_ij`, with
/// `g_ij = q(n_ij) . l_i / c_i` the fit's factor, times `c_i / own[i]` (over the particle's own
/// constant), written into `out[k][0]`, and the reverse bond's `d_ji / c_j` into `out[k][1]`
/// (`omega` is the deviatoric weights `w` or, without them, `delta / r`; with them, the
/// reverse index finds the reverse's). A particle whose largest `|g_ij|` passes `bound` is
/// blended towards the scalar calibration (`g = 1`): `g' = 1 + a (g - 1)` with the largest
/// `a <= 1` that keeps every `|g'| <= bound` (its fit is then exact no more). The reverse's
/// value is computed as its own row computes it: `q(n)` is even in `n`, the rest length
/// symmetric, so both slots hold exactly the bits each end writes for itself. Into
/// `worst[i]`, the particle's `d_ij / (c_i omega_ij)` of largest magnitude (1 when none passes
/// 1 in magnitude), for [`Correction`], in the same walk.
// The family, its geometry and weights, the tensors, the scalars and the bound are each the
// weights' own input.
#[allow(clippy::too_many_arguments)]
pub(crate) fn dilatation_weights(
    fam: &Family,
    x: &[Vec3],
    w: Option<(&[f64], &[u32])>,
    delta: f64,
    l: &[[f64; 6]],
    c: &[f64],
    bound: f64,
    own: &[f64],
    out: &mut [[f64; 2]],
    worst: &mut [f64],
) {
    let rl = fam.rest_lengths();
    let nb = fam.neighbours();
    let offsets = fam.offsets();
    // First the fit's factors of both ends, `[g_ij, g_ji]` (`q(n_ji) = q(n_ij)` to the bit, so
    // `g_ji` is what row j computes), and per particle its blend `a` and the factor over its
    // own constant.
    let mut blend = vec![[0.0; 2]; fam.len()];
    for_rows_mut(
        offsets,
        &mut blend,
        out,
        &|first, blend: &mut [[f64; 2]], out| {
            let base = offsets[first] as usize;
            wide(
                #[inline(always)]
                || {
                    for (i, b) in (first..).zip(blend.iter_mut()) {
                        let mut worst: f64 = 0.0;
                        for k in fam.range(i) {
                            let j = nb[k] as usize;
                            let q = mandel(rest_direction(fam, x, i, k));
                            let g_ij = (0..6).map(|p| q[p] * l[i][p]).sum::<f64>() / c[i];
                            let g_ji = (0..6).map(|p| q[p] * l[j][p]).sum::<f64>() / c[j];
                            out[k - base] = [g_ij, g_ji];
                            worst = worst.max((g_ij - 1.0).abs());
                        }
                        // |1 + a (g - 1)| <= 1 + a |g - 1| <= bound
                        let a = if worst > bound - 1.0 {
                            (bound - 1.0) / worst
                        } else {
                            1.0
                        };
                        *b = [a, c[i] / own[i]];
                    }
                },
            )
        },
    );
    // Then both ends' weights, each blended by its own particle's `a`, and the particle's
    // weight of largest magnitude over its `omega`.
    let blend = &blend;
    for_rows_mut(offsets, worst, out, &|first, worst: &mut [f64], out| {
        let base = offsets[first] as usize;
        wide(
            #[inline(always)]
            || {
                for (i, most) in (first..).zip(worst.iter_mut()) {
                    let mut m: f64 = 1.0;
                    for k in fam.range(i) {
                        let slot = &mut out[k - base];
                        let j = nb[k] as usize;
                        let (w_ij, w_ji) = match w {
                            None => (delta / rl[k], delta / rl[k]),
                            Some((w, rev)) => (w[k], w[rev[k] as usize]),
                        };
                        let ([g_ij, g_ji], bi, bj) = (*slot, blend[i], blend[j]);
                        *slot = [
                            w_ij * (1.0 + bi[0] * (g_ij - 1.0)) * bi[1],
                            w_ji * (1.0 + bj[0] * (g_ji - 1.0)) * bj[1],
                        ];
                        let f = slot[0] / w_ij;
                        if f.abs() > m.abs() {
                            m = f;
                        }
                    }
                    *most = m;
                }
            },
        )
    });
}

/// A distribution of correction factors (1: MODEL.md's constant).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Smallest factor.
    pub min: f64,
    /// Median.
    pub median: f64,
    /// 99th percentile of the factors' magnitudes.
    pub p99: f64,
    /// Largest magnitude.
    pub max: f64,
}

impl Spread {
    /// The spread of `v` (all 1 when empty); order statistics by selection (linear time), not
    /// by sorting.
    pub fn of(mut v: Vec<f64>) -> Spread {
        if v.is_empty() {
            return Spread {
                min: 1.0,
                median: 1.0,
                p99: 1.0,
                max: 1.0,
            };
        }
        let min = v.iter().copied().min_by(f64::total_cmp).unwrap_or(1.0);
        let half = v.len() / 2;
        let median = *v.select_nth_unstable_by(half, f64::total_cmp).1;
        for x in &mut v {
            *x = x.abs();
        }
        let top = v.len() - 1;
        let max = v.iter().copied().max_by(f64::total_cmp).unwrap_or(1.0);
        let p99 = *v.select_nth_unstable_by(top * 99 / 100, f64::total_cmp).1;
        Spread {
            min,
            median,
            p99,
            max,
        }
    }
}

/// How far a Chen model's constants stray from MODEL.md's, from
/// [`super::ChenModel::correction`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction {
    /// Per particle: the dilatation weight over MODEL.md's of largest magnitude on its bonds.
    pub dilatation: Spread,
    /// Per particle: the deviatoric constant `b_i` over MODEL.md's.
    pub deviatoric: Spread,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `a b` for 3 x 3 matrices.
    fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
    }

    /// `A` from the Mandel vector.
    fn full(a: [f64; 6]) -> [[f64; 3]; 3] {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        [
            [a[0], h * a[5], h * a[4]],
            [h * a[5], a[1], h * a[3]],
            [h * a[4], h * a[3], a[2]],
        ]
    }

    #[test]
    fn anisotropic_target_is_exact_for_identity_and_rotates_with_the_material() {
        let id = anisotropic_target(&crate::math::IDENTITY);
        for (p, v) in id.iter().enumerate() {
            let want = if p < 3 { 1.0 } else { 0.0 };
            // a polynomial of degree 2 in cos(polar) and in the azimuth's cosine: the
            // quadrature is exact, only round-off is left
            assert!((v - want).abs() < 1e-13, "{id:?}");
        }
        // a stretch of 1.5 along x: omega grows along x, so does the dilatation's weight
        let g = crate::anisotropy::chen_matrix(&crate::math::IDENTITY, [1.5, 1.0, 1.0 / 1.5]);
        let a = full(anisotropic_target(&g));
        assert!(a[0][0] > a[1][1] && a[1][1] > a[2][2], "{a:?}");
        assert!((a[0][0] + a[1][1] + a[2][2] - 3.0).abs() < 1e-13);
        // the same material turned by R (G R^T) reads R A R^T
        let r = crate::math::rotation([1.0, -2.0, 0.5], 0.7);
        let rt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| r[j][i]));
        let gr = mat_mul(&g, &rt);
        let ar = full(anisotropic_target(&gr));
        let want = mat_mul(&mat_mul(&r, &a), &rt);
        let mut worst: f64 = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                worst = worst.max((ar[i][j] - want[i][j]).abs());
            }
        }
        eprintln!("turned anisotropic target: largest difference {worst:e}");
        // the turned material's quadrature samples other directions: agreement says the
        // quadrature has converged (measured 2.2e-15 here at 32 x 64 points, 6e-12 at 24 x 48)
        assert!(worst < 1e-12, "{ar:?} {want:?}");
    }

    #[test]
    fn cholesky_solves_a_symmetric_system() {
        // a = m m^T + I for a fixed m: symmetric positive definite
        let mut a = [[0.0; 6]; 6];
        for p in 0..6 {
            for t in 0..6 {
                a[p][t] = (0..6)
                    .map(|k| ((p * 7 + k * 3) % 5) as f64 * ((t * 7 + k * 3) % 5) as f64)
                    .sum::<f64>()
                    + if p == t { 1.0 } else { 0.0 };
            }
        }
        let x = [1.0, -2.0, 0.5, 3.0, 0.0, -1.0];
        let b: Vec<f64> = (0..6)
            .map(|p| (0..6).map(|t| a[p][t] * x[t]).sum())
            .collect();
        let got = cholesky_solve(a, b.try_into().unwrap()).unwrap();
        for p in 0..6 {
            // entries of a up to ~100, condition far below 1e4: 1e-10 is generous round-off
            assert!((got[p] - x[p]).abs() < 1e-10, "{got:?}");
        }
        let mut singular = [[0.0; 6]; 6];
        singular[0][0] = 1.0;
        assert!(cholesky_solve(singular, [1.0; 6]).is_none());
    }
}
