//! Parameters of Xu's hyperelastic peridynamic material (docs/model.md section 5).

use super::basis::Curve;
use super::params::{bad, check_young_poisson, FractureParams};
use crate::error::PhysicsError;
use crate::math::{dot, Mat3, Vec3};

/// Xu's anisotropic kernel `G_ij = |Sigma R xi / r|` (docs/model.md section 4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XuAnisotropy {
    /// Orthonormal material axes, as the columns of `R`.
    pub axes: Mat3,
    /// `Sigma = diag(s1, s2, s3)`, `s1 s2 s3 = 1` (the overall stiffness is kept).
    pub stretch: Vec3,
}

impl XuAnisotropy {
    /// `G` of a bond along `xi` (any length but zero): `|Sigma R^T xi| / |xi|`, the stretch
    /// weighted by the bond's components along the material axes.
    #[inline]
    pub fn factor(&self, xi: Vec3) -> f64 {
        let r2 = dot(xi, xi);
        let mut s = 0.0;
        for a in 0..3 {
            let axis = [self.axes[0][a], self.axes[1][a], self.axes[2][a]];
            let c = self.stretch[a] * dot(axis, xi);
            s += c * c;
        }
        (s / r2).sqrt()
    }

    fn check(&self) -> Result<(), String> {
        let s = self.stretch;
        if !s.iter().all(|v| v.is_finite() && *v > 0.0) {
            return Err(format!("anisotropy stretches {s:?} must be positive"));
        }
        let product = s[0] * s[1] * s[2];
        if (product - 1.0).abs() > 1e-9 {
            return Err(format!(
                "anisotropy stretches {s:?} multiply to {product}, must be 1 (Xu's kernel keeps \
                 the overall stiffness); scale them by {:.6}",
                product.powf(-1.0 / 3.0)
            ));
        }
        for a in 0..3 {
            for b in 0..3 {
                let col = |c: usize| [self.axes[0][c], self.axes[1][c], self.axes[2][c]];
                let want = if a == b { 1.0 } else { 0.0 };
                let off = (dot(col(a), col(b)) - want).abs();
                if off.is_nan() || off > 1e-9 {
                    return Err(format!(
                        "anisotropy axes {:?} must be orthonormal",
                        self.axes
                    ));
                }
            }
        }
        Ok(())
    }
}

/// How Young's modulus and Poisson's ratio become Xu's `lambda` and `mu`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XuModuli {
    /// The paper's approximate relation (docs/model.md section 5):
    /// `lambda = 9 E nu / (2 (1 + nu)(1 - 2 nu))`, `mu = 15 E / (4 (1 + nu))`.
    Paper,
    /// The small-strain limit of the energy over a full, isotropic, normalised family:
    /// the bond term gives shear `mu h''(1) / 15` and adds `mu h''(1) / 15` to Lame's first
    /// constant, the dilatation term adds `lambda g''(1) / 9`. Solving for `lambda`, `mu`:
    /// `mu = 15 G / h''(1)`, `lambda = 9 (lambda_L - G) / g''(1)` with `G`, `lambda_L` the
    /// Lame constants of `E`, `nu`. For the named curves `mu` equals the paper's and
    /// `lambda` is smaller by `9 G / 2` (negative below `nu = 1/4`, which the energy allows when
    /// `g = h`, see [`XuMaterial::validate`]).
    Consistent,
}

/// One material region of Xu's model.
#[derive(Debug, Clone, PartialEq)]
pub struct XuMaterial {
    /// `lambda` of the dilatation term (Pa).
    pub lambda: f64,
    /// `mu` of the bond term (Pa).
    pub mu: f64,
    /// Density `rho` (kg/m^3).
    pub density: f64,
    /// Energy curve `g` of the dilatation.
    pub g: Curve,
    /// Energy curve `h` of each bond's stretch ratio.
    pub h: Curve,
    /// Anisotropic kernel; `None` is `G = 1`.
    pub anisotropy: Option<XuAnisotropy>,
    /// Bond breaking, as in Chen's model (`sw = e / delta` against `s_crit (1 + alpha phi)`).
    pub fracture: Option<FractureParams>,
}

impl XuMaterial {
    /// A material from Young's modulus `young` (Pa), Poisson's ratio `poisson`, `density`
    /// (kg/m^3) and the curves, with `lambda`, `mu` by `rule`.
    pub fn from_young_poisson(
        young: f64,
        poisson: f64,
        density: f64,
        g: Curve,
        h: Curve,
        rule: XuModuli,
    ) -> Result<Self, PhysicsError> {
        check_young_poisson(young, poisson)?;
        let (lambda, mu) = match rule {
            XuModuli::Paper => (
                9.0 * young * poisson / (2.0 * (1.0 + poisson) * (1.0 - 2.0 * poisson)),
                15.0 * young / (4.0 * (1.0 + poisson)),
            ),
            XuModuli::Consistent => {
                let shear = young / (2.0 * (1.0 + poisson));
                let lame = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
                (
                    9.0 * (lame - shear) / g.rest_curvature(),
                    15.0 * shear / h.rest_curvature(),
                )
            }
        };
        Ok(XuMaterial {
            lambda,
            mu,
            density,
            g,
            h,
            anisotropy: None,
            fracture: None,
        })
    }

    /// Smallest and largest `G` of the kernel (1, 1 when isotropic).
    pub fn kernel_range(&self) -> (f64, f64) {
        match &self.anisotropy {
            None => (1.0, 1.0),
            Some(a) => (
                a.stretch.iter().cloned().fold(f64::INFINITY, f64::min),
                a.stretch.iter().cloned().fold(0.0, f64::max),
            ),
        }
    }

    /// True when this material breaks bonds (a finite `s_crit`).
    pub fn fractures(&self) -> bool {
        self.fracture.is_some_and(|f| f.s_crit.is_finite())
    }

    /// Checks every parameter; `index` names the material in the error. Besides ranges: both
    /// curves convex at rest, and every bond's rest stiffness `lambda g''(1) + mu G h''(1)`
    /// positive. A negative `lambda` is allowed only with `g = h` and `mu min G > |lambda|`:
    /// then `W >= (mu min G - |lambda|) sum_j w_ij V_j h(tau_ij) >= 0` (Jensen's inequality on
    /// the convex `h`, with `sum_j w_ij V_j = 1`), so the energy stays bounded below.
    pub fn validate(&self, index: usize) -> Result<(), PhysicsError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.mu) {
            return Err(bad(index, format!("mu {} Pa must be positive", self.mu)));
        }
        if !self.lambda.is_finite() {
            return Err(bad(
                index,
                format!("lambda {} Pa must be finite", self.lambda),
            ));
        }
        if !pos(self.density) {
            return Err(bad(
                index,
                format!("density {} kg/m^3 must be positive", self.density),
            ));
        }
        let msg = |e: PhysicsError| bad(index, e.to_string());
        self.g.validate("g").map_err(msg)?;
        self.h.validate("h").map_err(msg)?;
        if let Some(a) = &self.anisotropy {
            a.check().map_err(|m| bad(index, m))?;
        }
        let (g_min, _) = self.kernel_range();
        let stiffness =
            self.lambda * self.g.rest_curvature() + self.mu * g_min * self.h.rest_curvature();
        if stiffness.is_nan() || stiffness <= 0.0 {
            return Err(bad(
                index,
                format!(
                    "bond stiffness at rest lambda g''(1) + mu G h''(1) = {stiffness} Pa is not \
                     positive (lambda {}, mu {}, smallest G {g_min})",
                    self.lambda, self.mu
                ),
            ));
        }
        if self.lambda < 0.0 && (self.g != self.h || self.mu * g_min <= -self.lambda) {
            return Err(bad(
                index,
                format!(
                    "lambda {} Pa < 0 needs g = h and mu * min G > |lambda| (mu {}, min G \
                     {g_min}), or the energy is unbounded below; Poisson's ratios under 1/4 \
                     need that",
                    self.lambda, self.mu
                ),
            ));
        }
        if let Some(f) = self.fracture {
            f.validate(index)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{mat_vec, rotation, IDENTITY};

    #[test]
    fn moduli_rules() {
        let (e, nu) = (1e6, 0.3);
        let p = XuMaterial::from_young_poisson(
            e,
            nu,
            1e3,
            Curve::Linear,
            Curve::Linear,
            XuModuli::Paper,
        )
        .unwrap();
        // docs/model.md: lam = 9 E nu / (2 (1 + nu)(1 - 2 nu)), mu = 15 E / (4 (1 + nu))
        assert!((p.lambda - 9.0 * e * nu / (2.0 * 1.3 * 0.4)).abs() < 1e-6);
        assert!((p.mu - 15.0 * e / (4.0 * 1.3)).abs() < 1e-6);
        let c = XuMaterial::from_young_poisson(
            e,
            nu,
            1e3,
            Curve::NeoHookean,
            Curve::NeoHookean,
            XuModuli::Consistent,
        )
        .unwrap();
        assert!((c.mu - p.mu).abs() < 1e-6);
        // smaller by 9 G / 2
        assert!((p.lambda - c.lambda - 4.5 * e / 2.6).abs() < 1e-6);
        assert!(c.validate(0).is_ok() && p.validate(0).is_ok());
        // nu = 0.1: consistent lambda < 0, allowed with g = h
        let low = XuMaterial::from_young_poisson(
            e,
            0.1,
            1e3,
            Curve::Linear,
            Curve::Linear,
            XuModuli::Consistent,
        )
        .unwrap();
        assert!(low.lambda < 0.0);
        assert!(low.validate(0).is_ok());
        let mixed = XuMaterial {
            g: Curve::NeoHookean,
            ..low
        };
        assert!(mixed.validate(3).is_err());
    }

    #[test]
    fn anisotropic_kernel() {
        let a = XuAnisotropy {
            axes: IDENTITY,
            stretch: [4.0, 0.25, 1.0],
        };
        assert!(a.check().is_ok());
        assert!((a.factor([2.0, 0.0, 0.0]) - 4.0).abs() < 1e-15);
        assert!((a.factor([0.0, -3.0, 0.0]) - 0.25).abs() < 1e-15);
        // it turns with the axes: the first axis along r x
        let r = rotation([0.3, 1.0, -0.2], 0.9);
        let b = XuAnisotropy {
            axes: r,
            stretch: a.stretch,
        };
        let along = mat_vec(&r, [1.0, 0.0, 0.0]);
        assert!((b.factor(along) - 4.0).abs() < 1e-14);
        assert!(XuAnisotropy {
            axes: IDENTITY,
            stretch: [2.0, 1.0, 1.0]
        }
        .check()
        .is_err());
        assert!(XuAnisotropy {
            axes: [[1.0; 3]; 3],
            stretch: [1.0; 3]
        }
        .check()
        .is_err());
    }
}
