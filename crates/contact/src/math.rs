//! Small vector helpers on `[f64; 3]` and conversions to parry3d's vector type.

use crate::Vec3;
use parry3d_f64::math::Vector;

#[inline]
pub(crate) fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub(crate) fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub(crate) fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

#[inline]
pub(crate) fn add_assign(a: &mut Vec3, b: Vec3) {
    a[0] += b[0];
    a[1] += b[1];
    a[2] += b[2];
}

#[inline]
pub(crate) fn is_finite(a: Vec3) -> bool {
    a.iter().all(|x| x.is_finite())
}

#[inline]
pub(crate) fn to_parry(a: Vec3) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

#[inline]
pub(crate) fn from_parry(a: Vector) -> Vec3 {
    [a.x, a.y, a.z]
}
