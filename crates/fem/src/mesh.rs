//! Straight-sided linear (P1) and quadratic (P2) tet meshes built from plain arrays.

use std::collections::HashMap;

use crate::basis::EDGES;
use crate::error::FemError;
use crate::math::{cross, dot, norm, scale, sub, Vec3};

/// Polynomial order of the elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Order {
    /// 4-node tets, linear shape functions (lock in bending; kept to show it).
    Linear,
    /// 10-node tets, quadratic shape functions, straight sides (edge nodes at midpoints).
    Quadratic,
}

impl Order {
    /// Nodes per element: 4 or 10.
    pub fn nodes_per_element(self) -> usize {
        match self {
            Order::Linear => 4,
            Order::Quadratic => 10,
        }
    }
}

/// A tet mesh with its finite-element nodes.
///
/// Nodes `0..vertex_count()` are the input vertices, in input order; a quadratic mesh appends
/// one node per unique edge at its midpoint, numbered in order of first appearance (tet by tet,
/// edge by edge in [`crate::EDGES`] order). Element `e` is built on input tet `e`; its nodes
/// are the four corners then, for P2, the six edge nodes in [`crate::EDGES`] order.
#[derive(Debug, Clone)]
pub struct Mesh {
    order: Order,
    nodes: Vec<Vec3>,
    vertex_count: usize,
    elements: Vec<u32>,
    tets: Vec<[u32; 4]>,
    grad_l: Vec<[Vec3; 4]>,
    volumes: Vec<f64>,
}

impl Mesh {
    /// Linear (4-node) mesh of the tets over the vertices (m). Every tet must be positively
    /// oriented (`(v1 - v0) . ((v2 - v0) x (v3 - v0)) > 0`) and not degenerate; an inverted
    /// tet is an error, not silently reoriented.
    pub fn linear(vertices: Vec<Vec3>, tets: Vec<[u32; 4]>) -> Result<Self, FemError> {
        let (grad_l, volumes) = geometry(&vertices, &tets)?;
        let elements = tets.iter().flatten().copied().collect();
        Ok(Self {
            order: Order::Linear,
            vertex_count: vertices.len(),
            nodes: vertices,
            elements,
            tets,
            grad_l,
            volumes,
        })
    }

    /// Quadratic (10-node) mesh: as [`Mesh::linear`], plus one node at the midpoint of every
    /// unique edge (straight-sided elements).
    pub fn quadratic(vertices: Vec<Vec3>, tets: Vec<[u32; 4]>) -> Result<Self, FemError> {
        let (grad_l, volumes) = geometry(&vertices, &tets)?;
        let vertex_count = vertices.len();
        let mut nodes = vertices;
        let mut edge_node: HashMap<(u32, u32), u32> = HashMap::with_capacity(tets.len() * 2);
        let mut elements = Vec::with_capacity(tets.len() * 10);
        for tet in &tets {
            elements.extend_from_slice(tet);
            for [a, b] in EDGES {
                let key = (tet[a].min(tet[b]), tet[a].max(tet[b]));
                let id = *edge_node.entry(key).or_insert_with(|| {
                    let (pa, pb) = (nodes[key.0 as usize], nodes[key.1 as usize]);
                    nodes.push([
                        0.5 * (pa[0] + pb[0]),
                        0.5 * (pa[1] + pb[1]),
                        0.5 * (pa[2] + pb[2]),
                    ]);
                    (nodes.len() - 1) as u32
                });
                elements.push(id);
            }
        }
        Ok(Self {
            order: Order::Quadratic,
            nodes,
            vertex_count,
            elements,
            tets,
            grad_l,
            volumes,
        })
    }

    /// Element order.
    pub fn order(&self) -> Order {
        self.order
    }

    /// Rest positions of all nodes (m).
    pub fn nodes(&self) -> &[Vec3] {
        &self.nodes
    }

    /// Number of nodes (vertices plus, for P2, edge nodes).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of input vertices (the first nodes).
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Number of elements (= input tets).
    pub fn element_count(&self) -> usize {
        self.tets.len()
    }

    /// Nodes per element (4 or 10).
    pub fn nodes_per_element(&self) -> usize {
        self.order.nodes_per_element()
    }

    /// Node ids of element `e` (4 or 10 of them).
    pub fn element(&self, e: usize) -> &[u32] {
        let n = self.nodes_per_element();
        &self.elements[e * n..(e + 1) * n]
    }

    /// All elements' node ids, `nodes_per_element()` per element.
    pub fn elements(&self) -> &[u32] {
        &self.elements
    }

    /// The input tets (corner vertex ids).
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }

    /// Volume of each element (m^3).
    pub fn volumes(&self) -> &[f64] {
        &self.volumes
    }

    /// Gradients (1/m) of the four barycentric coordinates of element `e`.
    pub fn barycentric_gradients(&self, e: usize) -> &[Vec3; 4] {
        &self.grad_l[e]
    }

    /// Barycentric coordinates of the point `p` (m) with respect to element `e`'s corners.
    pub fn barycentric(&self, e: usize, p: Vec3) -> [f64; 4] {
        let g = &self.grad_l[e];
        let d = sub(p, self.nodes[self.tets[e][0] as usize]);
        let l1 = dot(g[1], d);
        let l2 = dot(g[2], d);
        let l3 = dot(g[3], d);
        [1.0 - l1 - l2 - l3, l1, l2, l3]
    }
}

/// Barycentric gradients and volumes of the tets, checking ids, finiteness and orientation.
fn geometry(vertices: &[Vec3], tets: &[[u32; 4]]) -> Result<(Vec<[Vec3; 4]>, Vec<f64>), FemError> {
    if tets.is_empty() {
        return Err(FemError::EmptyMesh);
    }
    if let Some((vertex, &position)) = vertices
        .iter()
        .enumerate()
        .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
    {
        return Err(FemError::NonFiniteVertex { vertex, position });
    }
    let mut grads = Vec::with_capacity(tets.len());
    let mut volumes = Vec::with_capacity(tets.len());
    for (t, tet) in tets.iter().enumerate() {
        if let Some(&v) = tet.iter().find(|&&v| v as usize >= vertices.len()) {
            return Err(FemError::VertexOutOfRange {
                tet: t,
                vertex: v,
                count: vertices.len(),
            });
        }
        let p = tet.map(|v| vertices[v as usize]);
        let e = [sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0])];
        let six_v = dot(e[0], cross(e[1], e[2]));
        let longest = [
            e[0],
            e[1],
            e[2],
            sub(p[2], p[1]),
            sub(p[3], p[1]),
            sub(p[3], p[2]),
        ]
        .into_iter()
        .map(norm)
        .fold(0.0, f64::max);
        let volume = six_v / 6.0;
        if six_v.abs() <= 1e-12 * longest.powi(3) {
            return Err(FemError::DegenerateTet { tet: t, volume });
        }
        if six_v < 0.0 {
            return Err(FemError::InvertedTet { tet: t, volume });
        }
        let s = 1.0 / six_v;
        let g1 = scale(cross(e[1], e[2]), s);
        let g2 = scale(cross(e[2], e[0]), s);
        let g3 = scale(cross(e[0], e[1]), s);
        let g0 = [
            -(g1[0] + g2[0] + g3[0]),
            -(g1[1] + g2[1] + g3[1]),
            -(g1[2] + g2[2] + g3[2]),
        ];
        grads.push([g0, g1, g2, g3]);
        volumes.push(volume);
    }
    Ok((grads, volumes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tet() -> (Vec<Vec3>, Vec<[u32; 4]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ],
            vec![[0, 1, 2, 3], [1, 2, 3, 4]],
        )
    }

    #[test]
    fn quadratic_mesh_shares_edge_nodes() {
        let (v, t) = unit_tet();
        let m = Mesh::quadratic(v, t).unwrap();
        // 5 vertices + 6 + 6 edges - 3 shared edges (1-2, 1-3, 2-3).
        assert_eq!(m.node_count(), 5 + 9);
        assert!((m.volumes()[0] - 1.0 / 6.0).abs() < 1e-15);
        let l = m.barycentric(0, [0.1, 0.2, 0.3]);
        assert!((l[0] - 0.4).abs() < 1e-15 && (l[3] - 0.3).abs() < 1e-15);
    }

    #[test]
    fn bad_tets_are_named() {
        let (v, t) = unit_tet();
        assert_eq!(
            Mesh::linear(v.clone(), vec![t[0], [0, 2, 1, 3]]).unwrap_err(),
            FemError::InvertedTet {
                tet: 1,
                volume: -1.0 / 6.0
            }
        );
        assert!(matches!(
            Mesh::linear(v.clone(), vec![[0, 1, 2, 7]]),
            Err(FemError::VertexOutOfRange {
                tet: 0,
                vertex: 7,
                ..
            })
        ));
        assert!(matches!(
            Mesh::linear(v, vec![[0, 1, 2, 0]]),
            Err(FemError::DegenerateTet { tet: 0, .. })
        ));
    }
}
