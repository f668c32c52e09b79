//! Small geometric helpers of the setup (vector algebra is `perifrac_physics::math`).

use perifrac_physics::math::norm;

/// Axis-aligned bounds of `points` (infinite, inverted bounds when empty).
pub(crate) fn bounds(points: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    perifrac_topology::point_bounds(points.iter().copied())
}

/// World up: opposite gravity, +z without gravity.
pub(crate) fn up_from_gravity(gravity: [f64; 3]) -> [f64; 3] {
    let g = norm(gravity);
    if g > 0.0 {
        gravity.map(|c| -c / g)
    } else {
        [0.0, 0.0, 1.0]
    }
}
