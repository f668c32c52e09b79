//! Vertices placed from the particles by a local affine fit: each vertex goes where the
//! best-fitting affine map of the particles around it (the tets using it and their
//! face-neighbours through uncracked faces, a layer more where those lie in a plane) takes its
//! rest position. Exact for any rigid motion
//! and any uniform strain, whatever the step, and with no memory of earlier steps, so it does not
//! drift: advection (a mass-weighted mean velocity per vertex, stepped forward) turns a spinning
//! piece's hull inwards and, over the long steps of an implicit run (one per frame), can turn
//! a piece of a few dozen tets inside out.

use crate::mesh::{TetMesh, NO_TET};

/// A fit is used only when the rest barycentres around a vertex spread in all three directions:
/// the smallest over the largest principal spread (eigenvalues of their covariance) at least
/// this. Below it (a vertex with its neighbourhood nearly in a plane or on a line), the vertex
/// keeps its advected position.
const MIN_SPREAD: f64 = 1e-5;

/// Layers of face-neighbours a vertex's neighbourhood may grow by before it gives up.
const MAX_LAYERS: usize = 3;

impl TetMesh {
    /// Moves every vertex to the position the affine fit of the particles around it gives
    /// (see the module documentation), `particles` the current particle positions (one per
    /// tet, length). A vertex whose neighbourhood does not spread in three directions, or whose
    /// fit turns it inside out (determinant not positive), keeps its position. Returns how many
    /// vertices were placed.
    ///
    /// Panics if `particles` does not have one entry per tet.
    #[track_caller]
    pub fn place_vertices_from_particles(&mut self, particles: &[[f64; 3]]) -> usize {
        assert_eq!(particles.len(), self.tets.len(), "one particle per tet");
        let rest_bary: Vec<[f64; 3]> = self
            .tets
            .iter()
            .map(|t| {
                let mut b = [0.0; 3];
                for &v in t {
                    let r = self.rest[self.origin[v as usize] as usize];
                    for k in 0..3 {
                        b[k] += 0.25 * r[k];
                    }
                }
                b
            })
            .collect();
        let mut around: Vec<u32> = Vec::new();
        let mut grown: Vec<u32> = Vec::new();
        let mut placed = 0;
        for v in 0..self.pos.len() {
            let r = self.origin[v] as usize;
            around.clear();
            around.extend(
                self.star_tets[self.star_offsets[r]..self.star_offsets[r + 1]]
                    .iter()
                    .copied()
                    .filter(|&t| self.tets[t as usize].contains(&(v as u32))),
            );
            let x = self.rest[r];
            // The tets using the vertex and their face-neighbours; where those do not spread
            // in three directions (a box corner's few tets can have coplanar barycentres),
            // one more layer, up to [`MAX_LAYERS`].
            for _ in 0..MAX_LAYERS {
                grown.clear();
                for &t in &around {
                    grown.push(t);
                    for (f, &n) in self.neighbours[t as usize].iter().enumerate() {
                        if n != NO_TET && self.crack[t as usize] & (1 << f) == 0 {
                            grown.push(n);
                        }
                    }
                }
                grown.sort_unstable();
                grown.dedup();
                let same = grown.len() == around.len();
                std::mem::swap(&mut around, &mut grown);
                if same {
                    break;
                }
                if around.len() < 4 {
                    continue;
                }
                if let Some(p) = fit(&around, &rest_bary, particles, x) {
                    self.pos[v] = p;
                    placed += 1;
                    break;
                }
            }
        }
        placed
    }
}

/// The affine least-squares map of the rest points `rest[t]` onto `now[t]` over `tets`,
/// applied to `x`; `None` when the rest points do not spread in three directions or the map's
/// determinant is not positive.
fn fit(tets: &[u32], rest: &[[f64; 3]], now: &[[f64; 3]], x: [f64; 3]) -> Option<[f64; 3]> {
    let n = tets.len() as f64;
    let (mut cr, mut cn) = ([0.0; 3], [0.0; 3]);
    for &t in tets {
        for k in 0..3 {
            cr[k] += rest[t as usize][k] / n;
            cn[k] += now[t as usize][k] / n;
        }
    }
    // C = sum a a^T, D = sum b a^T with a, b the centred rest and current points.
    let (mut c, mut d) = ([[0.0; 3]; 3], [[0.0; 3]; 3]);
    for &t in tets {
        let a: [f64; 3] = std::array::from_fn(|k| rest[t as usize][k] - cr[k]);
        let b: [f64; 3] = std::array::from_fn(|k| now[t as usize][k] - cn[k]);
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] += a[i] * a[j];
                d[i][j] += b[i] * a[j];
            }
        }
    }
    let inv = inverse_if_spread(&c)?;
    let f: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| d[i][k] * inv[k][j]).sum()));
    if det(&f) <= 0.0 {
        return None;
    }
    let a: [f64; 3] = std::array::from_fn(|k| x[k] - cr[k]);
    Some(std::array::from_fn(|i| {
        cn[i] + f[i][0] * a[0] + f[i][1] * a[1] + f[i][2] * a[2]
    }))
}

fn det(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// The inverse of the symmetric positive semi-definite `c`, when its smallest eigenvalue is at
/// least [`MIN_SPREAD`] of its largest. The eigenvalue bounds come from the determinant and
/// trace: with `l1 >= l2 >= l3 >= 0`, `l1 <= tr` and `l3 >= det / (l1 l2) >= det / tr^2`, so
/// `det / tr^3 >= MIN_SPREAD` guarantees the ratio (a conservative test).
fn inverse_if_spread(c: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let tr = c[0][0] + c[1][1] + c[2][2];
    let dt = det(c);
    let spread = tr > 0.0 && dt >= MIN_SPREAD * tr * tr * tr;
    if !spread {
        return None;
    }
    let cof = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        c[r0][c0] * c[r1][c1] - c[r0][c1] * c[r1][c0]
    };
    // inverse = adjugate / det; the adjugate is the transposed cofactor matrix.
    Some(std::array::from_fn(|i| {
        std::array::from_fn(|j| cof(j, i) / dt)
    }))
}

#[cfg(test)]
mod tests {
    use crate::primitives;

    #[test]
    fn an_affine_motion_of_the_particles_moves_the_vertices_exactly() {
        let mut mesh = primitives::box_mesh([0.0; 3], [2.0, 1.0, 1.0], [4, 2, 2]);
        // Rotation by 1.2 rad about z with a stretch along x, and a shift.
        let (s, c) = 1.2f64.sin_cos();
        let map = |p: [f64; 3]| {
            let q = [1.3 * p[0], p[1], p[2]];
            [
                c * q[0] - s * q[1] + 5.0,
                s * q[0] + c * q[1] - 2.0,
                q[2] + 0.5,
            ]
        };
        let particles: Vec<[f64; 3]> = mesh.rest_barycentres().into_iter().map(map).collect();
        let placed = mesh.place_vertices_from_particles(&particles);
        assert_eq!(placed, mesh.num_vertices());
        for (x, r) in mesh.positions().iter().zip(mesh.rest_positions()) {
            let want = map(*r);
            for k in 0..3 {
                assert!((x[k] - want[k]).abs() < 1e-12, "{x:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn a_lone_tet_keeps_its_position() {
        let mut mesh = primitives::box_mesh([0.0; 3], [1.0, 1.0, 1.0], [1, 1, 1]);
        // Crack every interior face: six lone tets, each too few particles for a fit.
        let all: Vec<(u32, u32)> = (0..6u32)
            .flat_map(|t| (t + 1..6).map(move |u| (t, u)))
            .collect();
        mesh.crack_bonds(&all);
        mesh.split();
        let before = mesh.positions().to_vec();
        let moved: Vec<[f64; 3]> = mesh
            .rest_barycentres()
            .iter()
            .map(|b| [b[0] + 9.0, b[1], b[2]])
            .collect();
        assert_eq!(mesh.place_vertices_from_particles(&moved), 0);
        assert_eq!(mesh.positions(), &before[..]);
    }
}
