//! Xu's bond loops, generic over the bond curve `h`, the kernel `G` and the damage mask, so the
//! common cases (one named curve, isotropic, no fracture) carry no branch per bond.

use super::basis::Curve;
use super::kernel::Alive;
use crate::family::Family;
use crate::math::{norm, sub, Vec3};

/// The bond curve `h` of particle `i`'s bonds: `slope_pair` gives `(h_i'(tau), h_j'(tau))`.
pub(crate) trait BondCurve: Sync + Copy {
    fn slope_pair(&self, i: usize, j: usize, tau: f64) -> (f64, f64);
    fn value(&self, i: usize, tau: f64) -> f64;
    /// `(h_i(tau), h_i'(tau), h_j'(tau))`.
    #[inline(always)]
    fn value_slope_pair(&self, i: usize, j: usize, tau: f64) -> (f64, f64, f64) {
        let (si, sj) = self.slope_pair(i, j, tau);
        (self.value(i, tau), si, sj)
    }
}

/// `h = B_1` for every particle.
#[derive(Clone, Copy)]
pub(crate) struct LinearH;
impl BondCurve for LinearH {
    #[inline(always)]
    fn slope_pair(&self, _i: usize, _j: usize, tau: f64) -> (f64, f64) {
        let s = 2.0 * (tau - 1.0);
        (s, s)
    }
    #[inline(always)]
    fn value(&self, _i: usize, tau: f64) -> f64 {
        (tau - 1.0) * (tau - 1.0)
    }
}

/// `h = A_1` for every particle.
#[derive(Clone, Copy)]
pub(crate) struct NeoHookeanH;
impl BondCurve for NeoHookeanH {
    #[inline(always)]
    fn slope_pair(&self, _i: usize, _j: usize, tau: f64) -> (f64, f64) {
        let s = tau - 1.0 / tau;
        (s, s)
    }
    #[inline(always)]
    fn value(&self, _i: usize, tau: f64) -> f64 {
        Curve::NeoHookean.eval(tau).0
    }
}

/// `h = (3 B_3 - B_1) / 2` for every particle.
#[derive(Clone, Copy)]
pub(crate) struct StvkH;
impl BondCurve for StvkH {
    #[inline(always)]
    fn slope_pair(&self, _i: usize, _j: usize, tau: f64) -> (f64, f64) {
        let s = (tau * tau - 1.0) * tau;
        (s, s)
    }
    #[inline(always)]
    fn value(&self, _i: usize, tau: f64) -> f64 {
        let e = 0.5 * (tau * tau - 1.0);
        e * e
    }
}

/// Any curves, per particle: `curves[material[i]]`.
#[derive(Clone, Copy)]
pub(crate) struct PerParticleH<'a> {
    pub curves: &'a [Curve],
    pub material: &'a [u16],
    /// True when all materials share one curve (then `h_j' = h_i'`).
    pub uniform: bool,
}
impl BondCurve for PerParticleH<'_> {
    #[inline(always)]
    fn slope_pair(&self, i: usize, j: usize, tau: f64) -> (f64, f64) {
        let si = self.curves[self.material[i] as usize].slope(tau);
        if self.uniform {
            (si, si)
        } else {
            (si, self.curves[self.material[j] as usize].slope(tau))
        }
    }
    #[inline(always)]
    fn value(&self, i: usize, tau: f64) -> f64 {
        self.curves[self.material[i] as usize].eval(tau).0
    }
}

/// The kernel `(G_ij, G_ji)` of bond `k`.
pub(crate) trait Kernel: Sync + Copy {
    fn pair(&self, k: usize) -> (f64, f64);
}

/// `G = 1`.
#[derive(Clone, Copy)]
pub(crate) struct Unit;
impl Kernel for Unit {
    #[inline(always)]
    fn pair(&self, _k: usize) -> (f64, f64) {
        (1.0, 1.0)
    }
}

/// Stored per directed bond: `G` with the owner's axes and with the neighbour's.
#[derive(Clone, Copy)]
pub(crate) struct Stored<'a> {
    pub own: &'a [f64],
    pub other: &'a [f64],
}
impl Kernel for Stored<'_> {
    #[inline(always)]
    fn pair(&self, k: usize) -> (f64, f64) {
        (self.own[k], self.other[k])
    }
}

/// The pressure term's weights: `T_ij` carries `p_i a_ij + p_j a_ji` for bond `k`.
pub(crate) trait Pressure: Sync + Copy {
    /// The pair scalar `T_ij` of bond `k` from its `wr`, both ends' `p` and the bond term
    /// `q_i G_ij h_i' + q_j G_ji h_j'`; the same bits from both ends.
    fn pair(&self, k: usize, wr: f64, pi: f64, pj: f64, bond: f64) -> f64;
}

/// Xu's normalised weights: `a_ij = wr_ij` at both ends.
#[derive(Clone, Copy)]
pub(crate) struct Normalised;
impl Pressure for Normalised {
    #[inline(always)]
    fn pair(&self, _k: usize, wr: f64, pi: f64, pj: f64, bond: f64) -> f64 {
        wr * ((pi + pj) + bond)
    }
}

/// The fitted weights of `xu_fit.rs`: `a_ij = f_ij`, `a_ji = f_ji`, stored per bond.
#[derive(Clone, Copy)]
pub(crate) struct Fitted<'a> {
    pub pairs: &'a [[f64; 2]],
}
impl Pressure for Fitted<'_> {
    #[inline(always)]
    fn pair(&self, k: usize, wr: f64, pi: f64, pj: f64, bond: f64) -> f64 {
        let [fij, fji] = self.pairs[k];
        wr * bond + (pi * fij + pj * fji)
    }
}

/// Read-only inputs of the loops.
#[derive(Clone, Copy)]
pub(crate) struct XuInputs<'a> {
    pub family: &'a Family,
    pub y: &'a [Vec3],
    pub volumes: &'a [f64],
    /// `wt(r / delta) / r` per directed bond (1/m).
    pub wr: &'a [f64],
}

/// `sum_j wt_ij V_j tau_ij` over intact bonds of `i` (m^3): `theta_i` before normalisation.
#[inline(always)]
pub(crate) fn dilatation_sum<D: Alive>(inp: XuInputs, d: D, i: usize) -> f64 {
    row_sum(inp, d, i, |k, l| inp.wr[k] * l)
}

/// `sum_j f_ij V_j (l_ij - r_ij)` over intact bonds of `i` (m^2), with the fitted weights `f`
/// of `xu_fit.rs`: `theta_i - 1` before normalisation.
#[inline(always)]
pub(crate) fn fitted_dilatation_sum<D: Alive>(
    inp: XuInputs,
    pairs: &[[f64; 2]],
    d: D,
    i: usize,
) -> f64 {
    let rl = inp.family.rest_lengths();
    row_sum(inp, d, i, |k, l| pairs[k][0] * (l - rl[k]))
}

/// `sum_j term(k, l_ij) V_j` over the intact bonds `k` of `i`, `l` the current length (m).
#[inline(always)]
fn row_sum<D: Alive>(inp: XuInputs, d: D, i: usize, term: impl Fn(usize, f64) -> f64) -> f64 {
    let fam = inp.family;
    let nb = fam.neighbours();
    let yi = inp.y[i];
    let mut acc = 0.0;
    for k in fam.range(i) {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        acc += term(k, norm(sub(inp.y[j], yi))) * inp.volumes[j];
    }
    acc
}

/// Force on `i` (N): `sum_j V_i V_j (T_ij + T_ji) n_ij` with
/// `T_ij = a_ij p_i + wr_k q_i G_ij h_i'(tau)`, `p = inv_norm lambda g'(theta)`,
/// `q = inv_norm mu` from the dilatation pass and the pressure weights `a` of [`Pressure`]. The pair scalar is bitwise the same from both
/// ends (commutative sums and products), so Newton's third law holds bond by bond.
#[inline(always)]
pub(crate) fn force<H: BondCurve, G: Kernel, D: Alive, P: Pressure>(
    inp: XuInputs,
    (h, g, d, p): (H, G, D, P),
    pq: &[[f64; 2]],
    i: usize,
) -> Vec3 {
    bond_loop::<H, G, D, P, false>(inp, (h, g, d, p), pq, i).0
}

/// The bond part of `W_i / mu_i` before normalisation: `sum_j wt_ij V_j G_ij h_i(tau_ij)`
/// (m^3).
#[inline(always)]
pub(crate) fn bond_energy_sum<H: BondCurve, G: Kernel, D: Alive>(
    inp: XuInputs,
    h: H,
    g: G,
    d: D,
    i: usize,
) -> f64 {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let yi = inp.y[i];
    let mut acc = 0.0;
    for k in fam.range(i) {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let tau = norm(sub(inp.y[j], yi)) / r;
        acc += inp.wr[k] * r * inp.volumes[j] * g.pair(k).0 * h.value(i, tau);
    }
    acc
}

/// [`force`] and, in the same loop, the bond energy sum of [`bond_energy_sum`]: one pass for
/// the implicit step, which needs both at every trial point.
#[inline(always)]
pub(crate) fn force_and_energy<H: BondCurve, G: Kernel, D: Alive, P: Pressure>(
    inp: XuInputs,
    (h, g, d, p): (H, G, D, P),
    pq: &[[f64; 2]],
    i: usize,
) -> (Vec3, f64) {
    bond_loop::<H, G, D, P, true>(inp, (h, g, d, p), pq, i)
}

/// The force loop; with `ENERGY` it also sums `wt_ij V_j G_ij h_i(tau_ij)` (else 0, and no
/// curve value is evaluated).
#[inline(always)]
fn bond_loop<H: BondCurve, G: Kernel, D: Alive, P: Pressure, const ENERGY: bool>(
    inp: XuInputs,
    (h, g, d, pressure): (H, G, D, P),
    pq: &[[f64; 2]],
    i: usize,
) -> (Vec3, f64) {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let yi = inp.y[i];
    let vi = inp.volumes[i];
    let [pi, qi] = pq[i];
    let mut acc = [0.0; 3];
    let mut energy = 0.0;
    for k in fam.range(i) {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        let eta = sub(inp.y[j], yi);
        let l = norm(eta);
        let r = rl[k];
        let tau = l / r;
        let (hv, hi, hj) = if ENERGY {
            h.value_slope_pair(i, j, tau)
        } else {
            let (hi, hj) = h.slope_pair(i, j, tau);
            (0.0, hi, hj)
        };
        let (gij, gji) = g.pair(k);
        let [pj, qj] = pq[j];
        let vj = inp.volumes[j];
        let t = pressure.pair(k, inp.wr[k], pi, pj, qi * gij * hi + qj * gji * hj);
        let s = t * (vi * vj) / l;
        acc[0] += s * eta[0];
        acc[1] += s * eta[1];
        acc[2] += s * eta[2];
        if ENERGY {
            energy += inp.wr[k] * r * vj * gij * hv;
        }
    }
    (acc, energy)
}
