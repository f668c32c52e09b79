//! The compressible neo-Hookean law at a point: energy density, first Piola-Kirchhoff stress
//! and its tangent, all as functions of the displacement gradient `H = F - I`.
//!
//! `Psi(F) = mu/2 (tr(F^T F) - 3) - mu ln J + lambda/2 (ln J)^2`, `J = det F`, with the Lamé
//! constants of the linear material, so that small strains give linear elasticity.
//!
//! Everything is evaluated from `H`, not `F`, so that small strains keep their digits: with
//! `F^-T = (I + H)^-T`, `F - F^-T = H + F^-T H^T` exactly, `J - 1 = tr H + I2(H) + det H`
//! (`I2` the sum of the principal 2x2 minors) and `ln J = ln_1p(J - 1)`. Computed from `F`,
//! a strain of 1e-9 would lose seven of its sixteen digits to `F - F^-T` and the Newton
//! residual could not go below 1e-7 of the load.

use crate::material::Material;
use crate::math::{inverse, transpose, Mat3};

/// `dP_iJ / dF_kL`, stored at `[3 i + J][3 k + L]` (Pa).
pub type PiolaTangent = [[f64; 9]; 9];

/// Compressible neo-Hookean material with Lamé constants `lambda` and `mu` (Pa).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeoHookean {
    /// Lamé's first parameter (Pa).
    pub lambda: f64,
    /// Shear modulus (Pa).
    pub mu: f64,
}

/// What the stress and its tangent need at one point.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PointState {
    /// `F^-T`.
    pub inv_t: Mat3,
    /// `ln J`.
    pub ln_j: f64,
    /// `J - 1`.
    pub j_minus_1: f64,
    /// `I2(H) + det H`.
    pub i23: f64,
}

impl NeoHookean {
    /// The law with the Lamé constants of `material` (its density is not used here).
    pub fn new(material: &Material) -> Self {
        Self {
            lambda: material.lambda(),
            mu: material.mu(),
        }
    }

    /// `F^-T`, `ln J` and the invariants at displacement gradient `h`; `None` when `J <= 0` or
    /// something is not finite.
    #[inline]
    pub(crate) fn state(h: &Mat3) -> Option<PointState> {
        let i2 = h[0][0] * h[1][1] - h[0][1] * h[1][0] + h[0][0] * h[2][2] - h[0][2] * h[2][0]
            + h[1][1] * h[2][2]
            - h[1][2] * h[2][1];
        let i3 = crate::math::det(h);
        let j_minus_1 = h[0][0] + h[1][1] + h[2][2] + i2 + i3;
        // Rejects J <= 0 and NaN alike.
        if !j_minus_1.is_finite() || j_minus_1 <= -1.0 {
            return None;
        }
        let mut f = *h;
        for (i, row) in f.iter_mut().enumerate() {
            row[i] += 1.0;
        }
        let (inv, _) = inverse(&f);
        let inv_t = transpose(&inv);
        if inv_t.iter().flatten().any(|v| !v.is_finite()) {
            return None;
        }
        Some(PointState {
            inv_t,
            ln_j: j_minus_1.ln_1p(),
            j_minus_1,
            i23: i2 + i3,
        })
    }

    /// Energy density (J/m^3) at displacement gradient `h` (dimensionless, `F = I + h`), as
    /// `mu/2 |H|^2 - mu (I2 + det H) + mu (x - ln(1 + x)) + lambda/2 (ln J)^2` with `x = J - 1`
    /// (the same function as the definition, arranged to keep digits); `None` if `J <= 0`.
    pub fn energy_density(&self, h: &Mat3) -> Option<f64> {
        Self::state(h).map(|s| self.energy_of(h, &s))
    }

    #[inline]
    pub(crate) fn energy_of(&self, h: &Mat3, s: &PointState) -> f64 {
        let hh: f64 = h.iter().flatten().map(|v| v * v).sum();
        0.5 * self.mu * hh - self.mu * s.i23
            + self.mu * x_minus_ln_1p(s.j_minus_1)
            + 0.5 * self.lambda * s.ln_j * s.ln_j
    }

    /// First Piola-Kirchhoff stress (Pa) `P = mu (F - F^-T) + lambda ln J F^-T` at displacement
    /// gradient `h`; `None` if `J <= 0`.
    pub fn first_piola(&self, h: &Mat3) -> Option<Mat3> {
        Self::state(h).map(|s| self.piola_of(h, &s))
    }

    #[inline]
    pub(crate) fn piola_of(&self, h: &Mat3, s: &PointState) -> Mat3 {
        let g = &s.inv_t;
        let mut p = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                // (F^-T H^T)_ij = sum_k G_ik H_jk.
                let gh = g[i][0] * h[j][0] + g[i][1] * h[j][1] + g[i][2] * h[j][2];
                p[i][j] = self.mu * (h[i][j] + gh) + self.lambda * s.ln_j * g[i][j];
            }
        }
        p
    }

    /// Tangent `dP_iJ/dF_kL` (Pa) at displacement gradient `h`; `None` if `J <= 0`. With
    /// `G = F^-T`, `d(ln J)/dF = G` and `dG_iJ/dF_kL = -G_iL G_kJ`, so
    /// `dP_iJ/dF_kL = mu d_ik d_JL + lambda G_iJ G_kL + (mu - lambda ln J) G_iL G_kJ`.
    /// Symmetric (major symmetry), positive definite near `F = I`; it loses definiteness for
    /// large stretches (`ln J > mu / lambda` makes the last coefficient negative) and in
    /// compression-induced instabilities, which the Newton solver handles.
    pub fn tangent(&self, h: &Mat3) -> Option<PiolaTangent> {
        let s = Self::state(h)?;
        let g = &s.inv_t;
        let c = self.mu - self.lambda * s.ln_j;
        let mut a = [[0.0; 9]; 9];
        for i in 0..3 {
            for jj in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        let mut v = self.lambda * g[i][jj] * g[k][l] + c * g[i][l] * g[k][jj];
                        if i == k && jj == l {
                            v += self.mu;
                        }
                        a[3 * i + jj][3 * k + l] = v;
                    }
                }
            }
        }
        Some(a)
    }
}

/// `x - ln(1 + x)` for `x > -1`, without the cancellation of the direct formula near 0 (a
/// series below |x| = 1e-2, whose first omitted term is below 2e-19 of the sum).
#[inline]
fn x_minus_ln_1p(x: f64) -> f64 {
    if x.abs() < 1e-2 {
        // sum_{k=2}^{10} (-1)^k x^k / k, by Horner.
        let mut s = 0.0;
        for k in (2..=10).rev() {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            s = s * x + sign / f64::from(k);
        }
        s * x * x
    } else {
        x - x.ln_1p()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> NeoHookean {
        NeoHookean {
            lambda: 1.5e8,
            mu: 0.4e8,
        }
    }

    #[test]
    fn series_matches_the_direct_formula_where_both_are_accurate() {
        for x in [-9.9e-3, -1e-3, 1e-4, 5e-3, 9.99e-3] {
            let direct = x - f64::ln_1p(x);
            let rel = (x_minus_ln_1p(x) / direct - 1.0).abs();
            // The direct formula has a relative error of about 2 eps / |x| <= 5e-12 here.
            assert!(rel < 1e-11, "{x}: {rel}");
        }
        assert_eq!(x_minus_ln_1p(0.0), 0.0);
    }

    #[test]
    fn small_strains_give_linear_elasticity_to_full_precision() {
        let m = law();
        let e = 1e-9;
        let h: Mat3 = [
            [e, 2.0 * e, 0.0],
            [0.0, -0.5 * e, e],
            [0.3 * e, 0.0, 0.7 * e],
        ];
        let p = m.first_piola(&h).unwrap();
        let tr = h[0][0] + h[1][1] + h[2][2];
        for i in 0..3 {
            for j in 0..3 {
                let lin = m.mu * (h[i][j] + h[j][i]) + if i == j { m.lambda * tr } else { 0.0 };
                // Second-order terms are e^2 / e = 1e-9 of the stress.
                assert!(
                    (p[i][j] - lin).abs() <= 1e-8 * m.mu * e,
                    "{i}{j}: {} {lin}",
                    p[i][j]
                );
            }
        }
        assert!(m
            .first_piola(&[[-1.0, 0.0, 0.0], [0.0; 3], [0.0; 3]])
            .is_none());
        assert!(m
            .energy_density(&[[-2.0, 0.0, 0.0], [0.0; 3], [0.0; 3]])
            .is_none());
    }
}
