//! Peridynamic bars on Kuhn-lattice boxes, shared by the accuracy cases: building the model
//! (Chen's or Xu's, through [`PdMaterial`]), picking particles, fitting.

use perifrac_physics::{
    stable_frequency, ChenMaterial, ChenModel, ChenOptions, Curve, Discretization, Explicit,
    ExplicitConfig, ForceModel, GhostFit, GhostPlane, GhostReport, Ghosted, Implicit,
    ImplicitConfig, Integrator, Loads, PhysicsError, QuasiNewtonModel, Simulation, TimeStep, Vec3,
    XuMaterial, XuModel, XuModuli, XuOptions,
};
use perifrac_topology::mesher::box_cut_data;
pub(crate) use perifrac_topology::mesher::BoxCut as Cut;
use perifrac_topology::primitives::Lattice;
use perifrac_topology::TetMesh;

use crate::error::BenchError;

/// Seed of the bench's unstructured bars' points (the scenes' default, `defaults::MESH_SEED`).
pub(crate) const UNSTRUCTURED_SEED: u64 = 1;

/// The Kuhn lattice, the mesh of the accuracy cases' long-standing rows.
pub(crate) const KUHN: Cut = Cut::Lattice(Lattice::Kuhn);

/// An upper bound on the mean edge length of a Kuhn lattice over its cube side: the 7 edges a
/// cube owns in an infinite lattice (3 sides, 3 face diagonals, a body diagonal) average 1.282;
/// a finite box has more side edges on its boundary and averages less (1.262 for a 20 x 4 x 20
/// slab).
pub(crate) const KUHN_EDGE_PER_CELL: f64 = 1.3;

/// A material the harness can build a force model of: Chen's ([`ChenMaterial`]) or Xu's
/// ([`XuMaterial`], with the default options: constant influence, no inversion guard).
pub(crate) trait PdMaterial {
    /// The model this material makes.
    type Model: ForceModel;

    /// The model of this one material over `disc`.
    fn model(&self, disc: Discretization) -> Result<Self::Model, PhysicsError>;

    /// What the build of `model`'s ghosts found, when it has ghosts.
    fn ghosts(model: &Self::Model) -> Option<GhostReport> {
        let _ = model;
        None
    }
}

/// Chen's material with the scalar calibration (`correction = "calibrated"`): the tables'
/// "PD" rows, measured before the fitted dilatation became the default.
impl PdMaterial for ChenMaterial {
    type Model = ChenModel;

    fn model(&self, disc: Discretization) -> Result<ChenModel, PhysicsError> {
        let options = ChenOptions {
            fitted_dilatation: false,
            ..ChenOptions::default()
        };
        ChenModel::with_options(disc, std::slice::from_ref(self), options)
    }
}

/// Chen's material with the fitted dilatation (`ChenOptions::fitted_dilatation`, the default).
#[derive(Debug, Clone)]
pub(crate) struct FittedChen(pub ChenMaterial);

impl PdMaterial for FittedChen {
    type Model = ChenModel;

    fn model(&self, disc: Discretization) -> Result<ChenModel, PhysicsError> {
        let options = ChenOptions {
            fitted_dilatation: true,
            ..ChenOptions::default()
        };
        ChenModel::with_options(disc, std::slice::from_ref(&self.0), options)
    }
}

/// Chen's material with the fitted dilatation over families completed by ghosts across
/// `planes` (`perifrac_physics::ghost`), extrapolated as `fit` says.
#[derive(Debug, Clone)]
pub(crate) struct GhostedChen {
    /// The material.
    pub material: ChenMaterial,
    /// The faces mirrored, in the bar's own coordinates.
    pub planes: Vec<GhostPlane>,
    /// Affine or quadratic ghosts.
    pub fit: GhostFit,
}

impl PdMaterial for GhostedChen {
    type Model = Ghosted<ChenModel>;

    fn model(&self, disc: Discretization) -> Result<Ghosted<ChenModel>, PhysicsError> {
        let m = std::slice::from_ref(&self.material);
        Ghosted::chen(disc, m, ChenOptions::default(), &self.planes, self.fit)
    }

    fn ghosts(model: &Ghosted<ChenModel>) -> Option<GhostReport> {
        Some(model.layer().report().clone())
    }
}

/// Xu's neo-Hookean-like material (`g = h = A1`) with Young's modulus `young` (Pa), Poisson's
/// ratio `poisson` and density (kg/m^3), by the consistent conversion of the moduli.
pub(crate) fn xu_neo_hookean(
    case: &str,
    young: f64,
    poisson: f64,
    density: f64,
) -> Result<XuMaterial, BenchError> {
    XuMaterial::from_young_poisson(
        young,
        poisson,
        density,
        Curve::NeoHookean,
        Curve::NeoHookean,
        XuModuli::Consistent,
    )
    .map_err(|cause| BenchError::Physics {
        case: case.into(),
        cause,
    })
}

impl PdMaterial for XuMaterial {
    type Model = XuModel;

    fn model(&self, disc: Discretization) -> Result<XuModel, PhysicsError> {
        XuModel::new(disc, std::slice::from_ref(self), XuOptions::default())
    }
}

/// A peridynamic body ready to integrate; its rest positions, horizon and bonds are the
/// model's.
pub(crate) struct Body<M = ChenModel> {
    /// The model.
    pub model: M,
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
pub(crate) fn mesh_body<T: PdMaterial>(
    case: &str,
    mesh: &TetMesh,
    k: f64,
    material: &T,
) -> Result<Body<T::Model>, BenchError> {
    let physics = |cause| BenchError::Physics {
        case: case.into(),
        cause,
    };
    let horizon = k * mesh.mean_edge_length();
    let rest = mesh.rest_barycentres();
    let (disc, _) =
        Discretization::from_tets(&rest, &mesh.rest_volumes(), mesh.neighbours(), horizon)
            .map_err(physics)?;
    let model = material.model(disc).map_err(physics)?;
    Ok(Body { model })
}

/// The box `[min, max]` in `cells` cells, cut as `cut` says, as a peridynamic body of
/// `material` with horizon `k` times the mesh's mean edge length.
pub(crate) fn cut_body<T: PdMaterial>(
    case: &str,
    min: Vec3,
    max: Vec3,
    cells: [usize; 3],
    k: f64,
    material: &T,
    cut: Cut,
) -> Result<Body<T::Model>, BenchError> {
    let (v, t) = box_cut_data(min, max, cells, cut).map_err(|e| BenchError::Mesh {
        case: case.into(),
        message: e.to_string(),
    })?;
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
pub(crate) fn clamped_bar<T: PdMaterial>(
    case: &str,
    length: f64,
    side: f64,
    nx: usize,
    k: f64,
    material: &T,
    cut: Cut,
) -> Result<(Body<T::Model>, Vec<u32>), BenchError> {
    let b = held_bar(case, length, side, nx, k, material, false, cut)?;
    Ok((b.body, b.clamp))
}

/// A bar held at its ends: the body, the clamp layer behind x = 0 and, when asked for, a
/// layer of the same depth beyond x = `length` (the end a motion turns).
pub(crate) struct HeldBar<M> {
    /// The body, layers included.
    pub body: Body<M>,
    /// Particles of the layer behind x = 0 (rest x < 0).
    pub clamp: Vec<u32>,
    /// Particles of the layer beyond the far end (rest x > `length`); empty without one.
    pub end: Vec<u32>,
}

/// [`clamped_bar`], with a second layer of the clamp's depth beyond x = `length` when
/// `end_layer`: the bar proper, 0 < x < `length`, then has a layer one horizon thick at each
/// end to hold or move, as a finite-element bar's end faces are.
// The bar's shape, resolution, horizon, material, end layer and mesh are each a case's own.
#[allow(clippy::too_many_arguments)]
pub(crate) fn held_bar<T: PdMaterial>(
    case: &str,
    length: f64,
    side: f64,
    nx: usize,
    k: f64,
    material: &T,
    end_layer: bool,
    cut: Cut,
) -> Result<HeldBar<T::Model>, BenchError> {
    let n = cells_across(nx);
    let h = length / nx as f64;
    let clamp = (k * KUHN_EDGE_PER_CELL).ceil() as usize;
    let far = if end_layer { clamp } else { 0 };
    let body = cut_body(
        case,
        [-(clamp as f64) * h, -side / 2.0, -side / 2.0],
        [length + far as f64 * h, side / 2.0, side / 2.0],
        [nx + clamp + far, n, n],
        k,
        material,
        cut,
    )?;
    let clamp = body.select(|x| x[0] < 0.0);
    let end = if end_layer {
        body.select(|x| x[0] > length)
    } else {
        Vec::new()
    };
    Ok(HeldBar { body, clamp, end })
}

/// A box `[0, size]` of `cells` cells: [`cut_body`] on the Kuhn lattice, for the cases that
/// start at the origin.
pub(crate) fn block<T: PdMaterial>(
    case: &str,
    size: Vec3,
    cells: [usize; 3],
    k: f64,
    material: &T,
) -> Result<Body<T::Model>, BenchError> {
    cut_body(case, [0.0; 3], size, cells, k, material, KUHN)
}

impl<M: ForceModel> Body<M> {
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
    pub fn solver(self, case: &str, loads: Loads) -> Result<Explicit<M>, BenchError> {
        self.solver_at(case, loads, TimeStep::Auto { safety: 0.8 })
    }

    /// An explicit solver whose step divides `interval` (s) into whole steps: the largest such
    /// step at or under 0.8 of the estimated stable one, so that runs compared at sample times
    /// reach each sample exactly (whole steps of the unrounded step would pass the k-th sample
    /// by up to k steps).
    pub fn solver_dividing(
        mut self,
        case: &str,
        loads: Loads,
        interval: f64,
    ) -> Result<Explicit<M>, BenchError> {
        let rest = self.rest().to_vec();
        let horizon = self.horizon();
        let (omega, _) = stable_frequency(&mut self.model, &rest, horizon);
        let stable = 0.8 * 2.0 / omega;
        let dt = interval / (interval / stable).ceil().max(1.0);
        self.solver_at(case, loads, TimeStep::Fixed(dt))
    }

    /// An explicit solver with time step `dt`.
    pub fn solver_at(
        self,
        case: &str,
        loads: Loads,
        dt: TimeStep,
    ) -> Result<Explicit<M>, BenchError> {
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

    /// An implicit solver with `config`.
    pub fn implicit(
        self,
        case: &str,
        loads: Loads,
        config: ImplicitConfig,
    ) -> Result<Implicit<M>, BenchError>
    where
        M: QuasiNewtonModel,
    {
        let rest = self.rest().to_vec();
        Implicit::new(self.model, &rest, loads, config).map_err(|cause| BenchError::Physics {
            case: case.into(),
            cause,
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
pub(crate) fn rest_of<M: ForceModel, I: Integrator<M>>(s: &Simulation<M, I>) -> &[Vec3] {
    s.model().discretization().rest_positions()
}

/// Sets the velocity (m/s) of every particle of `s` to `velocity` at its rest position.
pub(crate) fn set_velocities<M: ForceModel, I: Integrator<M>>(
    s: &mut Simulation<M, I>,
    velocity: impl Fn(Vec3) -> Vec3,
) {
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
    use perifrac_topology::primitives::box_data;

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
