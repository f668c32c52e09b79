//! Peridynamic bars on Kuhn-lattice boxes, shared by the accuracy cases: building the model,
//! picking particles, fitting.

use perifrac_physics::{
    ChenMaterial, ChenModel, Discretization, Explicit, ExplicitConfig, Loads, TimeStep, Vec3,
};
use perifrac_topology::primitives::box_data;
use perifrac_topology::TetMesh;

use crate::error::BenchError;

/// An upper bound on the mean edge length of a Kuhn lattice over its cube side: the 7 edges a
/// cube owns in an infinite lattice (3 sides, 3 face diagonals, a body diagonal) average 1.282;
/// a finite box has more side edges on its boundary and averages less (1.262 for a 20 x 4 x 20
/// slab).
pub(crate) const KUHN_EDGE_PER_CELL: f64 = 1.3;

/// A peridynamic body ready to integrate; its rest positions, horizon and bonds are the
/// model's.
pub(crate) struct Body {
    /// The model.
    pub model: ChenModel,
}

/// `v, t` as a tet mesh, its refusal as a [`BenchError::Mesh`] of `case`.
pub(crate) fn tet_mesh(case: &str, v: Vec<Vec3>, t: Vec<[u32; 4]>) -> Result<TetMesh, BenchError> {
    let (mesh, _) = TetMesh::new(v, t).map_err(|e| BenchError::Mesh {
        case: case.into(),
        message: e.to_string(),
    })?;
    Ok(mesh)
}

/// `mesh` as a peridynamic body of `material`, one particle per tet, with horizon `k` times
/// the mesh's mean edge length.
pub(crate) fn mesh_body(
    case: &str,
    mesh: &TetMesh,
    k: f64,
    material: &ChenMaterial,
) -> Result<Body, BenchError> {
    let physics = |cause| BenchError::Physics {
        case: case.into(),
        cause,
    };
    let horizon = k * mesh.mean_edge_length();
    let rest = mesh.rest_barycentres();
    let (disc, _) =
        Discretization::from_tets(&rest, &mesh.rest_volumes(), mesh.neighbours(), horizon)
            .map_err(physics)?;
    let model = ChenModel::new(disc, std::slice::from_ref(material)).map_err(physics)?;
    Ok(Body { model })
}

/// The box `[min, max]` in `cells` Kuhn cells as a peridynamic body of `material` with
/// horizon `k` times the mesh's mean edge length.
pub(crate) fn body(
    case: &str,
    min: Vec3,
    max: Vec3,
    cells: [usize; 3],
    k: f64,
    material: &ChenMaterial,
) -> Result<Body, BenchError> {
    let (v, t) = box_data(min, max, cells);
    mesh_body(case, &tet_mesh(case, v, t)?, k, material)
}

/// Cells across the section of a bar of `nx` cells along: `nx / 10`, at least one.
pub(crate) fn cells_across(nx: usize) -> usize {
    (nx / 10).max(1)
}

/// A bar along x from 0 to `length` with a square section `side` (m, centred on the axis), `nx`
/// cells along and [`cells_across`] across, plus a clamp layer of whole cells at least one
/// horizon (`k` mean edges) thick behind x = 0. Returns the body and the clamp layer's
/// particles.
pub(crate) fn clamped_bar(
    case: &str,
    length: f64,
    side: f64,
    nx: usize,
    k: f64,
    material: &ChenMaterial,
) -> Result<(Body, Vec<u32>), BenchError> {
    let n = cells_across(nx);
    let h = length / nx as f64;
    let clamp = (k * KUHN_EDGE_PER_CELL).ceil() as usize;
    let b = body(
        case,
        [-(clamp as f64) * h, -side / 2.0, -side / 2.0],
        [length, side / 2.0, side / 2.0],
        [nx + clamp, n, n],
        k,
        material,
    )?;
    let held = b.select(|x| x[0] < 0.0);
    Ok((b, held))
}

/// A box `[0, size]` of `cells` cells: [`body`] for the cases that start at the origin.
pub(crate) fn block(
    case: &str,
    size: Vec3,
    cells: [usize; 3],
    k: f64,
    material: &ChenMaterial,
) -> Result<Body, BenchError> {
    body(case, [0.0; 3], size, cells, k, material)
}

impl Body {
    /// Rest positions of the particles (m).
    pub fn rest(&self) -> &[Vec3] {
        self.model.discretization().rest_positions()
    }

    /// Horizon (m).
    pub fn horizon(&self) -> f64 {
        self.model.discretization().horizon()
    }

    /// Directed bonds.
    pub fn bonds(&self) -> usize {
        self.model.discretization().family().num_bonds()
    }

    /// An explicit solver at 0.8 of the estimated stable step.
    pub fn solver(self, case: &str, loads: Loads) -> Result<Explicit<ChenModel>, BenchError> {
        self.solver_at(case, loads, TimeStep::Auto { safety: 0.8 })
    }

    /// An explicit solver with time step `dt`.
    pub fn solver_at(
        self,
        case: &str,
        loads: Loads,
        dt: TimeStep,
    ) -> Result<Explicit<ChenModel>, BenchError> {
        let config = ExplicitConfig {
            dt,
            guard_fraction: 0.5,
        };
        let rest = self.rest().to_vec();
        let horizon = self.horizon();
        Explicit::new(self.model, &rest, horizon, loads, config).map_err(|cause| {
            BenchError::Physics {
                case: case.into(),
                cause,
            }
        })
    }

    /// Indices of the particles whose rest position passes `select`.
    pub fn select(&self, select: impl Fn(Vec3) -> bool) -> Vec<u32> {
        let rest = self.rest();
        (0..rest.len() as u32)
            .filter(|&i| select(rest[i as usize]))
            .collect()
    }
}

/// Rest positions of the particles of `s` (m).
pub(crate) fn rest_of(s: &Explicit<ChenModel>) -> &[Vec3] {
    s.model().discretization().rest_positions()
}

/// Sets the velocity of every particle of `s` to `velocity` at its rest position.
pub(crate) fn set_velocities(s: &mut Explicit<ChenModel>, velocity: impl Fn(Vec3) -> Vec3) {
    let v: Vec<Vec3> = rest_of(s).iter().map(|&x| velocity(x)).collect();
    s.velocities_mut().copy_from_slice(&v);
}

/// Least-squares line `v = a + b u`: returns `(a, b)`.
pub(crate) fn fit_line(u: &[f64], v: &[f64]) -> (f64, f64) {
    let n = u.len() as f64;
    let (mu, mv) = (u.iter().sum::<f64>() / n, v.iter().sum::<f64>() / n);
    let cov: f64 = u.iter().zip(v).map(|(a, b)| (a - mu) * (b - mv)).sum();
    let var: f64 = u.iter().map(|a| (a - mu) * (a - mu)).sum();
    let b = cov / var;
    (mv - b * mu, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kuhn_edge_ratio_is_bounded() {
        for cells in [[2, 2, 2], [10, 10, 10], [40, 4, 4]] {
            let (v, t) = box_data([0.0; 3], cells.map(|c| c as f64), cells);
            let (mesh, _) = TetMesh::new(v, t).unwrap();
            let ratio = mesh.mean_edge_length();
            assert!(
                ratio > 1.2 && ratio < KUHN_EDGE_PER_CELL,
                "{cells:?}: {ratio}"
            );
        }
    }

    #[test]
    fn fit_line_recovers_a_line() {
        let u = [0.0, 1.0, 2.0, 3.0];
        let v: Vec<f64> = u.iter().map(|x| 2.0 - 0.5 * x).collect();
        let (a, b) = fit_line(&u, &v);
        assert!((a - 2.0).abs() < 1e-14 && (b + 0.5).abs() < 1e-14);
    }
}
