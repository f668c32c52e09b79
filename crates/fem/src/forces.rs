//! The global elastic force kernel: per-element forces in parallel into a caller-owned buffer,
//! then a deterministic per-node gather (no atomics, no locks, no allocation per call).

use rayon::prelude::*;

use crate::basis::{Basis, P1, P2};
use crate::element::{self, Lame};
use crate::error::FemError;
use crate::material::Material;
use crate::math::{sub, Vec3};
use crate::mesh::{Mesh, Order};

/// Kinematics of the elastic force.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinematics {
    /// Small-strain: `f = -K (x - X)`. Not invariant under rotation.
    Linear,
    /// Corotated: at each quadrature point, `F = R S` (polar decomposition) and the stress is the
    /// linear stress of `S - I`, rotated by `R`. Zero for any rigid motion, objective, and
    /// conservative (the energy is `mu |S - I|^2 + lambda/2 tr(S - I)^2` per unit volume). For
    /// P1 this is the classic element-wise `R K_e (R^T x - X)`; for P2 `R` is taken at each of
    /// the 4 quadrature points, not once per element.
    Corotated,
}

/// Whether a kernel runs on rayon's pool or on the calling thread.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Parallelism {
    /// The calling thread only (allocates nothing per call).
    Serial,
    /// Rayon's global pool (the result is bit-identical to `Serial`). Meshes of fewer than
    /// [`SERIAL_BELOW`] elements still run on the calling thread: waking the pool costs more
    /// than their work.
    #[default]
    Rayon,
}

/// Element count below which [`Parallelism::Rayon`] runs serially anyway.
pub const SERIAL_BELOW: usize = 256;

/// Elastic force and energy of a mesh of one material, with its scratch space.
#[derive(Debug, Clone)]
pub struct ElasticForces<'m> {
    mesh: &'m Mesh,
    lame: Lame,
    kinematics: Kinematics,
    parallelism: Parallelism,
    /// Per-element, per-local-node forces (N), `nodes_per_element` per element.
    local: Vec<Vec3>,
    /// For node `n`, `slots[offsets[n]..offsets[n + 1]]` are its indices into `local`.
    offsets: Vec<usize>,
    slots: Vec<u32>,
}

impl<'m> ElasticForces<'m> {
    /// Kernel for `mesh` and `material` with the given kinematics, on rayon's pool.
    pub fn new(mesh: &'m Mesh, material: &Material, kinematics: Kinematics) -> Self {
        let npe = mesh.nodes_per_element();
        let conn = mesh.elements();
        let mut offsets = vec![0usize; mesh.node_count() + 1];
        for &n in conn {
            offsets[n as usize + 1] += 1;
        }
        for i in 0..mesh.node_count() {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut slots = vec![0u32; conn.len()];
        for (slot, &n) in conn.iter().enumerate() {
            slots[fill[n as usize]] = slot as u32;
            fill[n as usize] += 1;
        }
        Self {
            mesh,
            lame: Lame {
                lambda: material.lambda(),
                mu: material.mu(),
            },
            kinematics,
            parallelism: Parallelism::Serial,
            local: vec![[0.0; 3]; mesh.element_count() * npe],
            offsets,
            slots,
        }
        .with_parallelism(Parallelism::default())
    }

    /// The same kernel on the given parallelism.
    pub fn with_parallelism(mut self, parallelism: Parallelism) -> Self {
        self.parallelism = if self.mesh.element_count() < SERIAL_BELOW {
            Parallelism::Serial
        } else {
            parallelism
        };
        self
    }

    /// The kinematics.
    pub fn kinematics(&self) -> Kinematics {
        self.kinematics
    }

    /// Internal elastic force (N) on every node at current node positions `positions` (m),
    /// written to `forces`. Corotated kinematics fails with [`FemError::ElementInverted`]
    /// (lowest element id, `time: None`) if some element has `det F <= 0`.
    ///
    /// # Panics
    /// If `positions` or `forces` does not have one entry per node.
    #[track_caller]
    pub fn compute(&mut self, positions: &[Vec3], forces: &mut [Vec3]) -> Result<(), FemError> {
        let n = self.mesh.node_count();
        assert_eq!(positions.len(), n, "positions: one per node");
        assert_eq!(forces.len(), n, "forces: one per node");
        let bad = match self.mesh.order() {
            Order::Linear => self.element_forces::<4, P1>(positions),
            Order::Quadratic => self.element_forces::<10, P2>(positions),
        };
        let (local, offsets, slots) = (&self.local, &self.offsets, &self.slots);
        let gather = |(node, f): (usize, &mut Vec3)| {
            let mut sum = [0.0; 3];
            for &s in &slots[offsets[node]..offsets[node + 1]] {
                let l = local[s as usize];
                sum = [sum[0] + l[0], sum[1] + l[1], sum[2] + l[2]];
            }
            *f = sum;
        };
        match self.parallelism {
            Parallelism::Serial => forces.iter_mut().enumerate().for_each(gather),
            Parallelism::Rayon => forces.par_iter_mut().enumerate().for_each(gather),
        }
        match bad {
            Some(element) => Err(FemError::ElementInverted {
                element,
                time: None,
            }),
            None => Ok(()),
        }
    }

    /// Fills `self.local`; returns the lowest inverted element, if any.
    fn element_forces<const N: usize, B: Basis<N>>(&mut self, x: &[Vec3]) -> Option<usize> {
        let (mesh, lame, kin) = (self.mesh, self.lame, self.kinematics);
        let kernel = |(e, out): (usize, &mut [Vec3])| -> Option<usize> {
            let out: &mut [Vec3; N] = out.try_into().expect("chunk of N");
            let u = displacements::<N>(mesh, e, x);
            let gl = mesh.barycentric_gradients(e);
            let vol = mesh.volumes()[e];
            match kin {
                Kinematics::Linear => {
                    element::force_linear::<N, B>(gl, vol, lame, &u, out);
                    None
                }
                Kinematics::Corotated => {
                    (!element::force_corotated::<N, B>(gl, vol, lame, &u, out)).then_some(e)
                }
            }
        };
        match self.parallelism {
            Parallelism::Serial => self
                .local
                .chunks_mut(N)
                .enumerate()
                .filter_map(kernel)
                .min(),
            Parallelism::Rayon => self
                .local
                .par_chunks_mut(N)
                .enumerate()
                .filter_map(kernel)
                .min(),
        }
    }

    /// Elastic strain energy (J) at node positions `positions` (m); corotated kinematics fails
    /// like [`ElasticForces::compute`]. Summed in element order (deterministic).
    #[track_caller]
    pub fn energy(&self, positions: &[Vec3]) -> Result<f64, FemError> {
        assert_eq!(
            positions.len(),
            self.mesh.node_count(),
            "positions: one per node"
        );
        match self.mesh.order() {
            Order::Linear => self.energy_of::<4, P1>(positions),
            Order::Quadratic => self.energy_of::<10, P2>(positions),
        }
    }

    fn energy_of<const N: usize, B: Basis<N>>(&self, x: &[Vec3]) -> Result<f64, FemError> {
        let mesh = self.mesh;
        let mut total = 0.0;
        for e in 0..mesh.element_count() {
            let u = displacements::<N>(mesh, e, x);
            let gl = mesh.barycentric_gradients(e);
            let vol = mesh.volumes()[e];
            total += match self.kinematics {
                Kinematics::Linear => element::energy_linear::<N, B>(gl, vol, self.lame, &u),
                Kinematics::Corotated => element::energy_corotated::<N, B>(gl, vol, self.lame, &u)
                    .ok_or(FemError::ElementInverted {
                        element: e,
                        time: None,
                    })?,
            };
        }
        Ok(total)
    }
}

/// Displacements `x - X` (m) of element `e`'s nodes.
#[inline]
fn displacements<const N: usize>(mesh: &Mesh, e: usize, x: &[Vec3]) -> [Vec3; N] {
    let conn = &mesh.elements()[e * N..(e + 1) * N];
    let rest = mesh.nodes();
    std::array::from_fn(|a| {
        let n = conn[a] as usize;
        sub(x[n], rest[n])
    })
}
