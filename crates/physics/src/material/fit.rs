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

use super::lanes::{self, wide};

/// Mandel components of `n n` (`n` unit): `n n : L = q(n) . l` with `l` the Mandel vector of
/// `L`.
#[inline]
pub(crate) fn mandel(n: Vec3) -> [f64; 6] {
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

/// Solves `a x = b` for a symmetric positive definite `N x N` `a` by Cholesky; `None` when a
/// pivot is not positive.
#[inline]
pub(crate) fn cholesky_solve<const N: usize>(
    mut a: [[f64; N]; N],
    mut b: [f64; N],
) -> Option<[f64; N]> {
    for c in 0..N {
        let mut d = a[c][c];
        for k in 0..c {
            d -= a[c][k] * a[c][k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        let d = d.sqrt();
        a[c][c] = d;
        for r in c + 1..N {
            let mut s = a[r][c];
            for k in 0..c {
                s -= a[r][k] * a[c][k];
            }
            a[r][c] = s / d;
        }
    }
    for r in 0..N {
        for k in 0..r {
            b[r] -= a[r][k] * b[k];
        }
        b[r] /= a[r][r];
    }
    for r in (0..N).rev() {
        for k in r + 1..N {
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
                    // the whole square, in rows the compiler packs: the upper triangle is the
                    // lower's products taken the other way round, and is overwritten below
                    let sq: [f64; 6] = std::array::from_fn(|p| s * q[p]);
                    for p in 0..6 {
                        for t in 0..6 {
                            a[p][t] += sq[p] * q[t];
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
                        // four bonds a vector where the CPU can, then one at a time (the
                        // same bits; the order of a maximum is immaterial)
                        let range = fam.range(i);
                        let row = &mut out[range.start - base..range.end - base];
                        let (done, mut worst) = lanes::fit_factors(fam, x, l, c, i, row);
                        for k in range.start + done..range.end {
                            let g = factors(fam, x, l, c, i, k);
                            out[k - base] = g;
                            worst = worst.max((g[0] - 1.0).abs());
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
                    // four bonds a vector where the CPU can and no deviatoric weights are
                    // given, then one at a time (the same bits, the bonds in order)
                    let range = fam.range(i);
                    let (done, mut m) = match w {
                        None => {
                            let row = &mut out[range.start - base..range.end - base];
                            lanes::fit_weights(fam, delta, blend, i, row, 1.0)
                        }
                        Some(_) => (0, 1.0),
                    };
                    for k in range.start + done..range.end {
                        let (w_ij, w_ji) = match w {
                            None => (delta / rl[k], delta / rl[k]),
                            Some((w, rev)) => (w[k], w[rev[k] as usize]),
                        };
                        let slot = &mut out[k - base];
                        let (d, f) = blended(*slot, (w_ij, w_ji), blend[i], blend[nb[k] as usize]);
                        *slot = d;
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

/// The fit's factors `[g_ij, g_ji]` of bond `k` of particle `i`: `q(n) . l / c` at each end
/// ([`dilatation_weights`]' first pass one bond at a time; [`lanes::fit_factors`] forms the
/// same bits four bonds a vector).
#[inline(always)]
fn factors(fam: &Family, x: &[Vec3], l: &[[f64; 6]], c: &[f64], i: usize, k: usize) -> [f64; 2] {
    let j = fam.neighbours()[k] as usize;
    let q = mandel(rest_direction(fam, x, i, k));
    let g_ij = (0..6).map(|p| q[p] * l[i][p]).sum::<f64>() / c[i];
    let g_ji = (0..6).map(|p| q[p] * l[j][p]).sum::<f64>() / c[j];
    [g_ij, g_ji]
}

/// A bond's weights `[w_ij (1 + a_i (g_ij - 1)) s_i, w_ji (1 + a_j (g_ji - 1)) s_j]` from its
/// factors `g`, its ends' weights `w` and their blends `[a, s]`, and the first over `w_ij`
/// ([`dilatation_weights`]' second pass one bond at a time; [`lanes::fit_weights`] forms the
/// same bits four bonds a vector).
#[inline(always)]
fn blended(
    [g_ij, g_ji]: [f64; 2],
    (w_ij, w_ji): (f64, f64),
    bi: [f64; 2],
    bj: [f64; 2],
) -> ([f64; 2], f64) {
    let d_ij = w_ij * (1.0 + bi[0] * (g_ij - 1.0)) * bi[1];
    let d_ji = w_ji * (1.0 + bj[0] * (g_ji - 1.0)) * bj[1];
    ([d_ij, d_ji], d_ij / w_ij)
}

/// A distribution of correction factors (1: docs/model.md's constant).
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

/// How far a Chen model's constants stray from docs/model.md's, from
/// [`super::ChenModel::correction`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction {
    /// Per particle: the dilatation weight over docs/model.md's of largest magnitude on its bonds.
    pub dilatation: Spread,
    /// Per particle: the deviatoric constant `b_i` over docs/model.md's.
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

    /// The setup's four-bond vectors ([`lanes::lengths`], [`lanes::fit_factors`],
    /// [`lanes::fit_weights`]) against the one-bond formulas, bit for bit, on every bond they
    /// take: a 4 x 4 x 3-cell Kuhn block (rows of 37 to 142 bonds, every count of tail bonds
    /// after the last four occurring) with its barycentres jittered by up to 1.5e-4 of a cell, so
    /// that no two bonds share a length or a direction, and tensors, constants and blends that
    /// differ from particle to particle (some factors negative). Off AVX2 the vectors take no
    /// bond and there is nothing to compare.
    #[test]
    fn setup_lanes_give_the_one_bond_formulas_bits() {
        use perifrac_topology::primitives::{lattice_box_data, Lattice};
        use perifrac_topology::TetMesh;
        let (v, t) = lattice_box_data([0.0; 3], [0.04, 0.04, 0.03], [4, 4, 3], Lattice::Kuhn);
        let (mesh, _) = TetMesh::new(v, t).expect("a valid box");
        let noise = crate::stable_step::start_vector(mesh.num_tets());
        let x: Vec<Vec3> = (mesh.rest_barycentres().iter().zip(&noise))
            .map(|(p, e)| std::array::from_fn(|a| p[a] + 3e-6 * e[a]))
            .collect();
        let delta = 1.45 * mesh.mean_edge_length();
        let disc =
            crate::Discretization::from_tets(&x, &mesh.rest_volumes(), mesh.neighbours(), delta)
                .expect("a valid family")
                .0;
        let fam = disc.family();
        let n = fam.len();
        let wave = |i: usize, p: usize| ((i * 7 + p * 3) as f64 * 0.37).sin();
        let l: Vec<[f64; 6]> = (0..n)
            .map(|i| std::array::from_fn(|p| if p < 3 { 1e4 } else { 3e4 * wave(i, p) }))
            .collect();
        let c: Vec<f64> = (0..n).map(|i| 1e4 * (1.0 + 0.2 * wave(i, 9))).collect();
        let blend: Vec<[f64; 2]> = (0..n)
            .map(|i| [0.5 + 0.5 * wave(i, 11).abs(), 1.0 + 0.1 * wave(i, 13)])
            .collect();
        let (mut took, mut negative) = (0usize, 0usize);
        for i in 0..n {
            let range = fam.range(i);
            let len = range.len();
            let nb = fam.row(i);
            // lengths: every bond, the vectors' and the tail's
            let mut r = vec![0.0; len];
            lanes::lengths(&x, i, nb, &mut r);
            for (o, &j) in nb.iter().enumerate() {
                let want = crate::math::norm(sub(x[j as usize], x[i]));
                assert_eq!(r[o].to_bits(), want.to_bits(), "length of bond {o} of {i}");
            }
            // the factors and their greatest departure from 1 over the bonds taken
            let mut row = vec![[0.0; 2]; len];
            let (done, worst) = lanes::fit_factors(fam, &x, &l, &c, i, &mut row);
            if lanes::available() {
                assert_eq!(done, len - len % 4, "particle {i}");
            }
            let mut want_worst: f64 = 0.0;
            for o in 0..done {
                let g = factors(fam, &x, &l, &c, i, range.start + o);
                assert_eq!(
                    row[o].map(f64::to_bits),
                    g.map(f64::to_bits),
                    "factors {o} of {i}"
                );
                want_worst = want_worst.max((g[0] - 1.0).abs());
                negative += usize::from(g[0] < 0.0);
            }
            assert_eq!(worst.to_bits(), want_worst.to_bits(), "particle {i}");
            // the weights from those factors, and the first of greatest magnitude
            let before = row.clone();
            let (done_w, m) = lanes::fit_weights(fam, delta, &blend, i, &mut row, 1.0);
            assert_eq!(done_w, done, "particle {i}");
            let mut want_m: f64 = 1.0;
            for o in 0..done {
                let k = range.start + o;
                let w = delta / fam.rest_lengths()[k];
                let (d, f) = blended(before[o], (w, w), blend[i], blend[nb[o] as usize]);
                assert_eq!(
                    row[o].map(f64::to_bits),
                    d.map(f64::to_bits),
                    "weights {o} of {i}"
                );
                if f.abs() > want_m.abs() {
                    want_m = f;
                }
            }
            assert_eq!(m.to_bits(), want_m.to_bits(), "particle {i}");
            took += done;
        }
        if lanes::available() {
            // the block has 22,678 bonds, and the vectors take all but the tails' 486
            assert!(took > 20_000, "{took}");
            // measured 22,192 and 5,516
            assert!(negative > 1_000, "{negative} negative factors");
        }
    }
}
