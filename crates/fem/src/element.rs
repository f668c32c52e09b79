//! Per-element kernels, generic over the element type: stiffness matrix, body load, and the
//! elastic force and energy for linear and corotated kinematics. All integrate with the
//! element's own rule ([`Basis::RULE`]).

use crate::basis::Basis;
use crate::math::{mat_mul, mat_t_mul, polar_rotation, Mat3, Vec3};

/// Lamé parameters (Pa).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lame {
    pub lambda: f64,
    pub mu: f64,
}

impl Lame {
    /// Stress (Pa) of a small strain: lambda tr(eps) I + 2 mu eps.
    #[inline]
    fn stress(&self, eps: &Mat3) -> Mat3 {
        let tr = eps[0][0] + eps[1][1] + eps[2][2];
        let mut s = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                s[i][j] = 2.0 * self.mu * eps[i][j];
            }
            s[i][i] += self.lambda * tr;
        }
        s
    }

    /// Energy density (J/m^3) of a small strain: mu eps:eps + lambda/2 tr(eps)^2.
    #[inline]
    fn energy_density(&self, eps: &Mat3) -> f64 {
        let tr = eps[0][0] + eps[1][1] + eps[2][2];
        let mut ee = 0.0;
        for row in eps {
            for v in row {
                ee += v * v;
            }
        }
        self.mu * ee + 0.5 * self.lambda * tr * tr
    }
}

/// Displacement gradient `H[i][j] = sum_a u_a[i] dN_a/dX_j`.
#[inline]
pub(crate) fn gradient<const N: usize>(u: &[Vec3; N], grads: &[Vec3; N]) -> Mat3 {
    let mut h = [[0.0; 3]; 3];
    for a in 0..N {
        for i in 0..3 {
            for j in 0..3 {
                h[i][j] += u[a][i] * grads[a][j];
            }
        }
    }
    h
}

#[inline]
fn sym(m: &Mat3) -> Mat3 {
    let mut s = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            s[i][j] = 0.5 * (m[i][j] + m[j][i]);
        }
    }
    s
}

/// Corotated strain `sym(R^T F) - I` and `R`, from the displacement gradient `H = F - I`.
#[inline]
fn corotated_strain(h: &Mat3) -> Option<(Mat3, Mat3)> {
    let mut f = *h;
    for (i, row) in f.iter_mut().enumerate() {
        row[i] += 1.0;
    }
    let r = polar_rotation(&f)?;
    // R^T F - I = R^T H + (R^T - I): computed so that a rigid rotation gives zero to rounding.
    let mut s = mat_t_mul(&r, h);
    for i in 0..3 {
        for j in 0..3 {
            s[i][j] += r[j][i];
        }
        s[i][i] -= 1.0;
    }
    Some((sym(&s), r))
}

/// Element stiffness (N/m), `(3N) x (3N)` row-major into `out`, DOF `3a + i` for node `a`,
/// component `i`: `K_ab,ij = sum_q w_q V [lambda dNa_i dNb_j + mu dNa_j dNb_i + mu d_ij dNa.dNb]`.
pub(crate) fn stiffness<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    lame: Lame,
    out: &mut [f64],
) {
    let n3 = 3 * N;
    debug_assert_eq!(out.len(), n3 * n3);
    out.fill(0.0);
    for &(l, w) in B::RULE {
        let g = B::gradients(l, grad_l);
        let wv = w * volume;
        for a in 0..N {
            for b in 0..N {
                let gab = g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2];
                for i in 0..3 {
                    let row = &mut out[(3 * a + i) * n3 + 3 * b..(3 * a + i) * n3 + 3 * b + 3];
                    for j in 0..3 {
                        let mut k = lame.lambda * g[a][i] * g[b][j] + lame.mu * g[a][j] * g[b][i];
                        if i == j {
                            k += lame.mu * gab;
                        }
                        row[j] += wv * k;
                    }
                }
            }
        }
    }
}

/// `integral of N_a dV` (m^3) for each node: the consistent load of a unit body force.
pub(crate) fn load<const N: usize, B: Basis<N>>(volume: f64) -> [f64; N] {
    let mut out = [0.0; N];
    for &(l, w) in B::RULE {
        let n = B::values(l);
        for a in 0..N {
            out[a] += w * volume * n[a];
        }
    }
    out
}

/// Internal elastic force (N) on each node, `-dE/dx`, for linear kinematics (`-K_e u`).
#[inline]
pub(crate) fn force_linear<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    lame: Lame,
    u: &[Vec3; N],
    out: &mut [Vec3; N],
) {
    *out = [[0.0; 3]; N];
    for &(l, w) in B::RULE {
        let g = B::gradients(l, grad_l);
        let sigma = lame.stress(&sym(&gradient(u, &g)));
        scatter_stress(&sigma, &g, w * volume, out);
    }
}

/// Internal elastic force (N) on each node for corotated kinematics: at each quadrature point
/// `P = R sigma(sym(R^T F) - I)` with `R` the polar rotation of that point's `F`, the exact
/// gradient of the energy [`energy_corotated`]. Returns `false` if some `det F <= 0`.
#[inline]
pub(crate) fn force_corotated<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    lame: Lame,
    u: &[Vec3; N],
    out: &mut [Vec3; N],
) -> bool {
    *out = [[0.0; 3]; N];
    for &(l, w) in B::RULE {
        let g = B::gradients(l, grad_l);
        let Some((eps, r)) = corotated_strain(&gradient(u, &g)) else {
            return false;
        };
        let p = mat_mul(&r, &lame.stress(&eps));
        scatter_stress(&p, &g, w * volume, out);
    }
    true
}

/// `out_a -= wv * P grad N_a`.
#[inline]
fn scatter_stress<const N: usize>(p: &Mat3, g: &[Vec3; N], wv: f64, out: &mut [Vec3; N]) {
    for a in 0..N {
        for i in 0..3 {
            out[a][i] -= wv * (p[i][0] * g[a][0] + p[i][1] * g[a][1] + p[i][2] * g[a][2]);
        }
    }
}

/// Strain energy (J) for linear kinematics: `sum_q w_q V (mu eps:eps + lambda/2 tr(eps)^2)`.
pub(crate) fn energy_linear<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    lame: Lame,
    u: &[Vec3; N],
) -> f64 {
    B::RULE
        .iter()
        .map(|&(l, w)| {
            let g = B::gradients(l, grad_l);
            w * volume * lame.energy_density(&sym(&gradient(u, &g)))
        })
        .sum()
}

/// Strain energy (J) for corotated kinematics, with `eps = sym(R^T F) - I`; `None` if some
/// `det F <= 0`.
pub(crate) fn energy_corotated<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    lame: Lame,
    u: &[Vec3; N],
) -> Option<f64> {
    let mut e = 0.0;
    for &(l, w) in B::RULE {
        let g = B::gradients(l, grad_l);
        let (eps, _) = corotated_strain(&gradient(u, &g))?;
        e += w * volume * lame.energy_density(&eps);
    }
    Some(e)
}
