//! Per-element neo-Hookean kernels, generic over the element type: strain energy, its gradient
//! (the internal force with the opposite sign) and its Hessian (the tangent stiffness), plus
//! the public element-level wrappers the tests use.

use crate::basis::{Basis, QuadPoint, P1, P2, RULE_1, RULE_14, RULE_4};
use crate::element::gradient;
use crate::error::FemError;
use crate::hyperelastic::NeoHookean;
use crate::material::Material;
use crate::math::Vec3;
use crate::mesh::{Mesh, Order};

/// Quadrature of the neo-Hookean energy over a quadratic (P2) element. A linear element has a
/// constant `F`, so its one-point rule is exact whatever is chosen here.
///
/// In P2, `F` is linear over the element and the energy is not a polynomial (`ln J`), so no
/// rule is exact. The 4-point rule is exact for the degree-2 integrand of the linear stiffness,
/// so it keeps the element's rank and its convergence order. The default 14-point rule (degree
/// 5, positive weights, points inside) costs 3.5 times as much per element, which does not
/// show in the solve time (the sparse factorisation is 85 % of it at 19k DOFs), and matters
/// where elements deform strongly: on the twisted bar at 20 cells it moves the mid-span corners
/// by 2e-4 m from the 4-point answer, as much as refining to 40 cells does. On the bent
/// cantilever the two rules differ by 6e-4, 5e-5 and 3e-6 m at the tip for 10, 20 and 40
/// cells, far below the discretisation error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Quadrature {
    /// The 4-point rule, exact for degree 2.
    Degree2,
    /// The 14-point rule, exact for degree 5.
    #[default]
    Degree5,
}

/// The rule for elements of `order`.
pub(crate) fn rule(order: Order, quadrature: Quadrature) -> &'static [QuadPoint] {
    match (order, quadrature) {
        (Order::Linear, _) => &RULE_1,
        (Order::Quadratic, Quadrature::Degree2) => &RULE_4,
        (Order::Quadratic, Quadrature::Degree5) => &RULE_14,
    }
}

/// Strain energy (J) of one element with node displacements `u` (m), and its gradient
/// `dW/du_a` (N) into `grad` when given. `None` if `J <= 0` at some quadrature point.
#[inline]
pub(crate) fn energy_gradient<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    law: &NeoHookean,
    rule: &[QuadPoint],
    u: &[Vec3; N],
    grad: Option<&mut [Vec3; N]>,
) -> Option<f64> {
    energy_gradient_scale::<N, B>(grad_l, volume, law, rule, u, grad).map(|(w, _)| w)
}

/// [`energy_gradient`], plus the size (J) of the terms the energy is summed from,
/// `sum w V (mu |H|^2 + lambda (ln J)^2)`, which bounds its rounding error in units of eps.
#[inline]
pub(crate) fn energy_gradient_scale<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    law: &NeoHookean,
    rule: &[QuadPoint],
    u: &[Vec3; N],
    mut grad: Option<&mut [Vec3; N]>,
) -> Option<(f64, f64)> {
    if let Some(gr) = grad.as_deref_mut() {
        *gr = [[0.0; 3]; N];
    }
    let mut energy = 0.0;
    let mut scale = 0.0;
    for &(l, w) in rule {
        let g = B::gradients(l, grad_l);
        let h = gradient(u, &g);
        let s = NeoHookean::state(&h)?;
        let wv = w * volume;
        let hh: f64 = h.iter().flatten().map(|v| v * v).sum();
        scale += wv * (law.mu * hh + law.lambda * s.ln_j * s.ln_j);
        energy += wv * law.energy_of(&h, &s);
        if let Some(gr) = grad.as_deref_mut() {
            let p = law.piola_of(&h, &s);
            for a in 0..N {
                for i in 0..3 {
                    gr[a][i] += wv * (p[i][0] * g[a][0] + p[i][1] * g[a][1] + p[i][2] * g[a][2]);
                }
            }
        }
    }
    Some((energy, scale))
}

/// Tangent stiffness (N/m) `d^2 W / du_a,i du_b,k`, `(3N) x (3N)` row-major into `out`. At
/// each point, with `h_a = F^-T grad N_a` and `c = mu - lambda ln J`:
/// `K_ab,ik += w V [mu (grad N_a . grad N_b) d_ik + lambda h_a,i h_b,k + c h_b,i h_a,k]`,
/// the contraction of [`NeoHookean::tangent`] with the two gradients. `false` if `J <= 0`.
pub(crate) fn tangent<const N: usize, B: Basis<N>>(
    grad_l: &[Vec3; 4],
    volume: f64,
    law: &NeoHookean,
    rule: &[QuadPoint],
    u: &[Vec3; N],
    out: &mut [f64],
) -> bool {
    let n3 = 3 * N;
    debug_assert_eq!(out.len(), n3 * n3);
    out.fill(0.0);
    for &(l, w) in rule {
        let g = B::gradients(l, grad_l);
        let h = gradient(u, &g);
        let Some(s) = NeoHookean::state(&h) else {
            return false;
        };
        let wv = w * volume;
        let c = law.mu - law.lambda * s.ln_j;
        let gt = &s.inv_t;
        let hv: [Vec3; N] = std::array::from_fn(|a| {
            std::array::from_fn(|i| gt[i][0] * g[a][0] + gt[i][1] * g[a][1] + gt[i][2] * g[a][2])
        });
        for a in 0..N {
            for b in 0..N {
                let gab = g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2];
                for i in 0..3 {
                    let row = &mut out[(3 * a + i) * n3 + 3 * b..(3 * a + i) * n3 + 3 * b + 3];
                    for (k, slot) in row.iter_mut().enumerate() {
                        let mut v = law.lambda * hv[a][i] * hv[b][k] + c * hv[b][i] * hv[a][k];
                        if i == k {
                            v += law.mu * gab;
                        }
                        *slot += wv * v;
                    }
                }
            }
        }
    }
    true
}

/// Displacements (m) of element `e`'s nodes, checking the element id and the array length.
fn element_displacements<const N: usize>(
    mesh: &Mesh,
    e: usize,
    displacements: &[Vec3],
) -> Result<[Vec3; N], FemError> {
    if e >= mesh.element_count() {
        return Err(FemError::ElementOutOfRange {
            element: e,
            count: mesh.element_count(),
        });
    }
    if displacements.len() != mesh.node_count() {
        return Err(FemError::LengthMismatch {
            what: "displacements",
            got: displacements.len(),
            expected: mesh.node_count(),
        });
    }
    let conn = mesh.element(e);
    Ok(std::array::from_fn(|a| displacements[conn[a] as usize]))
}

fn inverted(element: usize) -> FemError {
    FemError::ElementInverted {
        element,
        time: None,
    }
}

/// Neo-Hookean strain energy (J) of element `element` of `mesh` when the nodes move by
/// `displacements` (m, one per node of the mesh). Fails with [`FemError::ElementInverted`]
/// (`time: None`) if `J <= 0` at a quadrature point.
pub fn neo_hookean_energy(
    mesh: &Mesh,
    material: &Material,
    quadrature: Quadrature,
    element: usize,
    displacements: &[Vec3],
) -> Result<f64, FemError> {
    neo_hookean_element(mesh, material, quadrature, element, displacements, false).map(|(w, _)| w)
}

/// Gradient (N) of [`neo_hookean_energy`] with respect to the displacements of the element's
/// nodes, in the element's node order (the internal force on those nodes is its negative).
pub fn neo_hookean_gradient(
    mesh: &Mesh,
    material: &Material,
    quadrature: Quadrature,
    element: usize,
    displacements: &[Vec3],
) -> Result<Vec<Vec3>, FemError> {
    neo_hookean_element(mesh, material, quadrature, element, displacements, true).map(|(_, g)| g)
}

fn neo_hookean_element(
    mesh: &Mesh,
    material: &Material,
    quadrature: Quadrature,
    element: usize,
    displacements: &[Vec3],
    with_gradient: bool,
) -> Result<(f64, Vec<Vec3>), FemError> {
    fn run<const N: usize, B: Basis<N>>(
        mesh: &Mesh,
        law: &NeoHookean,
        rule: &[QuadPoint],
        e: usize,
        d: &[Vec3],
        with_gradient: bool,
    ) -> Result<(f64, Vec<Vec3>), FemError> {
        let u = element_displacements::<N>(mesh, e, d)?;
        let mut g = [[0.0; 3]; N];
        let w = energy_gradient::<N, B>(
            mesh.barycentric_gradients(e),
            mesh.volumes()[e],
            law,
            rule,
            &u,
            with_gradient.then_some(&mut g),
        )
        .ok_or_else(|| inverted(e))?;
        Ok((
            w,
            if with_gradient {
                g.to_vec()
            } else {
                Vec::new()
            },
        ))
    }
    let law = NeoHookean::new(material);
    let r = rule(mesh.order(), quadrature);
    match mesh.order() {
        Order::Linear => run::<4, P1>(mesh, &law, r, element, displacements, with_gradient),
        Order::Quadratic => run::<10, P2>(mesh, &law, r, element, displacements, with_gradient),
    }
}

/// Hessian (N/m) of [`neo_hookean_energy`] with respect to the element's node displacements:
/// `3n x 3n` row-major (`n` = nodes per element), DOF `3a + i` for local node `a`, component
/// `i`. Symmetric; not always positive definite far from the rest state.
pub fn neo_hookean_tangent(
    mesh: &Mesh,
    material: &Material,
    quadrature: Quadrature,
    element: usize,
    displacements: &[Vec3],
) -> Result<Vec<f64>, FemError> {
    fn run<const N: usize, B: Basis<N>>(
        mesh: &Mesh,
        law: &NeoHookean,
        rule: &[QuadPoint],
        e: usize,
        d: &[Vec3],
    ) -> Result<Vec<f64>, FemError> {
        let u = element_displacements::<N>(mesh, e, d)?;
        let mut k = vec![0.0; 9 * N * N];
        let gl = mesh.barycentric_gradients(e);
        if tangent::<N, B>(gl, mesh.volumes()[e], law, rule, &u, &mut k) {
            Ok(k)
        } else {
            Err(inverted(e))
        }
    }
    let law = NeoHookean::new(material);
    let r = rule(mesh.order(), quadrature);
    match mesh.order() {
        Order::Linear => run::<4, P1>(mesh, &law, r, element, displacements),
        Order::Quadratic => run::<10, P2>(mesh, &law, r, element, displacements),
    }
}
