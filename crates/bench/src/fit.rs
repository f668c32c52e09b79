//! Where a material point that is no particle has gone: a least-squares affine map
//! `y = c + B (X - X_mean)` fitted over nearby particles, read at the point.

use perifrac_physics::Vec3;

/// The current position (m) of the material point `at` (rest position, m), from the affine
/// map that fits the particles `near` best in least squares, their rest positions in `rest`
/// and current ones in `current`. A large rotation is affine, so a fit over a layer a few
/// cells deep at a bar's free end reads the end's centre to the bending of that layer. `None`
/// when the rest positions of `near` do not span three dimensions.
pub(crate) fn affine_at(rest: &[Vec3], current: &[Vec3], near: &[u32], at: Vec3) -> Option<Vec3> {
    let n = near.len() as f64;
    if near.len() < 4 {
        return None;
    }
    let mean = |v: &[Vec3]| -> Vec3 {
        let mut m = [0.0; 3];
        for &i in near {
            for d in 0..3 {
                m[d] += v[i as usize][d] / n;
            }
        }
        m
    };
    let (xm, ym) = (mean(rest), mean(current));
    // normal equations: C b_c = r_c, C = sum dX dX^T, r_c = sum dX dy_c
    let mut c = [[0.0; 3]; 3];
    let mut r = [[0.0; 3]; 3];
    for &i in near {
        let dx: Vec3 = std::array::from_fn(|d| rest[i as usize][d] - xm[d]);
        let dy: Vec3 = std::array::from_fn(|d| current[i as usize][d] - ym[d]);
        for a in 0..3 {
            for b in 0..3 {
                c[a][b] += dx[a] * dx[b];
                r[b][a] += dx[a] * dy[b];
            }
        }
    }
    let inv = inverse(&c)?;
    let dp: Vec3 = std::array::from_fn(|d| at[d] - xm[d]);
    Some(std::array::from_fn(|comp| {
        // row `comp` of B = C^-1 r_comp
        let row: Vec3 = std::array::from_fn(|a| (0..3).map(|b| inv[a][b] * r[comp][b]).sum());
        ym[comp] + (0..3).map(|a| row[a] * dp[a]).sum::<f64>()
    }))
}

/// The inverse of a symmetric positive semi-definite 3 x 3 matrix, `None` when it is singular
/// to rounding (its determinant below 1e-12 of the product of its diagonal).
fn inverse(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let cof = |a: usize, b: usize| {
        let (r0, r1) = ((a + 1) % 3, (a + 2) % 3);
        let (c0, c1) = ((b + 1) % 3, (b + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let det: f64 = (0..3).map(|b| m[0][b] * cof(0, b)).sum();
    let scale = m[0][0] * m[1][1] * m[2][2];
    if !(det.is_finite() && det > 1e-12 * scale.abs()) {
        return None;
    }
    Some(std::array::from_fn(|a| {
        std::array::from_fn(|b| cof(b, a) / det)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_affine_motion_is_read_exactly_anywhere() {
        let rest: Vec<Vec3> = (0..27)
            .map(|i| {
                [
                    (i % 3) as f64,
                    ((i / 3) % 3) as f64 * 0.5,
                    (i / 9) as f64 * 0.2,
                ]
            })
            .collect();
        // a rotation by 0.7 rad about z, a stretch along x and a shift
        let (s, c) = 0.7f64.sin_cos();
        let map = |x: Vec3| {
            [
                1.2 * (c * x[0] - s * x[1]) + 0.3,
                s * x[0] + c * x[1],
                x[2] - 1.0,
            ]
        };
        let current: Vec<Vec3> = rest.iter().map(|&x| map(x)).collect();
        let near: Vec<u32> = (0..27).collect();
        let at = [5.0, -1.0, 0.4];
        let got = affine_at(&rest, &current, &near, at).unwrap();
        let want = map(at);
        for d in 0..3 {
            assert!((got[d] - want[d]).abs() < 1e-12, "{got:?} {want:?}");
        }
        // points on a line do not fix the map
        let line: Vec<u32> = vec![0, 1, 2];
        assert!(affine_at(&rest, &current, &line, at).is_none());
        let flat: Vec<u32> = (0..9).collect();
        assert!(affine_at(&rest, &current, &flat, at).is_none());
    }
}
