//! Static linear elasticity: sparse stiffness on the free DOFs, consistent body load, sparse
//! Cholesky (faer, AMD ordering).

use faer::linalg::solvers::Solve;
use faer::{MatMut, Side};
use rayon::prelude::*;

use crate::assembly::{cholesky_error, FreeDofs, LowerPattern, CHUNK, CONSTRAINED};
use crate::basis::{Basis, P1, P2};
use crate::element::{self, Lame};
use crate::error::FemError;
use crate::math::{add, Vec3};
use crate::mesh::{Mesh, Order};
use crate::problem::Problem;

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
    let free = FreeDofs::new(problem)?;
    let n_free = free.count;
    let mut held = vec![[0.0; 3]; n_nodes];
    for (node, h) in held.iter_mut().enumerate() {
        if let Some(p) = problem.held_position(node, time) {
            let x = mesh.nodes()[node];
            *h = [p[0] - x[0], p[1] - x[1], p[2] - x[2]];
        }
    }
    let pattern = LowerPattern::new(mesh, &free);
    let mut values = vec![0.0; pattern.len()];
    let mut rhs = vec![0.0; n_free];

    // Consistent body load.
    let material = problem.material();
    let g = problem.gravity();
    for e in 0..mesh.element_count() {
        let load = element::load::<N, B>(mesh.volumes()[e]);
        for (a, &node) in mesh.element(e).iter().enumerate() {
            for (d, gd) in g.iter().enumerate() {
                let r = free.index[3 * node as usize + d];
                if r != CONSTRAINED {
                    rhs[r as usize] += material.density * gd * load[a];
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
            pattern.add_element(
                &mut values,
                k,
                mesh.element(start + i),
                &free.index,
                |r, nb, j, kv| rhs[r] -= kv * held[nb][j],
            );
        }
    }

    let k = pattern.matrix(&values);
    let llt = k
        .sp_cholesky(Side::Lower)
        .map_err(|e| cholesky_error(e, n_free))?;
    llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut rhs, n_free, 1));

    let mut displacements = held;
    for (node, u) in displacements.iter_mut().enumerate() {
        for (d, ud) in u.iter_mut().enumerate() {
            let r = free.index[3 * node + d];
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
