//! The shell's material: Young's modulus, Poisson's ratio, density and rest thickness.

use crate::error::ShellError;

/// An isotropic elastic shell material of uniform thickness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellMaterial {
    /// Young's modulus (Pa).
    pub young: f64,
    /// Poisson's ratio (dimensionless, in (-1, 0.5]).
    pub poisson: f64,
    /// Density (kg/m^3).
    pub density: f64,
    /// Rest thickness `h` (m).
    pub thickness: f64,
}

impl ShellMaterial {
    /// Checks every constant: modulus, density and thickness finite and > 0, Poisson's ratio
    /// in (-1, 0.5].
    pub fn new(
        young: f64,
        poisson: f64,
        density: f64,
        thickness: f64,
    ) -> Result<ShellMaterial, ShellError> {
        for (what, value) in [
            ("shell Young's modulus (Pa)", young),
            ("shell density (kg/m^3)", density),
            ("shell thickness (m)", thickness),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ShellError::BadSetting {
                    what,
                    expected: "finite and > 0",
                    value,
                });
            }
        }
        if !(poisson > -1.0 && poisson <= 0.5) {
            return Err(ShellError::BadSetting {
                what: "shell Poisson's ratio",
                expected: "in (-1, 0.5]",
                value: poisson,
            });
        }
        Ok(ShellMaterial {
            young,
            poisson,
            density,
            thickness,
        })
    }

    /// `Y h / (2 (1 - nu^2))` (N/m): the factor of the membrane energy density.
    pub fn membrane_factor(&self) -> f64 {
        self.young * self.thickness / (2.0 * (1.0 - self.poisson * self.poisson))
    }

    /// `Y h^3 / (24 (1 - nu^2))` (N m): the factor of Koiter's bending energy density, half the
    /// plate's flexural rigidity `D`.
    pub fn bending_factor(&self) -> f64 {
        self.young * self.thickness.powi(3) / (24.0 * (1.0 - self.poisson * self.poisson))
    }

    /// Mass per unit area `rho h` (kg/m^2).
    pub fn areal_density(&self) -> f64 {
        self.density * self.thickness
    }
}
