//! The shell's triangle mesh and its edge topology: each edge with the one or two triangles
//! beside it and their opposite vertices, each triangle with its three edges, and each vertex
//! with the edges whose forces reach it.

use crate::error::ShellError;
use perifrac_physics::math::{cross, norm, sub, Vec3};

/// Marks a missing triangle or opposite vertex on a boundary edge.
pub const NONE: u32 = u32::MAX;

/// Triangles at most this share of the equilateral triangle on their longest edge are refused
/// as degenerate: an interior angle below about 1e-8 rad.
const DEGENERATE_SHARE: f64 = 1e-8;

/// An edge and what lies beside it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// Its vertices, in the order `faces[0]` traverses them (so `faces[1]` runs the other way).
    pub v: [u32; 2],
    /// The triangle on each side; `faces[1]` is [`NONE`] on a boundary edge.
    pub faces: [u32; 2],
    /// The vertex of each triangle opposite the edge; `opposite[1]` is [`NONE`] on a boundary.
    pub opposite: [u32; 2],
}

impl Edge {
    /// Whether the edge has a triangle on one side only.
    #[inline]
    pub fn is_boundary(&self) -> bool {
        self.faces[1] == NONE
    }
}

/// Where a vertex sits in an edge's four-vertex stencil: an end (`v[0]`, `v[1]`) or the vertex
/// opposite it in `faces[0]` or `faces[1]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Role {
    /// `Edge::v[0]`.
    Start = 0,
    /// `Edge::v[1]`.
    End = 1,
    /// `Edge::opposite[0]`.
    Opposite0 = 2,
    /// `Edge::opposite[1]`.
    Opposite1 = 3,
}

/// A triangle mesh checked to be a consistently oriented 2-manifold (with or without boundary),
/// with its edge topology.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellMesh {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    edges: Vec<Edge>,
    /// Per triangle, the edge opposite each of its vertices.
    face_edges: Vec<[u32; 3]>,
    /// CSR over vertices of `(edge, role)`: the edges whose stencil holds the vertex.
    stencil_start: Vec<u32>,
    stencil: Vec<(u32, Role)>,
}

impl ShellMesh {
    /// Checks and builds the mesh from `vertices` (m) and `triangles` (vertex indices,
    /// counter-clockwise seen from the side the normal points to). Refused: no triangles, a
    /// non-finite vertex, an index out of range or repeated in a triangle, a degenerate
    /// triangle, an edge with more than two triangles, neighbours oriented inconsistently, a
    /// vertex where two fans of triangles touch, and a vertex in no triangle.
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<ShellMesh, ShellError> {
        if triangles.is_empty() {
            return Err(ShellError::Empty);
        }
        let n = vertices.len();
        if let Some((vertex, p)) = vertices
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|x| !x.is_finite()))
        {
            return Err(ShellError::NonFiniteVertex {
                vertex,
                position: *p,
            });
        }
        let mut used = vec![false; n];
        for (face, t) in triangles.iter().enumerate() {
            let ok =
                t.iter().all(|&i| (i as usize) < n) && t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
            if !ok {
                return Err(ShellError::BadTriangle {
                    face,
                    vertices: *t,
                    count: n,
                });
            }
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            let area = 0.5 * norm(cross(sub(b, a), sub(c, a)));
            let longest = [sub(b, a), sub(c, b), sub(a, c)]
                .iter()
                .map(|e| norm(*e))
                .fold(0.0, f64::max);
            let reference = 3f64.sqrt() / 4.0 * longest * longest;
            if area.is_nan() || area <= DEGENERATE_SHARE * reference {
                return Err(ShellError::Degenerate {
                    face,
                    area,
                    reference,
                });
            }
            for &i in t {
                used[i as usize] = true;
            }
        }
        if let Some(vertex) = used.iter().position(|u| !u) {
            return Err(ShellError::Unused { vertex });
        }
        let (edges, face_edges) = build_edges(&triangles)?;
        check_fans(n, &triangles, &face_edges, &edges)?;
        let (stencil_start, stencil) = build_stencils(n, &edges);
        Ok(ShellMesh {
            vertices,
            triangles,
            edges,
            face_edges,
            stencil_start,
            stencil,
        })
    }

    /// Vertex positions (m) the mesh was built from.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Triangles as vertex indices.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Edges, sorted by their lower vertex index, then the higher.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Per triangle, the edge opposite each of its vertices (edge `k` joins vertices `k + 1`
    /// and `k + 2`, mod 3).
    pub fn face_edges(&self) -> &[[u32; 3]] {
        &self.face_edges
    }

    /// The edges whose four-vertex stencil holds vertex `v`, with its role in each.
    pub fn stencil(&self, v: usize) -> &[(u32, Role)] {
        let lo = self.stencil_start[v] as usize;
        let hi = self.stencil_start[v + 1] as usize;
        &self.stencil[lo..hi]
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of edges on the boundary (one triangle beside them).
    pub fn num_boundary_edges(&self) -> usize {
        self.edges.iter().filter(|e| e.is_boundary()).count()
    }
}

/// Edges from the triangles' directed edges, sorted by vertex pair; each triangle's edges.
fn build_edges(triangles: &[[u32; 3]]) -> Result<(Vec<Edge>, Vec<[u32; 3]>), ShellError> {
    // (low, high, face, local vertex opposite, forward = runs low -> high)
    let mut half: Vec<(u32, u32, u32, u8, bool)> = Vec::with_capacity(3 * triangles.len());
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            half.push((a.min(b), a.max(b), f as u32, k as u8, a < b));
        }
    }
    half.sort_unstable();
    let mut edges = Vec::with_capacity(half.len() / 2 + 1);
    let mut face_edges = vec![[NONE; 3]; triangles.len()];
    let mut i = 0;
    while i < half.len() {
        let mut j = i + 1;
        while j < half.len() && half[j].0 == half[i].0 && half[j].1 == half[i].1 {
            j += 1;
        }
        let group = &half[i..j];
        let (lo, hi) = (group[0].0, group[0].1);
        if group.len() > 2 {
            return Err(ShellError::NonManifoldEdge {
                a: lo,
                b: hi,
                count: group.len(),
                faces: group.iter().take(3).map(|h| h.2 as usize).collect(),
            });
        }
        if group.len() == 2 && group[0].4 == group[1].4 {
            return Err(ShellError::Orientation {
                first: group[0].2 as usize,
                second: group[1].2 as usize,
                a: lo,
                b: hi,
            });
        }
        // faces[0] is the triangle running low -> high when there is one.
        let first = group.iter().position(|h| h.4).unwrap_or(0);
        let h0 = group[first];
        let v = if h0.4 { [lo, hi] } else { [hi, lo] };
        let opp = |h: &(u32, u32, u32, u8, bool)| triangles[h.2 as usize][h.3 as usize];
        let mut edge = Edge {
            v,
            faces: [h0.2, NONE],
            opposite: [opp(&h0), NONE],
        };
        if group.len() == 2 {
            let h1 = group[1 - first];
            edge.faces[1] = h1.2;
            edge.opposite[1] = opp(&h1);
        }
        let e = edges.len() as u32;
        for h in group {
            face_edges[h.2 as usize][h.3 as usize] = e;
        }
        edges.push(edge);
        i = j;
    }
    Ok((edges, face_edges))
}

/// Refuses a vertex whose triangles form more than one fan joined through its edges.
fn check_fans(
    n: usize,
    triangles: &[[u32; 3]],
    face_edges: &[[u32; 3]],
    edges: &[Edge],
) -> Result<(), ShellError> {
    let mut start = vec![0u32; n + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut faces = vec![0u32; start[n] as usize];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            faces[fill[v as usize] as usize] = f as u32;
            fill[v as usize] += 1;
        }
    }
    let mut parent: Vec<usize> = Vec::new();
    for v in 0..n {
        let around = &faces[start[v] as usize..start[v + 1] as usize];
        parent.clear();
        parent.extend(0..around.len());
        fn root(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        for (k, &f) in around.iter().enumerate() {
            let t = triangles[f as usize];
            for local in 0..3 {
                // The edges of f through v are those opposite its other two vertices.
                if t[local] == v as u32 {
                    continue;
                }
                let e = edges[face_edges[f as usize][local] as usize];
                if e.is_boundary() {
                    continue;
                }
                let other = if e.faces[0] == f {
                    e.faces[1]
                } else {
                    e.faces[0]
                };
                if let Some(m) = around.iter().position(|&g| g == other) {
                    let (a, b) = (root(&mut parent, k), root(&mut parent, m));
                    parent[a] = b;
                }
            }
        }
        let fans = (0..around.len())
            .filter(|&k| root(&mut parent, k) == k)
            .count();
        if fans > 1 {
            return Err(ShellError::NonManifoldVertex { vertex: v, fans });
        }
    }
    Ok(())
}

/// CSR over vertices of the edges whose stencil holds them, in edge order.
fn build_stencils(n: usize, edges: &[Edge]) -> (Vec<u32>, Vec<(u32, Role)>) {
    let members = |e: &Edge| {
        [
            (e.v[0], Role::Start),
            (e.v[1], Role::End),
            (e.opposite[0], Role::Opposite0),
            (e.opposite[1], Role::Opposite1),
        ]
    };
    let mut start = vec![0u32; n + 1];
    for e in edges {
        for (v, _) in members(e) {
            if v != NONE {
                start[v as usize + 1] += 1;
            }
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut stencil = vec![(0u32, Role::Start); start[n] as usize];
    for (k, e) in edges.iter().enumerate() {
        for (v, role) in members(e) {
            if v != NONE {
                stencil[fill[v as usize] as usize] = (k as u32, role);
                fill[v as usize] += 1;
            }
        }
    }
    (start, stencil)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        (v, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn two_triangles_share_one_edge() {
        let (v, t) = square();
        let m = ShellMesh::new(v, t).unwrap();
        assert_eq!(m.edges().len(), 5);
        assert_eq!(m.num_boundary_edges(), 4);
        let inner: Vec<_> = m.edges().iter().filter(|e| !e.is_boundary()).collect();
        assert_eq!(inner.len(), 1);
        let e = inner[0];
        // Triangle 1 (0, 2, 3) runs 0 -> 2, low to high: it is faces[0].
        assert_eq!(e.v, [0, 2]);
        assert_eq!(e.faces, [1, 0]);
        assert_eq!(e.opposite, [3, 1]);
        // Vertex 1 sits in the stencils of its two edges and of the diagonal (opposite).
        assert_eq!(m.stencil(1).len(), 3);
        for (f, t) in m.triangles().iter().enumerate() {
            for k in 0..3 {
                let e = m.edges()[m.face_edges()[f][k] as usize];
                let ends = [t[(k + 1) % 3], t[(k + 2) % 3]];
                assert!(ends.contains(&e.v[0]) && ends.contains(&e.v[1]));
            }
        }
    }

    #[test]
    fn bad_surfaces_are_refused_with_the_reason() {
        let (v, _) = square();
        assert_eq!(ShellMesh::new(v.clone(), vec![]), Err(ShellError::Empty));
        assert!(matches!(
            ShellMesh::new(v.clone(), vec![[0, 1, 4], [0, 2, 3]]),
            Err(ShellError::BadTriangle { face: 0, .. })
        ));
        assert!(matches!(
            ShellMesh::new(v.clone(), vec![[0, 1, 2], [0, 3, 2]]),
            Err(ShellError::Orientation { .. })
        ));
        assert!(matches!(
            ShellMesh::new(v.clone(), vec![[0, 1, 2]]),
            Err(ShellError::Unused { vertex: 3 })
        ));
        let mut flat = v.clone();
        flat[2] = [0.5, 0.0, 0.0];
        assert!(matches!(
            ShellMesh::new(flat, vec![[0, 1, 2], [0, 2, 3]]),
            Err(ShellError::Degenerate { face: 0, .. })
        ));
        let mut nan = v.clone();
        nan[3][1] = f64::NAN;
        assert!(matches!(
            ShellMesh::new(nan, vec![[0, 1, 2], [0, 2, 3]]),
            Err(ShellError::NonFiniteVertex { vertex: 3, .. })
        ));
        // Three triangles on edge 0-1.
        let mut fin = v.clone();
        fin.push([0.5, 0.0, 1.0]);
        fin.push([0.5, 0.0, -1.0]);
        assert!(matches!(
            ShellMesh::new(fin, vec![[0, 1, 2], [1, 0, 4], [0, 1, 5]]),
            Err(ShellError::Unused { .. }) | Err(ShellError::NonManifoldEdge { .. })
        ));
        // Two triangles touching at vertex 0 only.
        let bow = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ];
        assert_eq!(
            ShellMesh::new(bow, vec![[0, 1, 2], [0, 3, 4]]),
            Err(ShellError::NonManifoldVertex { vertex: 0, fans: 2 })
        );
    }

    #[test]
    fn three_triangles_on_one_edge_are_refused() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ];
        let err = ShellMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap_err();
        assert!(matches!(
            err,
            ShellError::NonManifoldEdge {
                a: 0,
                b: 1,
                count: 3,
                ..
            }
        ));
        assert!(err.to_string().contains("edge 0-1"));
    }
}
