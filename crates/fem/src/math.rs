//! Small fixed-size linear algebra: one `Real`, 3-vectors and row-major 3x3 matrices as plain
//! arrays, and the polar decomposition the corotated kinematics needs.

/// The scalar type of the whole crate.
pub type Real = f64;
/// A point or vector in 3D (m, m/s, N, ... as the context says).
pub type Vec3 = [Real; 3];
/// A 3x3 matrix, row-major: `m[i][j]` is row `i`, column `j`.
pub type Mat3 = [[Real; 3]; 3];

#[inline]
pub(crate) fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub(crate) fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn scale(a: Vec3, s: Real) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub(crate) fn dot(a: Vec3, b: Vec3) -> Real {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn norm(a: Vec3) -> Real {
    dot(a, a).sqrt()
}

/// `a b`.
#[inline]
pub(crate) fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

/// `a^T b`.
#[inline]
pub(crate) fn mat_t_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[0][i] * b[0][j] + a[1][i] * b[1][j] + a[2][i] * b[2][j];
        }
    }
    c
}

#[inline]
pub(crate) fn transpose(m: &Mat3) -> Mat3 {
    [
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]
}

#[inline]
pub(crate) fn det(m: &Mat3) -> Real {
    dot(m[0], cross(m[1], m[2]))
}

/// Inverse of `m`, and its determinant; the inverse is not finite when the determinant is 0.
#[inline]
pub(crate) fn inverse(m: &Mat3) -> (Mat3, Real) {
    let c0 = cross(m[1], m[2]);
    let c1 = cross(m[2], m[0]);
    let c2 = cross(m[0], m[1]);
    let d = dot(m[0], c0);
    let s = 1.0 / d;
    // Columns of the inverse are the cross products over the determinant.
    (
        [
            [c0[0] * s, c1[0] * s, c2[0] * s],
            [c0[1] * s, c1[1] * s, c2[1] * s],
            [c0[2] * s, c1[2] * s, c2[2] * s],
        ],
        d,
    )
}

#[inline]
pub(crate) fn frobenius_squared(m: &Mat3) -> Real {
    dot(m[0], m[0]) + dot(m[1], m[1]) + dot(m[2], m[2])
}

/// Rotation factor `R` of the polar decomposition `F = R S` (`S` symmetric positive definite),
/// by Higham's scaled Newton iteration `X <- (g X + X^-T / g) / 2`, which converges
/// quadratically for any non-singular `F` and keeps the sign of `det F`. Returns `None` when
/// `det F <= 0` (an inverted or flat element, which has no rotation factor).
pub(crate) fn polar_rotation(f: &Mat3) -> Option<Mat3> {
    if det(f) <= 0.0 {
        return None;
    }
    let mut x = *f;
    let mut scaled = true;
    for _ in 0..40 {
        let (inv, _) = inverse(&x);
        let inv_t = transpose(&inv);
        let g = if scaled {
            (frobenius_squared(&inv) / frobenius_squared(&x))
                .sqrt()
                .sqrt()
        } else {
            1.0
        };
        let mut next = [[0.0; 3]; 3];
        let mut change = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                next[i][j] = 0.5 * (g * x[i][j] + inv_t[i][j] / g);
                let d = next[i][j] - x[i][j];
                change += d * d;
            }
        }
        x = next;
        if change < 1e-6 {
            // Close to the answer: the unscaled iteration converges quadratically from here.
            scaled = false;
        }
        if change < 1e-30 {
            break;
        }
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn polar_of_rotated_stretch_recovers_rotation() {
        let (s, c) = (0.7f64.sin(), 0.7f64.cos());
        let r: Mat3 = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let sym: Mat3 = [[1.3, 0.2, -0.1], [0.2, 0.8, 0.05], [-0.1, 0.05, 1.1]];
        let f = mat_mul(&r, &sym);
        let got = polar_rotation(&f).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert!((got[i][j] - r[i][j]).abs() < 1e-14, "{got:?}");
            }
        }
        assert!(polar_rotation(&[[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
    }

    #[test]
    fn inverse_times_matrix_is_identity() {
        let m: Mat3 = [[2.0, 0.3, -1.0], [0.1, 1.5, 0.2], [0.4, -0.2, 3.0]];
        let (inv, d) = inverse(&m);
        assert!((d - det(&m)).abs() < 1e-14);
        let p = mat_mul(&m, &inv);
        for i in 0..3 {
            for j in 0..3 {
                assert!((p[i][j] - IDENTITY[i][j]).abs() < 1e-14);
            }
        }
    }
}
