//! The planes of a tet mesh's boundary near a point, for ghost particles (issue 18): near a flat
//! face one plane, near a sharp edge or corner one per face meeting there, on a curved surface
//! the tangent plane at the nearest point. Images mirrored across them are kept only outside the
//! body, which the generalised winding number of the boundary decides.

use hashbrown::HashMap;

use crate::faces::{cross, dot, norm, sub};
use crate::mesher::bvh::closest_on_triangle;
use crate::mesher::Winding;
use crate::TetMesh;

/// Faces whose (smoothed) normals differ by more than this angle (degrees) are separate planes
/// at a point: a box's edges (90 degrees) are sharp, while a curved surface whose normal turns
/// by up to 32 degrees across a horizon (a sphere 3.5 horizons in radius, measured) is one
/// tangent plane.
pub const PLANE_ANGLE: f64 = 45.0;

/// Neighbouring triangles whose normals are within this angle (degrees) are averaged into one
/// smoothed normal: the facets of a meshed curved surface turn by up to about 45 degrees
/// between neighbours, a box's faces by 90.
pub const SMOOTH_ANGLE: f64 = 60.0;

/// The cell `c` and its 26 neighbours.
fn around(c: [i64; 3]) -> impl Iterator<Item = [i64; 3]> {
    (-1..=1).flat_map(move |dx| {
        (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| [c[0] + dx, c[1] + dy, c[2] + dz]))
    })
}

/// The boundary of a tet mesh at rest, bucketed for queries within a radius.
#[derive(Debug, Clone)]
pub struct BoundaryPlanes {
    tris: Vec<[[f64; 3]; 3]>,
    normals: Vec<[f64; 3]>,
    cell: f64,
    grid: HashMap<[i64; 3], Vec<u32>>,
    winding: Winding,
}

impl BoundaryPlanes {
    /// The boundary of `mesh` at its rest positions, bucketed in cells of `radius` (m, the
    /// radius later queries use; positive).
    pub fn new(mesh: &TetMesh, radius: f64) -> Self {
        let s = mesh.surface();
        let tris: Vec<[[f64; 3]; 3]> = s
            .faces
            .iter()
            .map(|f| f.map(|v| s.vertices[v as usize]))
            .collect();
        let normals: Vec<[f64; 3]> = tris
            .iter()
            .map(|t| {
                let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
                let l = norm(n);
                if l > 0.0 {
                    n.map(|c| c / l)
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let cell = radius;
        let key = |p: [f64; 3]| p.map(|c| (c / cell).floor() as i64);
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (f, t) in tris.iter().enumerate() {
            let lo = key([0, 1, 2].map(|a| t[0][a].min(t[1][a]).min(t[2][a])));
            let hi = key([0, 1, 2].map(|a| t[0][a].max(t[1][a]).max(t[2][a])));
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        grid.entry([x, y, z]).or_default().push(f as u32);
                    }
                }
            }
        }
        // each triangle's normal smoothed over the triangles within half the radius whose own
        // normals are within SMOOTH_ANGLE of it (area-weighted): a faceted curved surface reads
        // as its tangent plane, while a box's edges (90 degrees) stay sharp
        let centre = |t: &[[f64; 3]; 3]| [0, 1, 2].map(|a| (t[0][a] + t[1][a] + t[2][a]) / 3.0);
        let area = |t: &[[f64; 3]; 3]| norm(cross(sub(t[1], t[0]), sub(t[2], t[0])));
        let cos = SMOOTH_ANGLE.to_radians().cos();
        let smoothed = (0..tris.len())
            .map(|f| {
                let n: [f64; 3] = normals[f];
                if n == [0.0; 3] {
                    return n;
                }
                let c = centre(&tris[f]);
                let k = key(c);
                let mut sum = [0.0; 3];
                for home in around(k) {
                    for &g in grid.get(&home).into_iter().flatten() {
                        let (t, m) = (&tris[g as usize], normals[g as usize]);
                        // a triangle in several cells is counted once, from its own
                        if key(centre(t)) != home
                            || dot(m, n) <= cos
                            || norm(sub(centre(t), c)) > 0.5 * radius
                        {
                            continue;
                        }
                        let w = area(t);
                        sum = [0, 1, 2].map(|a| sum[a] + w * m[a]);
                    }
                }
                let l = norm(sum);
                if l > 0.0 {
                    sum.map(|v| v / l)
                } else {
                    n
                }
            })
            .collect();
        let winding = Winding::new(&s.vertices, &s.faces);
        BoundaryPlanes {
            tris,
            normals: smoothed,
            cell,
            grid,
            winding,
        }
    }

    /// The planes of the boundary within `radius` (m, at most the bucketing radius) of `x`,
    /// nearest first, as `(point, outward unit normal)`: the nearest point of the nearest
    /// triangle with that triangle's normal, then the same for the nearest triangle whose normal
    /// is more than [`PLANE_ANGLE`] from every plane already taken, and so on.
    pub fn near(&self, x: [f64; 3], radius: f64) -> Vec<([f64; 3], [f64; 3])> {
        let c = x.map(|v| (v / self.cell).floor() as i64);
        let mut found: Vec<(f64, u32, [f64; 3])> = Vec::new();
        for cell in around(c) {
            for &f in self.grid.get(&cell).into_iter().flatten() {
                let p = closest_on_triangle(x, &self.tris[f as usize]);
                let d = norm(sub(p, x));
                if d < radius && !found.iter().any(|e| e.1 == f) {
                    found.push((d, f, p));
                }
            }
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let cos = PLANE_ANGLE.to_radians().cos();
        // each plane: its seed (the nearest triangle's nearest point and normal) and the sum of
        // its members' normals weighted by area, which smooths a faceted curved surface
        let mut planes: Vec<([f64; 3], [f64; 3], [f64; 3])> = Vec::new();
        for (_, f, p) in found {
            let n = self.normals[f as usize];
            if n == [0.0; 3] {
                continue;
            }
            let t = &self.tris[f as usize];
            let area = norm(cross(sub(t[1], t[0]), sub(t[2], t[0])));
            match planes.iter_mut().find(|q| dot(q.1, n) > cos) {
                Some(q) => q.2 = [0, 1, 2].map(|a| q.2[a] + area * n[a]),
                None => planes.push((p, n, n.map(|c| area * c))),
            }
        }
        planes
            .into_iter()
            .map(|(p, _, sum)| (p, sum.map(|c| c / norm(sum))))
            .collect()
    }

    /// Whether `x` lies inside the body (generalised winding number above one half).
    pub fn inside(&self, x: [f64; 3]) -> bool {
        self.winding.inside(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::box_data;

    #[test]
    fn a_cubes_faces_edges_and_corners_give_one_two_and_three_planes() {
        let (v, t) = box_data([0.0; 3], [1.0; 3], [4, 4, 4]);
        let (mesh, _) = TetMesh::new(v, t).unwrap();
        let b = BoundaryPlanes::new(&mesh, 0.2);
        let count = |x: [f64; 3]| b.near(x, 0.2).len();
        assert_eq!(count([0.5, 0.5, 0.5]), 0);
        assert_eq!(count([0.5, 0.5, 0.9]), 1);
        assert_eq!(count([0.5, 0.9, 0.9]), 2);
        assert_eq!(count([0.9, 0.9, 0.9]), 3);
        // the planes are the faces', their normals exact on flat faces
        let p = b.near([0.1, 0.5, 0.5], 0.2);
        assert_eq!(p[0].1, [-1.0, 0.0, 0.0]);
        assert!((p[0].0[0]).abs() < 1e-15);
        assert!(b.inside([0.5; 3]) && !b.inside([1.1, 0.5, 0.5]));
    }
}
