//! Diagnostics over particle arrays: kinetic energy, momentum, angular momentum.
//! Sums run sequentially in particle order, so they are deterministic.

use crate::math::{add, cross, dot, scale, Vec3};

/// Kinetic energy `sum m v^2 / 2` (J).
pub fn kinetic_energy(mass: &[f64], v: &[Vec3]) -> f64 {
    mass.iter().zip(v).map(|(m, v)| 0.5 * m * dot(*v, *v)).sum()
}

/// Linear momentum `sum m v` (kg m/s).
pub fn momentum(mass: &[f64], v: &[Vec3]) -> Vec3 {
    mass.iter()
        .zip(v)
        .fold([0.0; 3], |acc, (m, v)| add(acc, scale(*v, *m)))
}

/// Angular momentum about the origin `sum m y x v` (kg m^2/s).
pub fn angular_momentum(mass: &[f64], y: &[Vec3], v: &[Vec3]) -> Vec3 {
    mass.iter()
        .zip(y.iter().zip(v))
        .fold([0.0; 3], |acc, (m, (y, v))| {
            add(acc, scale(cross(*y, *v), *m))
        })
}
