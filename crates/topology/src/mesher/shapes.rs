//! Closed triangle surfaces of primitives (box, sphere, cylinder), outward-oriented, for
//! meshing through the same path as surface files and for tests.

use std::f64::consts::PI;

/// The surface of the axis-aligned box from `min` to `max` (m): 8 corners, 12 triangles.
pub fn cube_surface(min: [f64; 3], max: [f64; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    // Corner i has x from bit 0, y from bit 1, z from bit 2.
    let v = (0..8)
        .map(|i: usize| std::array::from_fn(|k| if (i >> k) & 1 == 1 { max[k] } else { min[k] }))
        .collect();
    let f = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    (v, f)
}

/// A UV sphere of `radius` about the origin: `segments` rings from pole to pole and twice as
/// many around (at least 3 and 6).
pub fn sphere_surface(radius: f64, segments: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let rings = segments.max(3);
    let around = 2 * rings;
    let mut v = vec![[0.0, 0.0, -radius]];
    for r in 1..rings {
        let theta = PI * r as f64 / rings as f64;
        let (z, rho) = (-radius * theta.cos(), radius * theta.sin());
        for a in 0..around {
            let phi = 2.0 * PI * a as f64 / around as f64;
            v.push([rho * phi.cos(), rho * phi.sin(), z]);
        }
    }
    v.push([0.0, 0.0, radius]);
    let top = (v.len() - 1) as u32;
    let ring = |r: usize, a: usize| (1 + (r - 1) * around + a % around) as u32;
    let mut f = Vec::new();
    for a in 0..around {
        f.push([0, ring(1, a + 1), ring(1, a)]);
        f.push([top, ring(rings - 1, a), ring(rings - 1, a + 1)]);
    }
    for r in 1..rings - 1 {
        for a in 0..around {
            let (p, q, s, t) = (
                ring(r, a),
                ring(r, a + 1),
                ring(r + 1, a),
                ring(r + 1, a + 1),
            );
            f.push([p, q, t]);
            f.push([p, t, s]);
        }
    }
    (v, f)
}

/// A closed cylinder of `radius` and `height` along z from the origin, `segments` around (at
/// least 3), with fan-triangulated caps.
pub fn cylinder_surface(
    radius: f64,
    height: f64,
    segments: usize,
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let n = segments.max(3);
    let mut v = vec![[0.0, 0.0, 0.0], [0.0, 0.0, height]];
    for z in [0.0, height] {
        for a in 0..n {
            let phi = 2.0 * PI * a as f64 / n as f64;
            v.push([radius * phi.cos(), radius * phi.sin(), z]);
        }
    }
    let bottom = |a: usize| (2 + a % n) as u32;
    let top = |a: usize| (2 + n + a % n) as u32;
    let mut f = Vec::new();
    for a in 0..n {
        f.push([0, bottom(a + 1), bottom(a)]);
        f.push([1, top(a), top(a + 1)]);
        f.push([bottom(a), bottom(a + 1), top(a + 1)]);
        f.push([bottom(a), top(a + 1), top(a)]);
    }
    (v, f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesher::{check_surface, enclosed_volume};

    #[test]
    fn shapes_are_closed_and_outward() {
        let (v, f) = sphere_surface(2.0, 24);
        assert!(check_surface(&v, &f).problems.is_watertight());
        // The inscribed polyhedron falls short of 4/3 pi r^3 by O(1/segments^2): 2% at 24.
        let exact = 4.0 / 3.0 * PI * 8.0;
        let vol = enclosed_volume(&v, &f);
        assert!(vol > 0.97 * exact && vol < exact, "{vol} vs {exact}");
        let (v, f) = cylinder_surface(1.0, 3.0, 32);
        assert!(check_surface(&v, &f).problems.is_watertight());
        // A 32-gon prism: (n/2) sin(2 pi / n) r^2 h, exactly.
        let exact = 16.0 * (2.0 * PI / 32.0).sin() * 3.0;
        assert!((enclosed_volume(&v, &f) - exact).abs() < 1e-12);
    }
}
