//! Per-pair contact force: closed forms, no parry calls (parry's point projection costs ~20x
//! these per point). The geometry comes from the parry shapes' parameters.

use crate::math::{dot, norm, scale, sub};
use crate::params::ContactParams;
use crate::Vec3;

/// Normal used when a particle centre coincides with a ball centre (no direction is defined).
pub(crate) const COINCIDENT_NORMAL: Vec3 = [0.0, 0.0, 1.0];

/// Contact coefficients prepared for the loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Coeffs {
    /// Stiffness (N/m).
    pub k: f64,
    /// `2 zeta sqrt(k)`: the damping coefficient is `damp sqrt(m)` (N s/m).
    pub damp: f64,
    /// Coulomb coefficient.
    pub mu: f64,
}

impl Coeffs {
    pub(crate) fn new(p: &ContactParams) -> Self {
        Self {
            k: p.stiffness,
            damp: 2.0 * p.damping_ratio * p.stiffness.sqrt(),
            mu: p.friction,
        }
    }

    /// The coefficients for a particle whose stiffness is `s` times the collider's (see
    /// [`crate::Colliders::set_stiffness_scale`]): the same damping ratio and friction.
    #[inline]
    pub(crate) fn scaled(&self, s: f64) -> Self {
        if s == 1.0 {
            return *self;
        }
        Self {
            k: self.k * s,
            damp: self.damp * s.sqrt(),
            mu: self.mu,
        }
    }
}

/// The stiffness scale of particle `i`: 1 when no scale is set.
#[inline]
pub(crate) fn scale_of(scale: &[f64], i: usize) -> f64 {
    scale.get(i).copied().unwrap_or(1.0)
}

/// Force (N) on a body of mass `m` (kg) that penetrates a surface by `d` > 0 (m) along the unit
/// normal `n` (pointing from the surface into the body), moving at `v_rel` (m/s, body minus
/// surface), over a step of `1 / inv_dt` seconds.
///
/// Normal: `max(0, k d - c v_rel.n)`, `c = 2 zeta sqrt(k m)`, never attractive. Friction:
/// `min(mu f_n, m |v_t| / dt)` against the tangential velocity `v_t`: the cap lets friction stop
/// the sliding within one step but never reverse it.
#[inline]
pub(crate) fn penalty_force(d: f64, n: Vec3, v_rel: Vec3, m: f64, inv_dt: f64, c: &Coeffs) -> Vec3 {
    let vn = dot(v_rel, n);
    let fn_ = (c.k * d - c.damp * m.sqrt() * vn).max(0.0);
    let mut f = scale(n, fn_);
    if c.mu > 0.0 && fn_ > 0.0 {
        let vt = sub(v_rel, scale(n, vn));
        let vt_len = norm(vt);
        if vt_len > 0.0 {
            let ft = (c.mu * fn_).min(m * vt_len * inv_dt);
            let s = ft / vt_len;
            f[0] -= s * vt[0];
            f[1] -= s * vt[1];
            f[2] -= s * vt[2];
        }
    }
    f
}

/// Unit normal from a ball centre towards a point at offset `dx` with `d2 = |dx|^2`, and the
/// distance. At (or numerically at) the centre the direction is undefined: returns
/// [`COINCIDENT_NORMAL`] and distance 0, deterministically.
#[inline]
pub(crate) fn ball_normal(dx: Vec3, d2: f64) -> (Vec3, f64) {
    if d2 > f64::MIN_POSITIVE {
        let dist = d2.sqrt();
        (scale(dx, 1.0 / dist), dist)
    } else {
        (COINCIDENT_NORMAL, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const C: Coeffs = Coeffs {
        k: 100.0,
        damp: 0.0,
        mu: 0.5,
    };

    #[test]
    fn normal_force_is_k_d() {
        let f = penalty_force(0.01, [0.0, 0.0, 1.0], [0.0; 3], 1.0, 1e3, &C);
        assert_eq!(f, [0.0, 0.0, 1.0]);
    }

    #[test]
    fn damping_never_attracts() {
        let c = Coeffs {
            damp: 2.0 * 10.0,
            ..C
        };
        // Separating fast: k d - c v_n < 0, so no force at all (and no friction).
        let f = penalty_force(0.01, [0.0, 0.0, 1.0], [3.0, 0.0, 5.0], 1.0, 1e3, &c);
        assert_eq!(f, [0.0; 3]);
    }

    #[test]
    fn friction_is_coulomb_then_capped() {
        // Fast sliding: mu f_n = 0.5 N against +x.
        let f = penalty_force(0.01, [0.0, 0.0, 1.0], [2.0, 0.0, 0.0], 1.0, 1e3, &C);
        assert_eq!(f, [-0.5, 0.0, 1.0]);
        // Slow sliding: m |v_t| / dt = 1e-4 * 1e3 = 0.1 N < 0.5 N.
        let f = penalty_force(0.01, [0.0, 0.0, 1.0], [0.0, -1e-4, 0.0], 1.0, 1e3, &C);
        assert!((f[1] - 0.1).abs() < 1e-15, "{f:?}");
    }

    #[test]
    fn coincident_centre_gets_fixed_normal() {
        assert_eq!(ball_normal([0.0; 3], 0.0), (COINCIDENT_NORMAL, 0.0));
        let tiny = [1e-160, 0.0, 0.0];
        assert_eq!(ball_normal(tiny, dot(tiny, tiny)).0, COINCIDENT_NORMAL);
        let (n, d) = ball_normal([3.0, 0.0, 4.0], 25.0);
        assert_eq!(d, 5.0);
        assert!((n[0] - 0.6).abs() < 1e-15 && n[1] == 0.0 && (n[2] - 0.8).abs() < 1e-15);
        // Just above the guard the direction is still a unit vector.
        let small = [1e-150, 0.0, 0.0];
        assert_eq!(ball_normal(small, dot(small, small)).0, [1.0, 0.0, 0.0]);
    }
}
