//! Per-pair terms of the incremental contact potential (closed forms, value and gradient from
//! one case split): the elastic penalty on the trial penetration, and the dissipative damping
//! and smoothed Coulomb friction potentials of a pair lagged at the start of the step.

use crate::math::{dot, norm, scale, sub};
use crate::Vec3;

/// What a pair in contact at the start of the step keeps for the whole step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lagged {
    /// Unit normal at the start, pointing from the collider into the body (particle or ball).
    pub n0: Vec3,
    /// Damping coefficient over the step length, `c_d / dt` (N/m), `c_d = 2 zeta sqrt(k m)`.
    pub damp_dt: f64,
    /// Coulomb bound `mu lambda` (N), `lambda = k d0` the normal force at the start.
    pub friction: f64,
    /// Slip displacement (m, > 0) below which friction is smoothed (static regime).
    pub eps: f64,
}

/// Elastic penalty `k d^2 / 2` (J) at penetration `d` (m, > 0) and `dE/dd = k d` (N).
#[inline]
pub(crate) fn elastic(k: f64, d: f64) -> (f64, f64) {
    (0.5 * k * d * d, k * d)
}

/// Smoothed friction magnitude `f0(x)` (m) and `f0'(x) / x` expressed as `(f0, f0' / x * eps)`.
///
/// `f0(x) = x` for `x >= eps`; below, the C1 blend `x^2 / eps - x^3 / (3 eps^2) + eps / 3`
/// (value `eps` and slope 1 at `eps`, slope 0 at 0). Written with `s = x / eps` so that no
/// `1 / eps^2` appears: the second value, `(2 - s)` below `eps` and `1 / s` above, is in `[1, 2]`
/// below and finite above (x >= eps > 0).
#[inline]
pub(crate) fn friction_blend(x: f64, eps: f64) -> (f64, f64) {
    if x >= eps {
        (x, eps / x)
    } else {
        let s = x / eps;
        (eps * (s * s - s * s * s / 3.0 + 1.0 / 3.0), 2.0 - s)
    }
}

/// Dissipative potential (J) of a lagged pair at relative displacement `u` (m) over the step
/// (body minus collider, end minus start), and its gradient with respect to `u` (N).
///
/// Damping: `(c_d / (2 dt)) min(0, n0 . u)^2`, zero for separating motion, so it never pulls.
/// Friction: `mu lambda f0(|u_t|)`, `u_t = u - (n0 . u) n0`; its gradient is tangential,
/// `mu lambda f0'(|u_t|) u_t / |u_t|`, along the slip, of length at most `mu lambda`, and 0 at
/// `u_t = 0` (no NaN: `u_t / eps` is formed before any product).
#[inline]
pub(crate) fn dissipation(l: &Lagged, u: Vec3) -> (f64, Vec3) {
    let un = dot(u, l.n0);
    let mut e = 0.0;
    let mut g = [0.0; 3];
    if un < 0.0 && l.damp_dt > 0.0 {
        e += 0.5 * l.damp_dt * un * un;
        g = scale(l.n0, l.damp_dt * un);
    }
    if l.friction > 0.0 {
        let ut = sub(u, scale(l.n0, un));
        let (f0, slope) = friction_blend(norm(ut), l.eps);
        e += l.friction * f0;
        let s = l.friction * slope;
        for a in 0..3 {
            g[a] += s * (ut[a] / l.eps);
        }
    }
    (e, g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blend_is_c1_at_eps_and_flat_at_zero() {
        let eps = 1e-5;
        let (v, s) = friction_blend(eps, eps);
        assert_eq!((v, s), (eps, 1.0));
        // Just below eps: f0 = eps (1 - d + d^3 / 3) and f0' = (2 - s) s = 1 - d^2 (s = 1 - d),
        // matching the linear branch to O(d^2).
        let d = 1e-6;
        let (v, s) = friction_blend(eps * (1.0 - d), eps);
        assert!((v - eps * (1.0 - d)).abs() < 1e-15 * eps, "{v}");
        assert!((s * (1.0 - d) - 1.0).abs() < 2.0 * d * d, "{s}");
        let (v, s) = friction_blend(0.0, eps);
        assert!((v - eps / 3.0).abs() < 1e-15 * eps && s == 2.0, "{v} {s}");
    }

    #[test]
    fn friction_gradient_is_bounded_and_tangential() {
        let l = Lagged {
            n0: [0.0, 0.0, 1.0],
            damp_dt: 0.0,
            friction: 2.0,
            eps: 1e-4,
        };
        for u in [[1.0, 0.0, 5.0], [3e-5, -2e-5, -1.0], [0.0, 0.0, 0.3]] {
            let (_, g) = dissipation(&l, u);
            assert_eq!(g[2], 0.0);
            assert!(norm(g) <= 2.0 * (1.0 + 1e-15), "{g:?}");
            assert!(g[0] * u[0] + g[1] * u[1] >= 0.0);
        }
        assert_eq!(dissipation(&l, [0.0; 3]).1, [0.0; 3]);
    }

    #[test]
    fn damping_only_resists_approach() {
        let l = Lagged {
            n0: [0.0, 1.0, 0.0],
            damp_dt: 10.0,
            friction: 0.0,
            eps: 1.0,
        };
        assert_eq!(dissipation(&l, [0.0, 0.5, 0.0]), (0.0, [0.0; 3]));
        assert_eq!(dissipation(&l, [0.0, -0.5, 0.0]), (1.25, [0.0, -5.0, 0.0]));
    }
}
