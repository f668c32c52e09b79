//! Small pieces placed rigidly: a piece of a few tets carries too few particles for advection
//! to follow its rotation (a lone tet's four vertices all move with its one particle; a piece of
//! three tets spinning shrinks towards its barycentres and can turn inside out). Such a piece's
//! vertices are put back into its rest shape, turned and moved as its advected vertices best
//! say: the rotation of Horn's closed-form fit (always proper, so never a mirror image) and the
//! centroid of the advected vertices.

use crate::mesh::TetMesh;
use crate::pieces::Pieces;

/// The default size (tets) up to which a piece is placed rigidly: below two box cells (12
/// tets), where a piece has no bending or stretching an eye could see, and where advection's
/// averaging over a vertex's few tets distorts most.
pub const RIGID_PIECE_TETS: usize = 12;

impl TetMesh {
    /// Puts the vertices of every piece of at most `max_tets` tets back into the piece's rest
    /// shape, turned by the best rotation from the rest to the current vertex positions and
    /// centred on the current vertices' centroid. Returns how many pieces it placed. Call it
    /// after [`TetMesh::split`] (each vertex then belongs to one piece); `pieces` must be this
    /// mesh's current pieces.
    ///
    /// Panics if `pieces` does not have one entry per tet.
    #[track_caller]
    pub fn place_small_pieces_rigidly(&mut self, pieces: &Pieces, max_tets: usize) -> usize {
        assert_eq!(
            pieces.piece_of_tet.len(),
            self.tets.len(),
            "one piece per tet"
        );
        let mut size = vec![0usize; pieces.count];
        for &p in &pieces.piece_of_tet {
            size[p as usize] += 1;
        }
        // Vertices of the small pieces, grouped by piece (each vertex once).
        let mut start = vec![0usize; pieces.count + 1];
        let mut owner = vec![u32::MAX; self.pos.len()];
        for (t, tet) in self.tets.iter().enumerate() {
            let p = pieces.piece_of_tet[t];
            if size[p as usize] > max_tets {
                continue;
            }
            for &v in tet {
                if owner[v as usize] == u32::MAX {
                    owner[v as usize] = p;
                    start[p as usize + 1] += 1;
                }
            }
        }
        for p in 0..pieces.count {
            start[p + 1] += start[p];
        }
        let mut fill = start.clone();
        let mut members = vec![0u32; start[pieces.count]];
        for (v, &p) in owner.iter().enumerate() {
            if p != u32::MAX {
                members[fill[p as usize]] = v as u32;
                fill[p as usize] += 1;
            }
        }
        let mut placed = 0;
        for p in 0..pieces.count {
            let vs = &members[start[p]..start[p + 1]];
            if vs.is_empty() {
                continue;
            }
            let rest = |v: u32| self.rest[self.origin[v as usize] as usize];
            let n = vs.len() as f64;
            let mut c_rest = [0.0; 3];
            let mut c_now = [0.0; 3];
            for &v in vs {
                for k in 0..3 {
                    c_rest[k] += rest(v)[k] / n;
                    c_now[k] += self.pos[v as usize][k] / n;
                }
            }
            // S[i][j] = sum over vertices of a_i b_j, a the centred rest position and b the
            // centred current one.
            let mut s = [[0.0; 3]; 3];
            for &v in vs {
                let r = rest(v);
                let x = self.pos[v as usize];
                for i in 0..3 {
                    for j in 0..3 {
                        s[i][j] += (r[i] - c_rest[i]) * (x[j] - c_now[j]);
                    }
                }
            }
            let rot = best_rotation(&s);
            for &v in vs {
                let a: [f64; 3] = std::array::from_fn(|k| rest(v)[k] - c_rest[k]);
                let x = &mut self.pos[v as usize];
                for i in 0..3 {
                    x[i] = c_now[i] + rot[i][0] * a[0] + rot[i][1] * a[1] + rot[i][2] * a[2];
                }
            }
            placed += 1;
        }
        placed
    }
}

/// The proper rotation `R` (rows) that best maps centred points `a_k` onto `b_k` in the least
/// squares sense, from `s[i][j] = sum_k a_k[i] b_k[j]` (Horn 1987: the unit quaternion is the
/// eigenvector of the largest eigenvalue of a symmetric 4x4 matrix built from `s`). Identity
/// when `s` says nothing (all zero).
pub(crate) fn best_rotation(s: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let [[xx, xy, xz], [yx, yy, yz], [zx, zy, zz]] = *s;
    let mut n = [
        [xx + yy + zz, yz - zy, zx - xz, xy - yx],
        [yz - zy, xx - yy - zz, xy + yx, zx + xz],
        [zx - xz, xy + yx, -xx + yy - zz, yz + zy],
        [xy - yx, zx + xz, yz + zy, -xx - yy + zz],
    ];
    let mut vecs = [[0.0; 4]; 4];
    for (i, row) in vecs.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    jacobi_eigen(&mut n, &mut vecs);
    // The column of the largest eigenvalue (ties: the lowest index, deterministic).
    let mut best = 0;
    for k in 1..4 {
        if n[k][k] > n[best][best] {
            best = k;
        }
    }
    let q: [f64; 4] = std::array::from_fn(|i| vecs[i][best]);
    let len = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let [w, x, y, z] = q.map(|c| c / len);
    [
        [
            w * w + x * x - y * y - z * z,
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            w * w - x * x + y * y - z * z,
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            w * w - x * x - y * y + z * z,
        ],
    ]
}

/// Cyclic Jacobi eigenvalue iteration of a symmetric 4x4 `a` in place: on return its diagonal
/// holds the eigenvalues and the columns of `v` (which must start as the identity) the
/// eigenvectors. A fixed sweep order makes it deterministic.
fn jacobi_eigen(a: &mut [[f64; 4]; 4], v: &mut [[f64; 4]; 4]) {
    for _sweep in 0..50 {
        let off: f64 = (0..4)
            .flat_map(|i| (0..4).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        let scale: f64 = (0..4).map(|i| a[i][i] * a[i][i]).sum::<f64>() + off;
        if off <= 1e-30 * scale || off == 0.0 {
            return;
        }
        for p in 0..3 {
            for q in p + 1..4 {
                if a[p][q] == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
                let t = sign / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (row_p, row_q) = (a[p], a[q]);
                for (k, (apk, aqk)) in row_p.into_iter().zip(row_q).enumerate() {
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives;

    fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
        let l = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        let [x, y, z] = axis.map(|c| c / l);
        let (s, c) = angle.sin_cos();
        let t = 1.0 - c;
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    }

    fn apply(r: &[[f64; 3]; 3], a: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| r[i][0] * a[0] + r[i][1] * a[1] + r[i][2] * a[2])
    }

    #[test]
    fn horn_recovers_a_rotation_and_never_a_mirror() {
        let pts = [
            [1.0, 0.2, -0.3],
            [-0.4, 1.1, 0.5],
            [0.3, -0.7, 0.9],
            [-0.9, -0.6, -1.1],
        ];
        for (axis, angle) in [
            ([0.0, 0.0, 1.0], 0.3),
            ([1.0, 2.0, -0.5], 2.9),
            ([0.3, -1.0, 0.2], std::f64::consts::PI),
            ([1.0, 0.0, 0.0], 0.0),
        ] {
            let r = rotation(axis, angle);
            let mut s = [[0.0; 3]; 3];
            for a in pts {
                let b = apply(&r, a);
                for i in 0..3 {
                    for j in 0..3 {
                        s[i][j] += a[i] * b[j];
                    }
                }
            }
            let got = best_rotation(&s);
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        (got[i][j] - r[i][j]).abs() < 1e-12,
                        "{axis:?} {angle}: {got:?}"
                    );
                }
            }
        }
        // Mirrored points: the best proper rotation, determinant +1.
        let mut s = [[0.0; 3]; 3];
        for a in pts {
            let b = [a[0], a[1], -a[2]];
            for i in 0..3 {
                for j in 0..3 {
                    s[i][j] += a[i] * b[j];
                }
            }
        }
        let r = best_rotation(&s);
        let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
            - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
            + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
        assert!((det - 1.0).abs() < 1e-12, "{det}");
        assert_eq!(best_rotation(&[[0.0; 3]; 3])[1], [0.0, 1.0, 0.0]);
    }

    #[test]
    fn an_inverted_small_piece_comes_back_right_side_out() {
        // One cell of 6 tets, all one piece; squash it through itself and turn it.
        let mut mesh = primitives::box_mesh([0.0; 3], [1.0, 1.0, 1.0], [1, 1, 1]);
        let r = rotation([1.0, 1.0, 0.0], 1.0);
        for x in mesh.positions_mut() {
            let mirrored = [x[0], x[1], 0.2 - 0.6 * x[2]];
            *x = apply(&r, mirrored);
            x[0] += 5.0;
        }
        let pieces = mesh.pieces();
        assert_eq!(mesh.place_small_pieces_rigidly(&pieces, 6), 1);
        for t in 0..mesh.num_tets() {
            let [a, b, c, d] = mesh.tets()[t].map(|v| mesh.positions()[v as usize]);
            let v = crate::faces::signed_volume(a, b, c, d);
            assert!((v - mesh.tet_rest_volume(t)).abs() < 1e-12, "tet {t}: {v}");
        }
        // A larger limit leaves nothing out, a smaller one places nothing.
        assert_eq!(mesh.place_small_pieces_rigidly(&pieces, 5), 0);
    }
}
