//! Static linear elasticity: sparse stiffness on the free DOFs, consistent body load, sparse
//! Cholesky (faer, AMD ordering).

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::LltError;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{MatMut, Side};
use rayon::prelude::*;

use crate::basis::{Basis, P1, P2};
use crate::element::{self, Lame};
use crate::error::FemError;
use crate::math::{add, Vec3};
use crate::mesh::{Mesh, Order};
use crate::problem::Problem;

/// Elements whose local stiffness matrices are held at once during assembly.
const CHUNK: usize = 2048;
const CONSTRAINED: u32 = u32::MAX;

/// A static solution.
#[derive(Debug, Clone)]
pub struct Solution {
    /// Displacement (m) of every node.
    pub displacements: Vec<Vec3>,
    /// Number of free degrees of freedom solved for.
    pub free_dofs: usize,
}

impl Solution {
    /// Current positions (m): rest positions of `mesh` plus displacements.
    pub fn positions(&self, mesh: &Mesh) -> Vec<Vec3> {
        mesh.nodes()
            .iter()
            .zip(&self.displacements)
            .map(|(&x, &u)| add(x, u))
            .collect()
    }
}

/// Static linear-elastic solution with prescribed motions evaluated at time 0; see
/// [`static_linear_at`].
pub fn static_linear(problem: &Problem) -> Result<Solution, FemError> {
    static_linear_at(problem, 0.0)
}

/// Static linear-elastic solution `K u = f` where `f` is the consistent load of the body force
/// `density * gravity` (exact quadrature) and constrained nodes have displacement
/// `held_position(node, time) - X` (zero for fixed ones).
///
/// Fails with [`FemError::NotPositiveDefinite`] when the constraints leave a rigid motion free.
pub fn static_linear_at(problem: &Problem, time: f64) -> Result<Solution, FemError> {
    match problem.mesh().order() {
        Order::Linear => solve::<4, P1>(problem, time),
        Order::Quadratic => solve::<10, P2>(problem, time),
    }
}

fn solve<const N: usize, B: Basis<N>>(problem: &Problem, time: f64) -> Result<Solution, FemError> {
    let mesh = problem.mesh();
    let n_nodes = mesh.node_count();
    // Free DOF numbering, increasing with the global DOF 3 * node + component.
    let mut free = vec![CONSTRAINED; 3 * n_nodes];
    let mut held = vec![[0.0; 3]; n_nodes];
    let mut count = 0u32;
    for node in 0..n_nodes {
        match problem.held_position(node, time) {
            Some(p) => {
                let x = mesh.nodes()[node];
                held[node] = [p[0] - x[0], p[1] - x[1], p[2] - x[2]];
            }
            None => {
                for d in 0..3 {
                    free[3 * node + d] = count;
                    count += 1;
                }
            }
        }
    }
    let n_free = count as usize;
    if n_free == 0 {
        return Err(FemError::Solver(
            "every degree of freedom is constrained".into(),
        ));
    }
    let (col_ptr, row_idx) = lower_pattern(mesh, &free, n_free);
    let mut values = vec![0.0; row_idx.len()];
    let mut rhs = vec![0.0; n_free];

    // Consistent body load.
    let material = problem.material();
    let g = problem.gravity();
    for e in 0..mesh.element_count() {
        let load = element::load::<N, B>(mesh.volumes()[e]);
        for (a, &node) in mesh.element(e).iter().enumerate() {
            for d in 0..3 {
                let r = free[3 * node as usize + d];
                if r != CONSTRAINED {
                    rhs[r as usize] += material.density * g[d] * load[a];
                }
            }
        }
    }

    // Stiffness: local matrices in parallel per chunk, then a serial scatter in element order.
    let lame = Lame {
        lambda: material.lambda(),
        mu: material.mu(),
    };
    let n3 = 3 * N;
    let mut local = vec![0.0; CHUNK.min(mesh.element_count()) * n3 * n3];
    for start in (0..mesh.element_count()).step_by(CHUNK) {
        let end = (start + CHUNK).min(mesh.element_count());
        let buf = &mut local[..(end - start) * n3 * n3];
        buf.par_chunks_mut(n3 * n3).enumerate().for_each(|(i, k)| {
            let e = start + i;
            element::stiffness::<N, B>(mesh.barycentric_gradients(e), mesh.volumes()[e], lame, k);
        });
        for (i, k) in buf.chunks(n3 * n3).enumerate() {
            let conn = mesh.element(start + i);
            for a in 0..N {
                for i_d in 0..3 {
                    let r = free[3 * conn[a] as usize + i_d];
                    if r == CONSTRAINED {
                        continue;
                    }
                    for b in 0..N {
                        let nb = conn[b] as usize;
                        for j_d in 0..3 {
                            let kv = k[(3 * a + i_d) * n3 + 3 * b + j_d];
                            let c = free[3 * nb + j_d];
                            if c == CONSTRAINED {
                                rhs[r as usize] -= kv * held[nb][j_d];
                            } else if r >= c {
                                let (lo, hi) = (
                                    col_ptr[c as usize] as usize,
                                    col_ptr[c as usize + 1] as usize,
                                );
                                let pos = row_idx[lo..hi]
                                    .binary_search(&r)
                                    .expect("pattern holds every element pair");
                                values[lo + pos] += kv;
                            }
                        }
                    }
                }
            }
        }
    }

    let symbolic = SymbolicSparseColMat::new_checked(n_free, n_free, col_ptr, None, row_idx);
    let k = SparseColMat::<u32, f64>::new(symbolic, values);
    let llt = k.sp_cholesky(Side::Lower).map_err(|e| match e {
        LltError::Numeric(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot {
            index,
        }) => FemError::NotPositiveDefinite {
            pivot: index,
            free: n_free,
        },
        other => FemError::Solver(format!("{other:?}")),
    })?;
    llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut rhs, n_free, 1));

    let mut displacements = held;
    for (node, u) in displacements.iter_mut().enumerate() {
        for (d, ud) in u.iter_mut().enumerate() {
            let r = free[3 * node + d];
            if r != CONSTRAINED {
                *ud = rhs[r as usize];
            }
        }
    }
    if displacements.iter().flatten().any(|v| !v.is_finite()) {
        return Err(FemError::Solver("the solution is not finite".into()));
    }
    Ok(Solution {
        displacements,
        free_dofs: n_free,
    })
}

/// Lower-triangle CSC pattern (column pointers, sorted row indices) of the stiffness on the
/// free DOFs: DOFs of nodes that share an element.
fn lower_pattern(mesh: &Mesh, free: &[u32], n_free: usize) -> (Vec<u32>, Vec<u32>) {
    let n_nodes = mesh.node_count();
    let npe = mesh.nodes_per_element();
    let conn = mesh.elements();
    let mut offsets = vec![0usize; n_nodes + 1];
    for &n in conn {
        offsets[n as usize + 1] += 1;
    }
    for i in 0..n_nodes {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut node_elems = vec![0u32; conn.len()];
    for (slot, &n) in conn.iter().enumerate() {
        node_elems[fill[n as usize]] = (slot / npe) as u32;
        fill[n as usize] += 1;
    }
    let neighbours: Vec<Vec<u32>> = (0..n_nodes)
        .into_par_iter()
        .map(|n| {
            let mut nb: Vec<u32> = node_elems[offsets[n]..offsets[n + 1]]
                .iter()
                .flat_map(|&e| mesh.element(e as usize).iter().copied())
                .filter(|&m| m as usize >= n)
                .collect();
            nb.sort_unstable();
            nb.dedup();
            nb
        })
        .collect();
    let mut col_ptr = Vec::with_capacity(n_free + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0u32);
    for (n, nb) in neighbours.iter().enumerate() {
        for d in 0..3 {
            let c = free[3 * n + d];
            if c == CONSTRAINED {
                continue;
            }
            for &m in nb {
                for e in 0..3 {
                    let r = free[3 * m as usize + e];
                    if r != CONSTRAINED && r >= c {
                        row_idx.push(r);
                    }
                }
            }
            col_ptr.push(u32::try_from(row_idx.len()).expect("fewer than 2^32 nonzeros"));
        }
    }
    (col_ptr, row_idx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;

    fn cube() -> Problem {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let t = vec![[0, 1, 2, 3], [1, 2, 3, 4]];
        let mesh = Mesh::quadratic(v, t).unwrap();
        Problem::new(mesh, Material::new(1e6, 0.25, 1000.0).unwrap()).unwrap()
    }

    #[test]
    fn unheld_body_is_reported() {
        let mut p = cube();
        assert!(matches!(
            static_linear(&p),
            Err(FemError::NotPositiveDefinite { .. } | FemError::Solver(_))
        ));
        p.fix_where(|_| true);
        assert!(matches!(static_linear(&p), Err(FemError::Solver(_))));
    }

    #[test]
    fn held_body_without_load_stays_at_rest() {
        let mut p = cube();
        p.fix_where(|x| x[2] == 0.0);
        let s = static_linear(&p).unwrap();
        assert!(s.displacements.iter().flatten().all(|&u| u.abs() < 1e-300));
    }
}
