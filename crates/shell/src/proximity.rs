//! Closest points between the primitives of self-contact: a point and a triangle, two
//! segments. Pure geometry, no forces.
//!
//! Each function returns the weights of the closest points as combinations of the
//! primitives' vertices. Since a distance is the minimum of `|sum w_i x_i|` over weights from a
//! fixed convex set, its gradient with respect to `x_i` is `w_i n` (`n` the unit vector between
//! the closest points) wherever the closest points are unique (Danskin's theorem): the weights
//! are all self-contact needs for exact forces.

use perifrac_physics::math::{axpy, dot, norm, scale, sub, Vec3};

/// Barycentric weights `[wa, wb, wc]` of the point of triangle `(a, b, c)` closest to `p`, by
/// the triangle's Voronoi regions (three corners, three edges, the interior).
pub fn point_triangle_weights(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f64; 3] {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let (pa_b, pa_c) = (dot(ab, ap), dot(ac, ap));
    if pa_b <= 0.0 && pa_c <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = sub(p, b);
    let (pb_b, pb_c) = (dot(ab, bp), dot(ac, bp));
    if pb_b >= 0.0 && pb_c <= pb_b {
        return [0.0, 1.0, 0.0];
    }
    let cp = sub(p, c);
    let (pc_b, pc_c) = (dot(ab, cp), dot(ac, cp));
    if pc_c >= 0.0 && pc_b <= pc_c {
        return [0.0, 0.0, 1.0];
    }
    // Signed areas (times the triangle's) of the sub-triangles opposite each corner, seen
    // through the projections above.
    let area_c = pa_b * pb_c - pb_b * pa_c;
    if area_c <= 0.0 && pa_b >= 0.0 && pb_b <= 0.0 {
        let t = pa_b / (pa_b - pb_b);
        return [1.0 - t, t, 0.0];
    }
    let area_b = pc_b * pa_c - pa_b * pc_c;
    if area_b <= 0.0 && pa_c >= 0.0 && pc_c <= 0.0 {
        let t = pa_c / (pa_c - pc_c);
        return [1.0 - t, 0.0, t];
    }
    let area_a = pb_b * pc_c - pc_b * pb_c;
    let (on_b, on_c) = (pb_c - pb_b, pc_b - pc_c);
    if area_a <= 0.0 && on_b >= 0.0 && on_c >= 0.0 {
        let t = on_b / (on_b + on_c);
        return [0.0, 1.0 - t, t];
    }
    let total = area_a + area_b + area_c;
    let (wb, wc) = (area_b / total, area_c / total);
    [1.0 - wb - wc, wb, wc]
}

/// Parameters `(s, t)` in `[0, 1]` of the closest points `p0 + s (p1 - p0)` and
/// `q0 + t (q1 - q0)` of two segments. Parallel segments (sine of their angle below 1e-6)
/// take `s = 0` and the `t` nearest it, one of their closest pairs.
pub fn segment_segment_params(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3) -> (f64, f64) {
    let dp = sub(p1, p0);
    let dq = sub(q1, q0);
    let r = sub(p0, q0);
    let (pp, qq, pq) = (dot(dp, dp), dot(dq, dq), dot(dp, dq));
    let (pr, qr) = (dot(dp, r), dot(dq, r));
    if pp <= 0.0 || qq <= 0.0 {
        // A segment of no length (never in a checked mesh): its first end.
        let t = if qq > 0.0 {
            (qr / qq).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let s = if pp > 0.0 {
            (-pr / pp).clamp(0.0, 1.0)
        } else {
            0.0
        };
        return (s, t);
    }
    let det = pp * qq - pq * pq;
    let mut s = if det > 1e-12 * pp * qq {
        ((pq * qr - pr * qq) / det).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (pq * s + qr) / qq;
    if t < 0.0 {
        t = 0.0;
        s = (-pr / pp).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((pq - pr) / pp).clamp(0.0, 1.0);
    }
    (s, t)
}

/// The point `a + t (b - a)`.
#[inline]
pub fn lerp(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    axpy(a, t, sub(b, a))
}

/// The point `w[0] a + w[1] b + w[2] c`.
#[inline]
pub fn combine3(w: [f64; 3], a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    axpy(axpy(scale(a, w[0]), w[1], b), w[2], c)
}

/// Distance (m) from `p` to triangle `t`.
pub fn point_triangle_distance(p: Vec3, t: [Vec3; 3]) -> f64 {
    let w = point_triangle_weights(p, t[0], t[1], t[2]);
    norm(sub(p, combine3(w, t[0], t[1], t[2])))
}

/// Distance (m) between segments `p` and `q`.
pub fn segment_distance(p: [Vec3; 2], q: [Vec3; 2]) -> f64 {
    let (s, t) = segment_segment_params(p[0], p[1], q[0], q[1]);
    norm(sub(lerp(p[0], p[1], s), lerp(q[0], q[1], t)))
}
