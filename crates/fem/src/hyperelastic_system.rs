//! A neo-Hookean body on its mesh: total potential energy, its gradient at every node and the
//! tangent on the free DOFs. Element kernels run on rayon in fixed chunks of elements; their
//! results are scattered serially in element order, so every sum is bit-for-bit the same
//! whatever the thread count.

use std::marker::PhantomData;

use rayon::prelude::*;

use crate::assembly::{FreeDofs, LowerPattern, CHUNK};
use crate::basis::{Basis, QuadPoint};
use crate::element;
use crate::error::FemError;
use crate::hyperelastic::NeoHookean;
use crate::hyperelastic_element::{self as kernel, Quadrature};
use crate::math::{dot, Vec3};
use crate::mesh::Mesh;
use crate::problem::Problem;

/// Displacements (m) of element `e`'s nodes.
#[inline]
fn element_displacements<const N: usize>(mesh: &Mesh, e: usize, u: &[Vec3]) -> [Vec3; N] {
    let conn = mesh.element(e);
    std::array::from_fn(|a| u[conn[a] as usize])
}

/// Energies at one state.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Energies {
    /// Strain energy W (J).
    pub strain: f64,
    /// Total potential energy `W - s f . u` (J).
    pub potential: f64,
    /// Size (J) of the terms `potential` is summed from: its rounding error is a small
    /// multiple of eps times this.
    pub scale: f64,
}

/// The body, its free DOFs, the pattern of its tangent and the scratch space of the kernels.
pub(crate) struct System<'p, const N: usize, B: Basis<N>> {
    problem: &'p Problem,
    law: NeoHookean,
    rule: &'static [QuadPoint],
    /// Consistent load (N) of the full body force `density * gravity` on every node.
    load: Vec<Vec3>,
    pub free: FreeDofs,
    pub pattern: LowerPattern,
    local_grad: Vec<Vec3>,
    local_energy: Vec<Option<(f64, f64)>>,
    local_k: Vec<f64>,
    local_ok: Vec<bool>,
    _basis: PhantomData<B>,
}

impl<'p, const N: usize, B: Basis<N>> System<'p, N, B> {
    pub fn new(problem: &'p Problem, quadrature: Quadrature) -> Result<Self, FemError> {
        let mesh = problem.mesh();
        let free = FreeDofs::new(problem)?;
        let pattern = LowerPattern::new(mesh, &free);
        let rho_g = problem.gravity().map(|g| problem.material().density * g);
        let mut load = vec![[0.0; 3]; mesh.node_count()];
        for e in 0..mesh.element_count() {
            let l = element::load::<N, B>(mesh.volumes()[e]);
            for (a, &node) in mesh.element(e).iter().enumerate() {
                for d in 0..3 {
                    load[node as usize][d] += rho_g[d] * l[a];
                }
            }
        }
        let chunk = CHUNK.min(mesh.element_count());
        Ok(Self {
            problem,
            law: NeoHookean::new(problem.material()),
            rule: kernel::rule(mesh.order(), quadrature),
            load,
            free,
            pattern,
            local_grad: vec![[0.0; 3]; chunk * N],
            local_energy: vec![None; chunk],
            local_k: vec![0.0; chunk * 9 * N * N],
            local_ok: vec![true; chunk],
            _basis: PhantomData,
        })
    }

    /// Energies at node displacements `u` (m) under load factor `s`, and the gradient
    /// `dPi/du` (N) at every node into `grad` (the residual: internal minus external force).
    /// `Err(element)` with the lowest element that has `J <= 0` somewhere.
    pub fn evaluate(&mut self, u: &[Vec3], s: f64, grad: &mut [Vec3]) -> Result<Energies, usize> {
        let mesh = self.problem.mesh();
        let n_el = mesh.element_count();
        for (g, f) in grad.iter_mut().zip(&self.load) {
            *g = f.map(|c| -s * c);
        }
        let (mut strain, mut scale) = (0.0, 0.0);
        for start in (0..n_el).step_by(CHUNK) {
            let end = (start + CHUNK).min(n_el);
            let (law, rule) = (&self.law, self.rule);
            let mut local_grad = std::mem::take(&mut self.local_grad);
            let mut local_energy = std::mem::take(&mut self.local_energy);
            local_grad[..(end - start) * N]
                .par_chunks_mut(N)
                .zip(local_energy[..end - start].par_iter_mut())
                .enumerate()
                .for_each(|(i, (out, energy))| {
                    let e = start + i;
                    let out: &mut [Vec3; N] = out.try_into().expect("chunk of N");
                    let ue = element_displacements::<N>(mesh, e, u);
                    *energy = kernel::energy_gradient_scale::<N, B>(
                        mesh.barycentric_gradients(e),
                        mesh.volumes()[e],
                        law,
                        rule,
                        &ue,
                        Some(out),
                    );
                });
            let bad = local_energy[..end - start].iter().position(Option::is_none);
            if bad.is_none() {
                for (i, (out, energy)) in local_grad
                    .chunks(N)
                    .zip(&local_energy[..end - start])
                    .enumerate()
                {
                    let (w, sc) = energy.unwrap_or_default();
                    strain += w;
                    scale += sc;
                    for (a, &node) in mesh.element(start + i).iter().enumerate() {
                        let gn = &mut grad[node as usize];
                        for d in 0..3 {
                            gn[d] += out[a][d];
                        }
                    }
                }
            }
            self.local_grad = local_grad;
            self.local_energy = local_energy;
            if let Some(i) = bad {
                return Err(start + i);
            }
        }
        let work: f64 = u.iter().zip(&self.load).map(|(ui, fi)| dot(*ui, *fi)).sum();
        Ok(Energies {
            strain,
            potential: strain - s * work,
            scale: scale + (s * work).abs(),
        })
    }

    /// Adds the tangent `d^2 W / du^2` (N/m) at `u` into `values` (lower triangle on the free
    /// DOFs, [`LowerPattern`] order); `constrained(r, node, component, k)` gets every entry
    /// coupling free row `r` to a constrained DOF. `Err(element)` as in [`System::evaluate`].
    pub fn tangent(
        &mut self,
        u: &[Vec3],
        values: &mut [f64],
        mut constrained: impl FnMut(usize, usize, usize, f64),
    ) -> Result<(), usize> {
        let mesh = self.problem.mesh();
        let n_el = mesh.element_count();
        let n9 = 9 * N * N;
        values.fill(0.0);
        for start in (0..n_el).step_by(CHUNK) {
            let end = (start + CHUNK).min(n_el);
            let (law, rule) = (&self.law, self.rule);
            let mut local_k = std::mem::take(&mut self.local_k);
            let mut local_ok = std::mem::take(&mut self.local_ok);
            local_k[..(end - start) * n9]
                .par_chunks_mut(n9)
                .zip(local_ok[..end - start].par_iter_mut())
                .enumerate()
                .for_each(|(i, (k, ok))| {
                    let e = start + i;
                    let ue = element_displacements::<N>(mesh, e, u);
                    *ok = kernel::tangent::<N, B>(
                        mesh.barycentric_gradients(e),
                        mesh.volumes()[e],
                        law,
                        rule,
                        &ue,
                        k,
                    );
                });
            let bad = local_ok[..end - start].iter().position(|ok| !ok);
            if bad.is_none() {
                for (i, k) in local_k[..(end - start) * n9].chunks(n9).enumerate() {
                    self.pattern.add_element(
                        values,
                        k,
                        mesh.element(start + i),
                        &self.free.index,
                        &mut constrained,
                    );
                }
            }
            self.local_k = local_k;
            self.local_ok = local_ok;
            if let Some(i) = bad {
                return Err(start + i);
            }
        }
        Ok(())
    }
}
