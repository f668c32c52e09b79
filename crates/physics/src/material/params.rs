//! Parameters of the Chen elastoplastic material with fracture (docs/model.md section 2).

use crate::error::PhysicsError;
use crate::math::Mat3;

/// Yield limit of the Chen plastic model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YieldParams {
    /// `Psi0`: yield when `A_dev^2 / 2 > Psi0` (units of `A^2`, i.e. (N/m^6)^2: depends on delta).
    pub psi0: f64,
    /// Cap of the plastic extension as a ratio of the rest bond length (dimensionless).
    pub gamma_ratio: f64,
    /// `psi0` was converted from a yield strain with docs/model.md's `b = 15 mu / (2 pi delta^5)`:
    /// each particle scales it by `(b_i / b)^2`, so that a bond yields at that deviatoric
    /// strain with the particle's own (corrected) `b_i`, at the surface as in the bulk. False:
    /// `psi0` is the paper's raw limit, the same for every particle.
    pub from_strain: bool,
}

/// Fracture criterion (docs/model.md section 2, Fracture).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractureParams {
    /// Critical measure `s_crit` for `sw = (e - ep) / delta` (dimensionless); infinity: no fracture.
    pub s_crit: f64,
    /// Damage scaling `alpha` of the threshold `s_crit (1 + alpha phi)` (dimensionless, >= 0).
    pub alpha: f64,
}

impl FractureParams {
    /// Checks `s_crit > 0` (infinity allowed) and a finite `alpha >= 0`; `index` names the
    /// material in the error.
    pub fn validate(&self, index: usize) -> Result<(), PhysicsError> {
        if self.s_crit.is_nan() || self.s_crit <= 0.0 {
            return Err(bad(
                index,
                format!(
                    "s_crit {} must be positive (infinity: no fracture)",
                    self.s_crit
                ),
            ));
        }
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return Err(bad(
                index,
                format!("alpha {} must be finite and >= 0", self.alpha),
            ));
        }
        Ok(())
    }
}

/// One material region of the Chen model.
#[derive(Debug, Clone, PartialEq)]
pub struct ChenMaterial {
    /// Bulk modulus `kappa` (Pa).
    pub bulk_modulus: f64,
    /// Shear modulus `mu` (Pa).
    pub shear_modulus: f64,
    /// Density `rho` (kg/m^3).
    pub density: f64,
    /// Yield limit; `None` is purely elastic (no plastic state is allocated).
    pub plasticity: Option<YieldParams>,
    /// Fracture threshold; `None` (or an infinite `s_crit`) never breaks (no damage state).
    pub fracture: Option<FractureParams>,
    /// Anisotropy matrix `G` of `omega = delta / |G xi|` (docs/model.md section 4); `None` is `I`.
    pub anisotropy: Option<Mat3>,
}

impl ChenMaterial {
    /// Elastic material from bulk modulus `kappa` (Pa), shear modulus `mu` (Pa), density (kg/m^3).
    pub fn elastic(bulk_modulus: f64, shear_modulus: f64, density: f64) -> Self {
        ChenMaterial {
            bulk_modulus,
            shear_modulus,
            density,
            plasticity: None,
            fracture: None,
            anisotropy: None,
        }
    }

    /// Elastic material from Young's modulus (Pa) and Poisson's ratio (in (-1, 0.5)).
    pub fn from_young_poisson(
        young: f64,
        poisson: f64,
        density: f64,
    ) -> Result<Self, PhysicsError> {
        check_young_poisson(young, poisson)?;
        let kappa = young / (3.0 * (1.0 - 2.0 * poisson));
        let mu = young / (2.0 * (1.0 + poisson));
        Ok(Self::elastic(kappa, mu, density))
    }

    /// Young's modulus (Pa) from `kappa` and `mu`.
    pub fn young(&self) -> f64 {
        let (k, m) = (self.bulk_modulus, self.shear_modulus);
        9.0 * k * m / (3.0 * k + m)
    }

    /// Poisson's ratio from `kappa` and `mu`.
    pub fn poisson(&self) -> f64 {
        let (k, m) = (self.bulk_modulus, self.shear_modulus);
        (3.0 * k - 2.0 * m) / (2.0 * (3.0 * k + m))
    }

    /// True when this material breaks bonds (a finite `s_crit`).
    pub fn fractures(&self) -> bool {
        self.fracture.is_some_and(|f| f.s_crit.is_finite())
    }

    /// Checks every parameter; `index` names the material in the error.
    pub fn validate(&self, index: usize) -> Result<(), PhysicsError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.bulk_modulus) {
            return Err(bad(
                index,
                format!("bulk modulus {} Pa must be positive", self.bulk_modulus),
            ));
        }
        if !pos(self.shear_modulus) {
            return Err(bad(
                index,
                format!("shear modulus {} Pa must be positive", self.shear_modulus),
            ));
        }
        if !pos(self.density) {
            return Err(bad(
                index,
                format!("density {} kg/m^3 must be positive", self.density),
            ));
        }
        if let Some(y) = self.plasticity {
            if !pos(y.psi0) {
                return Err(bad(
                    index,
                    format!("yield Psi0 {} must be positive", y.psi0),
                ));
            }
            if y.gamma_ratio.is_nan() || y.gamma_ratio <= 0.0 {
                return Err(bad(
                    index,
                    format!("plastic cap ratio {} must be positive", y.gamma_ratio),
                ));
            }
        }
        if let Some(f) = self.fracture {
            f.validate(index)?;
        }
        if let Some(g) = self.anisotropy {
            if !g.iter().flatten().all(|v| v.is_finite()) || det(&g).abs() < 1e-12 {
                return Err(bad(
                    index,
                    "anisotropy matrix G must be finite and invertible".into(),
                ));
            }
        }
        Ok(())
    }
}

fn det(m: &Mat3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// The error of material `material`.
pub(super) fn bad(material: usize, message: String) -> PhysicsError {
    PhysicsError::BadMaterial { material, message }
}

/// Young's modulus `young` (Pa) positive and finite, Poisson's ratio `poisson` in (-1, 0.5).
pub(super) fn check_young_poisson(young: f64, poisson: f64) -> Result<(), PhysicsError> {
    if !(poisson > -1.0 && poisson < 0.5) {
        return Err(bad(
            0,
            format!("Poisson's ratio {poisson} outside (-1, 0.5)"),
        ));
    }
    if !(young.is_finite() && young > 0.0) {
        return Err(bad(
            0,
            format!("Young's modulus {young} Pa must be positive"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_parameters_with_errors() {
        assert!(ChenMaterial::from_young_poisson(1e9, 0.5, 1000.0).is_err());
        assert!(ChenMaterial::from_young_poisson(1e9, -1.0, 1000.0).is_err());
        assert!(ChenMaterial::from_young_poisson(-1e9, 0.3, 1000.0).is_err());
        assert!(ChenMaterial::elastic(-1.0, 1.0, 1.0).validate(2).is_err());
        assert!(ChenMaterial::elastic(1.0, -1.0, 1.0).validate(0).is_err());
        assert!(ChenMaterial::elastic(1.0, 1.0, f64::NAN)
            .validate(0)
            .is_err());
        let m = ChenMaterial::from_young_poisson(2e9, 0.25, 1000.0).unwrap();
        assert!(m.validate(0).is_ok());
        // round trip E, nu -> kappa, mu -> E, nu is exact to a few ulps
        assert!((m.young() / 2e9 - 1.0).abs() < 1e-14);
        assert!((m.poisson() - 0.25).abs() < 1e-14);
    }
}
