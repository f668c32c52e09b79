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

/// A peridynamic body ready to integrate, and facts for the report.
pub(crate) struct Body {
    /// Rest positions of the particles (m).
    pub rest: Vec<Vec3>,
    /// Horizon (m).
    pub horizon: f64,
    /// Directed bonds.
    pub bonds: usize,
    /// The model.
    pub model: ChenModel,
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
    let (mesh, _) = TetMesh::new(v, t).map_err(|e| BenchError::Mesh {
        case: case.into(),
        message: e.to_string(),
    })?;
    let physics = |source| BenchError::Physics {
        case: case.into(),
        source,
    };
    let horizon = k * mesh.mean_edge_length();
    let rest = mesh.rest_barycentres();
    let (disc, report) =
        Discretization::from_tets(&rest, &mesh.rest_volumes(), mesh.neighbours(), horizon)
            .map_err(physics)?;
    let model = ChenModel::new(disc, std::slice::from_ref(material)).map_err(physics)?;
    Ok(Body {
        rest,
        horizon,
        bonds: report.bonds,
        model,
    })
}

/// A bar along x from 0 to `length` with a square section `side` (m, centred on the axis), `nx`
/// cells along and `nx / 10` across, plus a clamp layer of whole cells at least one horizon
/// (`k` mean edges) thick behind x = 0. Returns the body and the clamp layer's particles.
pub(crate) fn clamped_bar(
    case: &str,
    length: f64,
    side: f64,
    nx: usize,
    k: f64,
    material: &ChenMaterial,
) -> Result<(Body, Vec<u32>), BenchError> {
    let n = (nx / 10).max(1);
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
    /// An explicit solver at 0.8 of the estimated stable step.
    pub fn solver(self, case: &str, loads: Loads) -> Result<Explicit<ChenModel>, BenchError> {
        let config = ExplicitConfig {
            dt: TimeStep::Auto { safety: 0.8 },
            guard_fraction: 0.5,
        };
        Explicit::new(self.model, &self.rest, self.horizon, loads, config).map_err(|source| {
            BenchError::Physics {
                case: case.into(),
                source,
            }
        })
    }

    /// Indices of the particles whose rest position passes `select`.
    pub fn select(&self, select: impl Fn(Vec3) -> bool) -> Vec<u32> {
        (0..self.rest.len() as u32)
            .filter(|&i| select(self.rest[i as usize]))
            .collect()
    }
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
