//! Xu's one-dimensional basis functions and the energy curves built from them (docs/model.md
//! section 5): `A_n`, `B_n` of a stretch `s > 0` with their first and second derivatives, and
//! [`Curve`], a combination of them that is zero with zero slope at `s = 1`.

use crate::error::PhysicsError;

/// Largest basis order accepted in a custom curve (higher powers overflow for modest stretch).
pub const MAX_ORDER: u8 = 12;

/// One basis function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    /// `A_n`: infinite as `s -> 0` (resists compression), `n >= 1`.
    A(u8),
    /// `B_n`: finite at `s = 0`, `n >= 1`.
    B(u8),
}

impl Basis {
    /// `(f(s), f'(s), f''(s))` (dimensionless) at stretch `s > 0`.
    pub fn eval(self, s: f64) -> (f64, f64, f64) {
        match self {
            Basis::A(1) => (
                0.5 * (s * s - 1.0) - s.ln(),
                s - 1.0 / s,
                1.0 + 1.0 / (s * s),
            ),
            Basis::A(n) => {
                let nf = n as f64;
                let sn = s.powi(n as i32);
                let inv = 1.0 / sn;
                let value = ((sn * s - 1.0) / (nf + 1.0) + (s * inv - 1.0) / (nf - 1.0)) / nf;
                (value, (sn - inv) / nf, sn / s + inv / s)
            }
            Basis::B(n) => {
                let nf = n as f64;
                let sn = s.powi(n as i32);
                let value = 2.0 / nf * ((sn * s - 1.0) / (nf + 1.0) - s + 1.0);
                (value, 2.0 * (sn - 1.0) / nf, 2.0 * sn / s)
            }
        }
    }

    /// Parses `"A1"` .. `"A12"`, `"B1"` .. `"B12"`.
    pub fn parse(name: &str) -> Option<Basis> {
        let (kind, order) = name.split_at_checked(1)?;
        let n: u8 = order.parse().ok()?;
        if n == 0 || n > MAX_ORDER {
            return None;
        }
        match kind {
            "A" => Some(Basis::A(n)),
            "B" => Some(Basis::B(n)),
            _ => None,
        }
    }
}

/// An energy curve `f(s) = sum_k c_k basis_k(s)`, with closed forms for the named ones.
#[derive(Debug, Clone, PartialEq)]
pub enum Curve {
    /// `B_1 = (s - 1)^2`: the linear peridynamic solid.
    Linear,
    /// `A_1 = (s^2 - 1) / 2 - ln s`: neo-Hookean-like, infinite energy at `s -> 0`.
    NeoHookean,
    /// `(3 B_3 - B_1) / 2 = ((s^2 - 1) / 2)^2`: St Venant-Kirchhoff-like; it softens under
    /// compression (`f'' < 0` below `s = 1 / sqrt 3`) and has zero slope at `s = 0`.
    Stvk,
    /// A custom combination `(basis, coefficient)`.
    Custom(Vec<(Basis, f64)>),
}

impl Curve {
    /// `(f(s), f'(s), f''(s))` at stretch `s > 0`.
    #[inline]
    pub fn eval(&self, s: f64) -> (f64, f64, f64) {
        match self {
            Curve::Linear => {
                let d = s - 1.0;
                (d * d, 2.0 * d, 2.0)
            }
            Curve::NeoHookean => Basis::A(1).eval(s),
            Curve::Stvk => {
                let e = 0.5 * (s * s - 1.0);
                (e * e, 2.0 * e * s, 3.0 * s * s - 1.0)
            }
            Curve::Custom(terms) => terms.iter().fold((0.0, 0.0, 0.0), |acc, &(b, c)| {
                let (f, d1, d2) = b.eval(s);
                (acc.0 + c * f, acc.1 + c * d1, acc.2 + c * d2)
            }),
        }
    }

    /// First derivative `f'(s)`.
    #[inline]
    pub fn slope(&self, s: f64) -> f64 {
        match self {
            Curve::Linear => 2.0 * (s - 1.0),
            Curve::NeoHookean => s - 1.0 / s,
            Curve::Stvk => (s * s - 1.0) * s,
            Curve::Custom(_) => self.eval(s).1,
        }
    }

    /// Curvature at rest `f''(1)`: 2 for the three named curves.
    pub fn rest_curvature(&self) -> f64 {
        self.eval(1.0).2
    }

    /// Checks the curve: finite coefficients, and a positive curvature at rest (an energy that
    /// is not convex at rest has no stable rest shape). `what` names it in the message.
    pub fn validate(&self, what: &str) -> Result<(), PhysicsError> {
        if let Curve::Custom(terms) = self {
            if terms.is_empty() {
                return Err(PhysicsError::BadSetting(format!(
                    "{what}: a custom energy needs at least one basis term"
                )));
            }
            if let Some((b, c)) = terms.iter().find(|(_, c)| !c.is_finite()) {
                return Err(PhysicsError::BadSetting(format!(
                    "{what}: coefficient {c} of {b:?} must be finite"
                )));
            }
        }
        let k = self.rest_curvature();
        if !(k.is_finite() && k > 0.0) {
            return Err(PhysicsError::BadSetting(format!(
                "{what}: the energy is not convex at rest (f''(1) = {k}, must be > 0)"
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every basis is zero with zero slope at rest, and its derivatives match central finite
    /// differences of the value (h = 1e-5: truncation ~ h^2 f''' ~ 1e-9 for s in [0.3, 3] and
    /// n <= 6; rounding ~ 1e-16 |f| / h ~ 1e-10).
    #[test]
    fn basis_values_and_derivatives() {
        let mut all: Vec<Basis> = (1..=6).map(Basis::A).collect();
        all.extend((1..=6).map(Basis::B));
        for b in all {
            let (f, d1, d2) = b.eval(1.0);
            assert!(f.abs() < 1e-15 && d1.abs() < 1e-15, "{b:?}: {f} {d1}");
            assert!(d2 > 0.0);
            for &s in &[0.3, 0.7, 1.0, 1.4, 3.0] {
                let h = 1e-5;
                let (_, d1, d2) = b.eval(s);
                let fd1 = (b.eval(s + h).0 - b.eval(s - h).0) / (2.0 * h);
                let fd2 = (b.eval(s + h).1 - b.eval(s - h).1) / (2.0 * h);
                let scale = 1.0 + d1.abs() + d2.abs();
                assert!((fd1 - d1).abs() < 1e-7 * scale, "{b:?} s={s}: {fd1} {d1}");
                assert!((fd2 - d2).abs() < 1e-7 * scale, "{b:?} s={s}: {fd2} {d2}");
            }
        }
    }

    /// The closed forms equal their basis combinations (docs/model.md section 5).
    #[test]
    fn named_curves_are_their_basis_combinations() {
        let linear = Curve::Custom(vec![(Basis::B(1), 1.0)]);
        let neo = Curve::Custom(vec![(Basis::A(1), 1.0)]);
        let stvk = Curve::Custom(vec![(Basis::B(3), 1.5), (Basis::B(1), -0.5)]);
        for &s in &[0.2, 0.6, 1.0, 1.3, 2.5] {
            for (named, custom) in [
                (Curve::Linear, &linear),
                (Curve::NeoHookean, &neo),
                (Curve::Stvk, &stvk),
            ] {
                let (a, b) = (named.eval(s), custom.eval(s));
                // a few ulps of values up to ~10
                assert!((a.0 - b.0).abs() < 1e-13, "{named:?} {s}");
                assert!((a.1 - b.1).abs() < 1e-13, "{named:?} {s}");
                assert!((a.2 - b.2).abs() < 1e-13, "{named:?} {s}");
                assert_eq!(named.slope(s), named.eval(s).1);
            }
        }
        for c in [Curve::Linear, Curve::NeoHookean, Curve::Stvk] {
            assert_eq!(c.rest_curvature(), 2.0);
        }
        // StVK softens under strong compression; neo-Hookean does not
        assert!(Curve::Stvk.eval(0.5).2 < 0.0);
        assert!(Curve::NeoHookean.eval(0.5).2 > 0.0);
    }

    #[test]
    fn parsing_and_validation() {
        assert_eq!(Basis::parse("A3"), Some(Basis::A(3)));
        assert_eq!(Basis::parse("B12"), Some(Basis::B(12)));
        for bad in ["A0", "C1", "B13", "", "A", "Ax"] {
            assert_eq!(Basis::parse(bad), None, "{bad}");
        }
        assert!(Curve::Linear.validate("g").is_ok());
        let concave = Curve::Custom(vec![(Basis::B(1), -1.0)]);
        assert!(concave.validate("h").is_err());
        assert!(Curve::Custom(vec![]).validate("h").is_err());
        assert!(Curve::Custom(vec![(Basis::A(2), f64::NAN)])
            .validate("g")
            .is_err());
    }
}
