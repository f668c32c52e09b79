//! Scalar and vector types used throughout the crate, with small inline helpers.
//!
//! Vectors are plain `[f64; 3]`: the force loop gathers per particle over CSR bonds (no scattered
//! writes), where aligned SIMD types showed no gain, and plain arrays cross crate boundaries
//! (topology, io) without conversion.

/// Floating-point type of all physical quantities (SI units).
pub type Real = f64;

/// A 3-vector (position in m, velocity in m/s, force in N, ...).
pub type Vec3 = [Real; 3];

/// `a + b`.
#[inline(always)]
pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a - b`.
#[inline(always)]
pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `s * a`.
#[inline(always)]
pub fn scale(a: Vec3, s: Real) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// `a + s * b`.
#[inline(always)]
pub fn axpy(a: Vec3, s: Real, b: Vec3) -> Vec3 {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

/// Dot product.
#[inline(always)]
pub fn dot(a: Vec3, b: Vec3) -> Real {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
#[inline(always)]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Squared Euclidean norm.
#[inline(always)]
pub fn norm_squared(a: Vec3) -> Real {
    dot(a, a)
}

/// Euclidean norm.
#[inline(always)]
pub fn norm(a: Vec3) -> Real {
    dot(a, a).sqrt()
}

/// A 3x3 matrix stored by rows.
pub type Mat3 = [[Real; 3]; 3];

/// `m * v`.
#[inline(always)]
pub fn mat_vec(m: &Mat3, v: Vec3) -> Vec3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// The identity matrix.
pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Rotation by `angle` radians about the unit `axis` (Rodrigues' formula).
pub fn rotation(axis: Vec3, angle: Real) -> Mat3 {
    let n = norm(axis);
    let [x, y, z] = scale(axis, 1.0 / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [c + x * x * t, x * y * t - z * s, x * z * t + y * s],
        [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
        [z * x * t - y * s, z * y * t + x * s, c + z * z * t],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_is_orthonormal_and_turns_x_to_y() {
        let r = rotation([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2);
        let v = mat_vec(&r, [1.0, 0.0, 0.0]);
        // exact up to cos(pi/2) ~ 6e-17
        assert!(norm(sub(v, [0.0, 1.0, 0.0])) < 1e-15);
        let w = mat_vec(&r, [0.3, -0.2, 0.7]);
        assert!((norm(w) - norm([0.3, -0.2, 0.7])).abs() < 1e-15);
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
    }
}
