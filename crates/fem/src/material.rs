//! Isotropic linear elastic material.

use crate::error::FemError;

/// Isotropic elastic material, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus (Pa), positive.
    pub young: f64,
    /// Poisson's ratio (dimensionless), in (-1, 0.5).
    pub poisson: f64,
    /// Mass density (kg/m^3), positive.
    pub density: f64,
}

impl Material {
    /// A validated material: `young` (Pa) > 0, -1 < `poisson` < 0.5, `density` (kg/m^3) > 0.
    pub fn new(young: f64, poisson: f64, density: f64) -> Result<Self, FemError> {
        let m = Self {
            young,
            poisson,
            density,
        };
        m.validate()?;
        Ok(m)
    }

    /// Checks the ranges [`Material::new`] checks (for a struct built by hand).
    pub fn validate(&self) -> Result<(), FemError> {
        let bad = |name, value, range| Err(FemError::BadMaterial { name, value, range });
        if !(self.young.is_finite() && self.young > 0.0) {
            return bad("young", self.young, "positive and finite, Pa");
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return bad("poisson", self.poisson, "-1 < nu < 0.5");
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad("density", self.density, "positive and finite, kg/m^3");
        }
        Ok(())
    }

    /// Lamé's first parameter lambda (Pa).
    pub fn lambda(&self) -> f64 {
        let (e, nu) = (self.young, self.poisson);
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    }

    /// Shear modulus mu (Pa).
    pub fn mu(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// P-wave (dilatational) speed sqrt((lambda + 2 mu) / rho) (m/s).
    pub fn p_wave_speed(&self) -> f64 {
        ((self.lambda() + 2.0 * self.mu()) / self.density).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lame_parameters_and_validation() {
        let m = Material::new(1e8, 0.3, 1000.0).unwrap();
        assert!((m.mu() - 1e8 / 2.6).abs() < 1e-6);
        assert!((m.lambda() - 1e8 * 0.3 / (1.3 * 0.4)).abs() < 1e-6);
        assert!(Material::new(1e8, 0.5, 1000.0).is_err());
        assert!(Material::new(-1.0, 0.3, 1000.0).is_err());
        assert!(Material::new(1.0, 0.3, f64::NAN).is_err());
    }
}
