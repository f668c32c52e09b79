//! Anisotropy helpers (docs/model.md section 4). Chen's per-particle matrix `G` enters the Chen
//! model through [`crate::ChenMaterial::anisotropy`] (`omega = delta / |G xi|`); Xu's scalar
//! bond factor is [`crate::XuAnisotropy::factor`].

use crate::math::{Mat3, Vec3};

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
    fn chen_matrix_is_identity_for_unit_stretch() {
        let g = chen_matrix(&rotation([0.2, 0.3, 1.0], 1.0), [1.0; 3]);
        for (r, row) in g.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                assert!((v - IDENTITY[r][c]).abs() < 1e-15);
            }
        }
    }
}
