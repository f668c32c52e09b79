//! A shell's frame for output: its current triangles with crack flags and piece ids, or, on
//! request, each piece given a thickness (a closed surface of two offset sheets joined along
//! every free edge), so renders show shards, not sheets of no thickness.

use perifrac_physics::math::{add, cross, dot, norm, scale, sub, Vec3};

use crate::mesh::ShellMesh;
use crate::model::ShellModel;

/// A triangle surface to write: positions (m), unit normals and velocities (m/s) per vertex,
/// triangles, per triangle whether it lies on a crack (1) or not (0), and per triangle the id
/// of its piece (pieces numbered by their lowest triangle, in order).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameMesh {
    /// Vertex positions (m).
    pub vertices: Vec<Vec3>,
    /// Per vertex unit normal: the area-weighted mean of its triangles' (+z where they have no
    /// area); the lower sheet of a thickened frame faces the other way.
    pub normals: Vec<Vec3>,
    /// Per vertex velocity (m/s): the mid-surface vertex's, on both sheets.
    pub velocities: Vec<Vec3>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle: 1 on a crack (a side wall along a crack edge), 0 otherwise.
    pub crack: Vec<u8>,
    /// Per triangle: its piece.
    pub piece: Vec<u32>,
}

/// Each triangle's piece (connected through shared edges), numbered in order of each piece's
/// lowest triangle.
pub fn pieces(mesh: &ShellMesh) -> Vec<u32> {
    let nf = mesh.triangles().len();
    let mut parent: Vec<usize> = (0..nf).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for e in mesh.edges() {
        if !e.is_boundary() {
            let a = root(&mut parent, e.faces[0] as usize);
            let b = root(&mut parent, e.faces[1] as usize);
            // The lower root stays the root, so a piece is named by its lowest triangle.
            let (lo, hi) = (a.min(b), a.max(b));
            parent[hi] = lo;
        }
    }
    let mut id = vec![u32::MAX; nf];
    let mut next = 0u32;
    (0..nf)
        .map(|f| {
            let r = root(&mut parent, f);
            if id[r] == u32::MAX {
                id[r] = next;
                next += 1;
            }
            id[r]
        })
        .collect()
}

impl ShellModel {
    /// The frame at positions `x` (m) and velocities `v` (m/s): the triangles as they are
    /// (`thickness` `None`), or every piece as a closed surface of `thickness` (m): the
    /// mid-surface offset by half of it each way along the area-weighted vertex normals, the
    /// lower sheet turned over, and a wall of two triangles along every free edge (flagged as
    /// crack where the edge is one).
    pub fn frame(&self, x: &[Vec3], v: &[Vec3], thickness: Option<f64>) -> FrameMesh {
        let mesh = self.mesh();
        let tris = mesh.triangles();
        let piece = pieces(mesh);
        let cracks = self.crack_edges();
        let is_crack = |f: usize, k: usize| cracks.get(f).is_some_and(|c| c[k]);
        let n = x.len();
        let mut sums = vec![[0.0; 3]; n];
        for tri in tris {
            let [a, b, c] = tri.map(|i| x[i as usize]);
            let area_normal = cross(sub(b, a), sub(c, a));
            for &i in tri {
                sums[i as usize] = add(sums[i as usize], area_normal);
            }
        }
        let unit: Vec<Vec3> = sums
            .iter()
            .map(|nrm| {
                let l = norm(*nrm);
                if l > 0.0 && l.is_finite() {
                    scale(*nrm, 1.0 / l)
                } else {
                    [0.0, 0.0, 1.0]
                }
            })
            .collect();
        let Some(t) = thickness.filter(|t| *t > 0.0) else {
            let crack = vec![0u8; tris.len()];
            return FrameMesh {
                vertices: x.to_vec(),
                normals: unit.clone(),
                velocities: v.to_vec(),
                triangles: tris.to_vec(),
                crack,
                piece,
            };
        };
        // Half the thickness along each unit vertex normal: upper sheet, then lower.
        let offsets: Vec<Vec3> = sums
            .iter()
            .map(|nrm| {
                let l = norm(*nrm);
                if l > 0.0 {
                    scale(*nrm, 0.5 * t / l)
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let mut normals = Vec::with_capacity(2 * n);
        normals.extend_from_slice(&unit);
        normals.extend(unit.iter().map(|u| scale(*u, -1.0)));
        let mut velocities = Vec::with_capacity(2 * n);
        velocities.extend_from_slice(v);
        velocities.extend_from_slice(v);
        let mut vertices = Vec::with_capacity(2 * n);
        vertices.extend(x.iter().zip(&offsets).map(|(p, o)| add(*p, *o)));
        vertices.extend(x.iter().zip(&offsets).map(|(p, o)| sub(*p, *o)));
        let lower = |i: u32| i + n as u32;
        let mut triangles = Vec::with_capacity(4 * tris.len());
        let mut crack = Vec::with_capacity(4 * tris.len());
        let mut pieces_out = Vec::with_capacity(4 * tris.len());
        for (f, tri) in tris.iter().enumerate() {
            triangles.push(*tri);
            triangles.push([lower(tri[0]), lower(tri[2]), lower(tri[1])]);
            crack.extend([0, 0]);
            pieces_out.extend([piece[f], piece[f]]);
        }
        for e in mesh.edges().iter().filter(|e| e.is_boundary()) {
            // The triangle beside it runs v0 -> v1; the wall runs the other way on top.
            let f = e.faces[0] as usize;
            let k = mesh.face_edges()[f]
                .iter()
                .position(|&j| mesh.edges()[j as usize] == *e)
                .unwrap_or(0);
            let (a, b) = (e.v[0], e.v[1]);
            triangles.push([b, a, lower(a)]);
            triangles.push([b, lower(a), lower(b)]);
            let c = u8::from(is_crack(f, k));
            crack.extend([c, c]);
            pieces_out.extend([piece[f], piece[f]]);
        }
        FrameMesh {
            vertices,
            normals,
            velocities,
            triangles,
            crack,
            piece: pieces_out,
        }
    }
}

/// Signed volume (m^3) enclosed by a closed, outward-oriented triangle surface.
pub fn enclosed_volume(vertices: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            dot(a, cross(b, c)) / 6.0
        })
        .sum()
}
