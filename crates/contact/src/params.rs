//! Penalty contact coefficients.

use crate::error::ContactError;

/// Penalty contact coefficients for one collider, applied to each particle that touches it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Normal penalty stiffness per particle (N/m): force `k d` at penetration depth `d`.
    pub stiffness: f64,
    /// Normal damping as a fraction of critical damping of the particle on the penalty spring
    /// (dimensionless, >= 0): `c = 2 damping_ratio sqrt(k m)`. 0 gives an elastic bounce.
    pub damping_ratio: f64,
    /// Coulomb friction coefficient `mu` (dimensionless, >= 0).
    pub friction: f64,
}

impl ContactParams {
    /// Default `factor` for [`ContactParams::from_material`] (dimensionless).
    pub const DEFAULT_STIFFNESS_FACTOR: f64 = 1.0;

    /// Coefficients with the stiffness derived from the material: `k = factor E r_p` (N/m), with
    /// `young` = `E` (Pa) and `contact_radius` = `r_p` (m).
    ///
    /// Reasoning: a particle of radius `r_p` stands for a lump of material about `2 r_p` across.
    /// Pressing it a depth `d` into a rigid half-space compresses a column of cross-section
    /// `~r_p^2` and length `~r_p`, so `F ~ E r_p^2 d / r_p = E r_p d`. Hertz's law for a sphere
    /// on a half-space, `F = 4/3 E* sqrt(r_p) d^(3/2)`, linearised at `d = r_p / 10`, gives
    /// `0.42 E r_p`: the same scale. `factor` = 1 ([`Self::DEFAULT_STIFFNESS_FACTOR`]) is the
    /// default; a larger factor lowers penetration but shortens the stable step.
    ///
    /// Effect on the stable time step: a particle of mass `m = rho V` on the penalty spring
    /// oscillates at `omega = sqrt(k / m)`, and explicit velocity Verlet needs
    /// `dt < 2 / omega` ([`Self::critical_time_step`]). With `r_p` the equivalent-sphere radius
    /// (`V = 4/3 pi r_p^3`) this is `dt < 2 r_p sqrt(4.19 / factor) / c`, `c = sqrt(E / rho)`,
    /// about `4.1 r_p / c` for `factor` = 1: above the bond network's own limit (of order
    /// `dx / c` with the spacing `dx ~ 2 r_p`), so default contact does not shorten the step.
    /// Keep `factor` below about 4 for that to hold.
    pub fn from_material(
        young: f64,
        contact_radius: f64,
        factor: f64,
        damping_ratio: f64,
        friction: f64,
    ) -> Self {
        Self {
            stiffness: factor * young * contact_radius,
            damping_ratio,
            friction,
        }
    }

    /// Largest stable explicit step (s) for a particle of `mass` (kg) on this penalty spring
    /// with its damping: `2 / omega (sqrt(1 + zeta^2) - zeta)`, `omega = sqrt(k / m)`.
    /// Infinite when the stiffness is zero.
    pub fn critical_time_step(&self, mass: f64) -> f64 {
        if self.stiffness <= 0.0 {
            return f64::INFINITY;
        }
        let omega = (self.stiffness / mass).sqrt();
        let zeta = self.damping_ratio;
        2.0 / omega * ((1.0 + zeta * zeta).sqrt() - zeta)
    }

    /// Checks every coefficient is finite and >= 0; `collider` names the owner in the error.
    pub(crate) fn validate(&self, collider: &str) -> Result<(), ContactError> {
        for (what, value) in [
            ("stiffness", self.stiffness),
            ("damping_ratio", self.damping_ratio),
            ("friction", self.friction),
        ] {
            if !value.is_finite() {
                return Err(ContactError::NonFinite {
                    collider: collider.to_owned(),
                    what,
                    value,
                });
            }
            if value < 0.0 {
                return Err(ContactError::Negative {
                    collider: collider.to_owned(),
                    what,
                    value,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_material_is_factor_e_r() {
        let p = ContactParams::from_material(70e9, 1e-3, 2.0, 0.1, 0.5);
        assert_eq!(p.stiffness, 2.0 * 70e9 * 1e-3);
        assert_eq!((p.damping_ratio, p.friction), (0.1, 0.5));
    }

    #[test]
    fn critical_step_undamped_is_two_over_omega() {
        let p = ContactParams {
            stiffness: 4.0,
            damping_ratio: 0.0,
            friction: 0.0,
        };
        // omega = sqrt(4 / 1) = 2, so 2 / omega = 1.
        assert_eq!(p.critical_time_step(1.0), 1.0);
        let damped = ContactParams {
            damping_ratio: 0.5,
            ..p
        };
        assert!(damped.critical_time_step(1.0) < 1.0);
    }

    #[test]
    fn validate_rejects_negative_and_nan() {
        let mut p = ContactParams::from_material(1.0, 1.0, 1.0, 0.0, 0.0);
        assert!(p.validate("ground 0").is_ok());
        p.friction = -0.1;
        let e = p.validate("ground 0").unwrap_err();
        assert!(
            e.to_string().contains("ground 0: friction must be >= 0"),
            "{e}"
        );
        p.friction = f64::NAN;
        assert!(matches!(
            p.validate("ball 2"),
            Err(ContactError::NonFinite {
                what: "friction",
                ..
            })
        ));
    }
}
