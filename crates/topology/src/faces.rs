//! Local face tables of a tetrahedron.
//!
//! Local face `f` is the face opposite local vertex `f`. For a positively oriented tet
//! (`det[b-a, c-a, d-a] > 0`) the corner orders below list every face counter-clockwise seen
//! from outside, so the right-hand normal points away from the opposite vertex:
//!
//! | face | corners   |
//! |------|-----------|
//! | 0    | (1, 2, 3) |
//! | 1    | (0, 3, 2) |
//! | 2    | (0, 1, 3) |
//! | 3    | (0, 2, 1) |
//!
//! Why: `(b, c, d, a)` is an odd permutation of `(a, b, c, d)`, so `a` lies on the negative side
//! of `(b, c, d)`; the other rows follow the same parity argument.

/// Corners of each local face, outward (counter-clockwise from outside) for a positive tet.
pub const FACE_CORNERS: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// The six edges of a tet as local corner pairs.
pub const EDGES: [[usize; 2]; 6] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];

/// Signed volume of the tet `(a, b, c, d)`: `det[b-a, c-a, d-a] / 6` (length^3).
#[inline]
pub fn signed_volume(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    let u = sub(b, a);
    let v = sub(c, a);
    let w = sub(d, a);
    dot(u, cross(v, w)) / 6.0
}

#[inline]
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_faces_point_away_from_the_opposite_vertex() {
        // A positive but deliberately irregular tet, so no symmetry hides a wrong row.
        let p = [
            [0.1, -0.2, 0.05],
            [1.3, 0.1, -0.1],
            [0.2, 0.9, 0.3],
            [0.4, 0.3, 1.7],
        ];
        assert!(signed_volume(p[0], p[1], p[2], p[3]) > 0.0);
        for (f, corners) in FACE_CORNERS.iter().enumerate() {
            assert!(
                !corners.contains(&f),
                "face {f} must not contain vertex {f}"
            );
            let [a, b, c] = corners.map(|k| p[k]);
            let n = cross(sub(b, a), sub(c, a));
            assert!(dot(n, sub(p[f], a)) < 0.0, "face {f} normal points inward");
        }
    }
}
