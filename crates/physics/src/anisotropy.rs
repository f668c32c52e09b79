//! Anisotropy helpers (MODEL.md section 4). Chen's per-particle matrix `G` enters the Chen model
//! through [`crate::ChenMaterial::anisotropy`] (`omega = delta / |G xi|`); Xu's scalar bond
//! factor is provided here for the hyperelastic model to come.

use crate::math::{mat_vec, norm, scale, Mat3, Vec3};

/// Xu's scalar bond factor `G_ij = |Sigma R xi / r|` (dimensionless), where the columns of
/// `axes` are the orthonormal material axes `R` and `stretch = (s1, s2, s3)` is `Sigma`.
/// Returns `None` unless `s1 s2 s3 = 1` (to 1e-12), which keeps the overall stiffness.
pub fn xu_bond_factor(axes: &Mat3, stretch: Vec3, xi: Vec3) -> Option<f64> {
    if (stretch[0] * stretch[1] * stretch[2] - 1.0).abs() > 1e-12 {
        return None;
    }
    let r = norm(xi);
    let u = mat_vec(axes, scale(xi, 1.0 / r));
    Some(norm([
        stretch[0] * u[0],
        stretch[1] * u[1],
        stretch[2] * u[2],
    ]))
}

/// Chen's `G` for stiffness scaled by `stretch[a]` along the orthonormal axis `a` (columns of
/// `axes`): `G = R^T diag(1 / s) R`, so `omega = delta / |G xi|` grows along stiff axes.
pub fn chen_matrix(axes: &Mat3, stretch: Vec3) -> Mat3 {
    let mut g = [[0.0; 3]; 3];
    for (r, row) in g.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|a| axes[a][r] * axes[a][c] / stretch[a]).sum();
        }
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{rotation, IDENTITY};

    #[test]
    fn xu_factor_is_one_for_isotropy_and_needs_unit_determinant() {
        let xi = [0.3, -0.4, 1.2];
        assert!((xu_bond_factor(&IDENTITY, [1.0; 3], xi).unwrap() - 1.0).abs() < 1e-15);
        assert!(xu_bond_factor(&IDENTITY, [2.0, 1.0, 1.0], xi).is_none());
        let s = [2.0, 0.5, 1.0];
        // along the first axis the factor is s1
        assert!((xu_bond_factor(&IDENTITY, s, [3.0, 0.0, 0.0]).unwrap() - 2.0).abs() < 1e-15);
        // it rotates with the axes
        let r = rotation([1.0, 1.0, 0.0], 0.7);
        let rt = [
            [r[0][0], r[1][0], r[2][0]],
            [r[0][1], r[1][1], r[2][1]],
            [r[0][2], r[1][2], r[2][2]],
        ];
        let along = mat_vec(&rt, [1.0, 0.0, 0.0]);
        assert!((xu_bond_factor(&r, s, along).unwrap() - 2.0).abs() < 1e-14);
    }

    #[test]
    fn chen_matrix_is_identity_for_unit_stretch() {
        let g = chen_matrix(&rotation([0.2, 0.3, 1.0], 1.0), [1.0; 3]);
        for (r, row) in g.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                assert!((v - IDENTITY[r][c]).abs() < 1e-15);
            }
        }
    }
}
