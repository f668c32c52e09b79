//! The Chen bond loops, generic over the bond weight, the plastic extension and the damage mask.
//! Each variant is monomorphised, so the elastic loop carries no plastic or fracture branch.

use std::cell::RefCell;

use crate::family::Family;
use crate::fracture::Breaker;
use crate::math::{norm, sub, Vec3};

/// Bond weights `omega_ij` (own side) and `omega_ji` (the other side) of bond `k`: the
/// deviatoric weights, and the dilatation weights where a fitted correction makes them differ.
pub(crate) trait Weights: Sync + Copy {
    /// Whether the dilatation weights differ from the deviatoric ones (a compile-time switch:
    /// without it the loops keep their single-weight arithmetic, bit for bit).
    const SPLIT: bool = false;
    fn pair(&self, k: usize, r: f64) -> (f64, f64);
    /// `(omega_ij r, omega_ji r)` of bond `k` (m): the weights times the rest length, which an
    /// isotropic weight gives without a division.
    #[inline(always)]
    fn pair_times_r(&self, k: usize, r: f64) -> (f64, f64) {
        let (wij, wji) = self.pair(k, r);
        (wij * r, wji * r)
    }
    /// `Some(delta)` (m) when the weight is `delta / r` both ways: the force loop then takes
    /// one reciprocal of `r l` per bond in place of two divisions.
    #[inline(always)]
    fn isotropic(&self) -> Option<f64> {
        None
    }
    /// The dilatation weights `d_ij`, `d_ji` of bond `k` (the deviatoric ones unless `SPLIT`).
    #[inline(always)]
    fn dil_pair(&self, k: usize, r: f64) -> (f64, f64) {
        self.pair(k, r)
    }
}

/// Isotropic weight `delta / r`, the same both ways.
#[derive(Clone, Copy)]
pub(crate) struct Isotropic {
    pub delta: f64,
}

impl Weights for Isotropic {
    #[inline(always)]
    fn pair(&self, _k: usize, r: f64) -> (f64, f64) {
        let w = self.delta / r;
        (w, w)
    }

    #[inline(always)]
    fn pair_times_r(&self, _k: usize, _r: f64) -> (f64, f64) {
        (self.delta, self.delta)
    }

    #[inline(always)]
    fn isotropic(&self) -> Option<f64> {
        Some(self.delta)
    }
}

/// Per-directed-bond weights (anisotropy), with the reverse-bond index.
#[derive(Clone, Copy)]
pub(crate) struct PerBond<'a> {
    pub w: &'a [f64],
    pub rev: &'a [u32],
}

impl Weights for PerBond<'_> {
    #[inline(always)]
    fn pair(&self, k: usize, _r: f64) -> (f64, f64) {
        (self.w[k], self.w[self.rev[k] as usize])
    }
}

/// Deviatoric weights `W` (isotropic or per bond) with the fitted dilatation weights of
/// [`super::ChenOptions::fitted_dilatation`]: `dw[k] = (d_ij, d_ji)` stored in bond order, so
/// the loops stream 16 bytes a bond and gather nothing through the reverse index.
#[derive(Clone, Copy)]
pub(crate) struct Fitted<'a, W> {
    pub base: W,
    pub dw: &'a [[f64; 2]],
}

impl<W: Weights> Weights for Fitted<'_, W> {
    const SPLIT: bool = true;

    #[inline(always)]
    fn pair(&self, k: usize, r: f64) -> (f64, f64) {
        self.base.pair(k, r)
    }

    #[inline(always)]
    fn pair_times_r(&self, k: usize, r: f64) -> (f64, f64) {
        self.base.pair_times_r(k, r)
    }

    #[inline(always)]
    fn isotropic(&self) -> Option<f64> {
        self.base.isotropic()
    }

    #[inline(always)]
    fn dil_pair(&self, k: usize, _r: f64) -> (f64, f64) {
        let [dij, dji] = self.dw[k];
        (dij, dji)
    }
}

/// Plastic extensions `ep_ij`, `ep_ji` of bond `k`.
pub(crate) trait Plastic: Sync + Copy {
    fn pair(&self, k: usize) -> (f64, f64);
    /// A lower bound on every plastic extension, at most 0 (m).
    fn floor(&self) -> f64;
}

/// Elastic material: no plastic extension.
#[derive(Clone, Copy)]
pub(crate) struct NoPlastic;

impl Plastic for NoPlastic {
    #[inline(always)]
    fn pair(&self, _k: usize) -> (f64, f64) {
        (0.0, 0.0)
    }

    fn floor(&self) -> f64 {
        0.0
    }
}

/// Stored plastic extensions in pairs: `ep[k] = (ep_ij, ep_ji)` in bond order, both ends of
/// every bond kept by the return map alike, so the loops stream them and gather nothing.
#[derive(Clone, Copy)]
pub(crate) struct WithPlastic<'a> {
    pub ep: &'a [[f64; 2]],
}

impl Plastic for WithPlastic<'_> {
    #[inline(always)]
    fn pair(&self, k: usize) -> (f64, f64) {
        let [ij, ji] = self.ep[k];
        (ij, ji)
    }

    /// The least plastic extension and 0: one serial pass over the bonds' 16 bytes.
    fn floor(&self) -> f64 {
        // Eight running minima: a single one chains every comparison on the last. Each own
        // extension is also its reverse bond's second, so the first of each pair suffices.
        let mut lanes = [0.0f64; 8];
        let chunks = self.ep.chunks_exact(8);
        let rest = chunks.remainder();
        for c in chunks {
            for (l, e) in lanes.iter_mut().zip(c) {
                *l = if e[0] < *l { e[0] } else { *l };
            }
        }
        let mut least = rest
            .iter()
            .fold(0.0f64, |a, e| if e[0] < a { e[0] } else { a });
        for l in lanes {
            least = if l < least { l } else { least };
        }
        least
    }
}

/// Which bonds are intact.
pub(crate) trait Alive: Sync + Copy {
    fn alive(&self, k: usize) -> bool;
}

/// No damage state: every bond is intact.
#[derive(Clone, Copy)]
pub(crate) struct AllAlive;

impl Alive for AllAlive {
    #[inline(always)]
    fn alive(&self, _k: usize) -> bool {
        true
    }
}

/// Damage mask: 1 intact, 0 broken.
#[derive(Clone, Copy)]
pub(crate) struct Mask<'a>(pub &'a [u8]);

impl Alive for Mask<'_> {
    #[inline(always)]
    fn alive(&self, k: usize) -> bool {
        self.0[k] != 0
    }
}

/// Read-only inputs shared by the loops.
#[derive(Clone, Copy)]
pub(crate) struct Inputs<'a> {
    pub family: &'a Family,
    pub y: &'a [Vec3],
    pub volumes: &'a [f64],
    /// Per-particle dilatation constant `c_i` (`9 / (4 pi delta^4)` uncalibrated).
    pub c_theta: &'a [f64],
}

/// Dilatation `theta_i = c sum_j omega_ij e_ij V_j` over intact bonds, and, when `MOMENT`, the
/// deviatoric moment `S_i = sum_j omega_ij r_ij (ed_ij - ep_ij) V_j` of the energy-consistent
/// pressure term (0 otherwise).
#[inline(always)]
pub(crate) fn dilatation<W: Weights, P: Plastic, D: Alive, const MOMENT: bool>(
    inp: Inputs,
    w: W,
    p: P,
    d: D,
    i: usize,
) -> (f64, f64) {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let yi = inp.y[i];
    let (mut acc, mut u, mut m) = (0.0, 0.0, 0.0);
    for k in fam.range(i) {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let e = norm(sub(inp.y[j], yi)) - r;
        acc += dilatation_term(w, k, r, inp.volumes[j], e);
        if MOMENT {
            let wrv = w.pair_times_r(k, r).0 * inp.volumes[j];
            u += wrv * (e - p.pair(k).0);
            m += wrv * r;
        }
    }
    let theta = inp.c_theta[i] * acc;
    (theta, u - theta * m / 3.0)
}

/// [`dilatation`] of an elastic particle fused with the damage check: walks `i`'s own bond
/// states `row` (1 intact), marks with 2 the intact bonds `brk` breaks at `inp.y` and leaves
/// them out of the sums, exactly as a check followed by [`dilatation`] would (the same terms in
/// the same order). Returns `(theta_i, S_i)` and the number of bonds it marked.
#[inline(always)]
pub(crate) fn dilatation_breaking<W: Weights, const MOMENT: bool>(
    inp: Inputs,
    w: W,
    brk: &Breaker,
    i: usize,
    row: &mut [u8],
) -> ((f64, f64), u32) {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let range = fam.range(i);
    let first = range.start;
    let yi = inp.y[i];
    let (mut acc, mut u, mut m) = (0.0, 0.0, 0.0);
    let mut count = 0;
    for k in range {
        let state = &mut row[k - first];
        if *state != 1 {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let e = norm(sub(inp.y[j], yi)) - r;
        if brk.breaks_elastic(i, j, e) {
            *state = 2;
            count += 1;
            continue;
        }
        acc += dilatation_term(w, k, r, inp.volumes[j], e);
        if MOMENT {
            let wrv = w.pair_times_r(k, r).0 * inp.volumes[j];
            u += wrv * e;
            m += wrv * r;
        }
    }
    let theta = inp.c_theta[i] * acc;
    ((theta, u - theta * m / 3.0), count)
}

/// Per-particle constants of the return map: `b_j` and `(Psi0_j, gamma_ratio_j)`.
#[derive(Clone, Copy)]
pub(crate) struct Yield<'a> {
    pub coef_b: &'a [f64],
    pub params: &'a [(f64, f64)],
}

impl Yield<'_> {
    /// The return map (MODEL.md, Plasticity) of particle `i`'s end of a bond: `wr` its weight
    /// times its rest length `r` (m), `w` its weight (asked for only when the bond yields),
    /// extension `e` (m), plastic extension `ep` (m), `i`'s dilatation `theta`. Returns
    /// `(ed, ep_new)`. Both ends of a bond run this with the same bits wherever it is called, so
    /// a bond's two stored pairs stay mirror images.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn map(
        &self,
        i: usize,
        wr: f64,
        w: impl FnOnce() -> f64,
        theta: f64,
        e: f64,
        r: f64,
        ep: f64,
    ) -> (f64, f64) {
        let (psi0, gamma_ratio) = self.params[i];
        let b = self.coef_b[i];
        let ed = e - theta * r / 3.0;
        // inside the yield surface, `(A_dev r)^2 / 2 <= psi0 r^2` with `A_dev r = 4 omega r b
        // (ed - ep)`, decides without the weight's division (most bonds, most steps)
        let trial_r = 4.0 * wr * b * (ed - ep);
        if 0.5 * trial_r * trial_r <= psi0 * (r * r) {
            return (ed, ep);
        }
        let four_wb = 4.0 * w() * b;
        let trial = four_wb * (ed - ep);
        let new = crate::plastic::return_map_bond(trial, ep, four_wb, psi0, gamma_ratio * r);
        (ed, new)
    }
}

/// `*slot = new` only where the bits differ (returns whether it stored): most bonds do not
/// yield in a step, and a line of the pairs left clean is not written back to memory.
#[inline(always)]
fn store_changed(slot: &mut f64, new: f64) -> bool {
    let changed = slot.to_bits() != new.to_bits();
    if changed {
        *slot = new;
    }
    changed
}

/// Extensions a walk keeps for its second loop over a particle's bonds; longer rows compute
/// the rest again (the same bits).
pub(crate) const ROW_BUFFER: usize = 512;

/// A row's `(e_ij, omega_ij r_ij)` kept between the loops of a walk.
pub(crate) type RowBuffer = [[f64; 2]; ROW_BUFFER];

thread_local! {
    /// Each worker's row buffer (8 KiB, never on the heap).
    static ROW: RefCell<RowBuffer> = const { RefCell::new([[0.0; 2]; ROW_BUFFER]) };
}

/// Runs `f` with this thread's row buffer (whose contents are left from the last use).
#[inline(always)]
pub(crate) fn with_row_buffer<T>(f: impl FnOnce(&mut RowBuffer) -> T) -> T {
    ROW.with(|b| f(&mut b.borrow_mut()))
}

/// The first pass of a plastic step for particle `i`: `theta_i` over the intact bonds, then the
/// return map of `i`'s own end of each (`ep` is `i`'s slice of the pairs: the first of each is
/// updated; the second, the other end's, is the force pass's to update) and the deviatoric
/// moment `S_i` with the new extensions. `buf` keeps the first loop's extensions. Returns
/// `[theta_i, S_i, least, changed]`, `least` the least of 0 and the extensions it changed (m),
/// `changed` 1 when it changed any (else 0).
#[inline(always)]
pub(crate) fn dilatation_yield<W: Weights, D: Alive>(
    inp: Inputs,
    w: W,
    d: D,
    yp: Yield,
    i: usize,
    ep: &mut [[f64; 2]],
    buf: &mut RowBuffer,
) -> [f64; 4] {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let range = fam.range(i);
    let first = range.start;
    let yi = inp.y[i];
    let mut acc = 0.0;
    for k in range {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let e = norm(sub(inp.y[j], yi)) - r;
        if let Some(b) = buf.get_mut(k - first) {
            *b = [e, w.pair_times_r(k, r).0];
        }
        acc += dilatation_term(w, k, r, inp.volumes[j], e);
    }
    let theta = inp.c_theta[i] * acc;
    let (moment, least, changed) = own_return_map(inp, w, |k| d.alive(k), yp, i, theta, ep, buf);
    [theta, moment, least, f64::from(u8::from(changed))]
}

/// [`dilatation_yield`] fused with the damage check: `row` is `i`'s own bond states (1 intact),
/// the bonds `brk` breaks at `inp.y` with the pairs `ep` as they were (whose least value is
/// `floor`) are marked 2 and left out, exactly as a check before [`dilatation_yield`] would.
/// Returns what [`dilatation_yield`] does and the number of bonds it marked.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn dilatation_yield_breaking<W: Weights>(
    inp: Inputs,
    w: W,
    brk: &Breaker,
    floor: f64,
    yp: Yield,
    i: usize,
    row: &mut [u8],
    ep: &mut [[f64; 2]],
    buf: &mut RowBuffer,
) -> ([f64; 4], u32) {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let range = fam.range(i);
    let first = range.start;
    let yi = inp.y[i];
    let mut acc = 0.0;
    let mut count = 0;
    for k in range {
        let state = &mut row[k - first];
        if *state != 1 {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let e = norm(sub(inp.y[j], yi)) - r;
        let [epij, epji] = ep[k - first];
        if brk.near(e - floor) && brk.breaks(i, j, e, (epij, epji)) {
            *state = 2;
            count += 1;
            continue;
        }
        if let Some(b) = buf.get_mut(k - first) {
            *b = [e, w.pair_times_r(k, r).0];
        }
        acc += dilatation_term(w, k, r, inp.volumes[j], e);
    }
    let theta = inp.c_theta[i] * acc;
    let alive = |k: usize| row[k - first] == 1;
    let (moment, least, changed) = own_return_map(inp, w, alive, yp, i, theta, ep, buf);
    ([theta, moment, least, f64::from(u8::from(changed))], count)
}

/// Bond `k`'s term of `theta_i / c_i` as [`dilatation`] sums it.
#[inline(always)]
fn dilatation_term<W: Weights>(w: W, k: usize, r: f64, vj: f64, e: f64) -> f64 {
    if W::SPLIT {
        w.dil_pair(k, r).0 * vj * e
    } else {
        w.pair(k, r).0 * vj * e
    }
}

/// The second loop of [`dilatation_yield`]: the return map of `i`'s own end of its bonds that
/// `alive` keeps; returns `S_i = sum_j omega_ij r_ij (ed_ij - ep_ij) V_j` after it, the least
/// of 0 and the extensions it changed (m), and whether it changed any.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn own_return_map<W: Weights>(
    inp: Inputs,
    w: W,
    alive: impl Fn(usize) -> bool,
    yp: Yield,
    i: usize,
    theta: f64,
    ep: &mut [[f64; 2]],
    buf: &RowBuffer,
) -> (f64, f64, bool) {
    let fam = inp.family;
    let range = fam.range(i);
    let first = range.start;
    let yi = inp.y[i];
    let (mut moment, mut least, mut changed) = (0.0, 0.0f64, false);
    for k in range {
        if !alive(k) {
            continue;
        }
        let j = fam.neighbours()[k] as usize;
        let r = fam.rest_lengths()[k];
        let [e, wr] = match buf.get(k - first) {
            Some(&b) => b,
            None => [norm(sub(inp.y[j], yi)) - r, w.pair_times_r(k, r).0],
        };
        let slot = &mut ep[k - first][0];
        let (ed, new) = yp.map(i, wr, || w.pair(k, r).0, theta, e, r, *slot);
        if store_changed(slot, new) {
            least = least.min(new);
            changed = true;
        }
        moment += wr * (ed - new) * inp.volumes[j];
    }
    (moment, least, changed)
}

/// Force on particle `i` (N): `V_i sum_j 0.5 (A_ij + A_ji) n_ij V_j` over intact bonds, where
/// `pq[j] = [a_j theta_j, b_j theta_j / 3]` and `coef_b[j] = b_j` come from the dilatation pass.
#[inline(always)]
pub(crate) fn force<W: Weights, P: Plastic, D: Alive>(
    inp: Inputs,
    w: W,
    p: P,
    d: D,
    pq: &[[f64; 2]],
    coef_b: &[f64],
    i: usize,
) -> Vec3 {
    force_with(inp, w, d, pq, coef_b, i, |k, _, _, _| p.pair(k))
}

/// [`force`] of a plastic step after [`dilatation_yield`]: finishes the return map on the
/// other end of each intact bond (`ep` is `i`'s slice of the pairs, whose second entries it
/// updates, with the dilatations `theta` of that pass) and uses the new extensions. The other
/// end `j` is mapped only where `changed[j]`, that pass's flag that `j` changed one of its own
/// ends: elsewhere the map gives back what is stored, as `j`'s own pass found for the same bond
/// with the same bits (`ep[k][1] == ep[rev k][0]`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn force_yield<W: Weights, D: Alive>(
    inp: Inputs,
    w: W,
    d: D,
    pq: &[[f64; 2]],
    yp: Yield,
    theta: &[[f64; 2]],
    changed: &[bool],
    i: usize,
    ep: &mut [[f64; 2]],
) -> Vec3 {
    let first = inp.family.range(i).start;
    force_with(inp, w, d, pq, yp.coef_b, i, |k, j, e, r| {
        let slot = &mut ep[k - first];
        if changed[j] {
            let wr = w.pair_times_r(k, r).1;
            let new = yp
                .map(j, wr, || w.pair(k, r).1, theta[j][0], e, r, slot[1])
                .1;
            // the other end's own pass stored the same value, and its least with it
            store_changed(&mut slot[1], new);
        }
        (slot[0], slot[1])
    })
}

/// The force loop, with `ep_of(k, j, e, r)` giving bond `k`'s `(ep_ij, ep_ji)`.
#[inline(always)]
fn force_with<W: Weights, D: Alive>(
    inp: Inputs,
    w: W,
    d: D,
    pq: &[[f64; 2]],
    coef_b: &[f64],
    i: usize,
    mut ep_of: impl FnMut(usize, usize, f64, f64) -> (f64, f64),
) -> Vec3 {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let yi = inp.y[i];
    let vi = inp.volumes[i];
    let [pi, qi] = pq[i];
    let bi = coef_b[i];
    let mut acc = [0.0; 3];
    for k in fam.range(i) {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let eta = sub(inp.y[j], yi);
        let l = norm(eta);
        let e = l - r;
        let [pj, qj] = pq[j];
        let s = if let Some(delta) = w.isotropic() {
            // omega = delta / r both ways, so r (A_ij + A_ji) / 4 needs no division and one
            // reciprocal of r l serves both (the weight's and the direction's): two divisions a
            // bond become one. Every sum and product pairs the two ends' terms commutatively,
            // so the pair scalar is bitwise the same from both ends, as in the general branch.
            let inv = 1.0 / (r * l);
            let (epij, epji) = ep_of(k, j, e, r);
            let bsum = bi * (e - epij) + coef_b[j] * (e - epji);
            let t = if W::SPLIT {
                let (dij, dji) = w.dil_pair(k, r);
                r * (dij * pi + dji * pj) + delta * (bsum - (qi + qj) * r)
            } else {
                delta * ((pi + pj) + bsum - (qi + qj) * r)
            };
            2.0 * t * (vi * inp.volumes[j]) * inv
        } else {
            let (wij, wji) = w.pair(k, r);
            let (epij, epji) = ep_of(k, j, e, r);
            let (aij, aji) = if W::SPLIT {
                let (dij, dji) = w.dil_pair(k, r);
                (
                    dij * pi + wij * (bi * (e - epij) - qi * r),
                    dji * pj + wji * (coef_b[j] * (e - epji) - qj * r),
                )
            } else {
                (
                    wij * (pi + bi * (e - epij) - qi * r),
                    wji * (pj + coef_b[j] * (e - epji) - qj * r),
                )
            };
            // 0.5 (A_ij + A_ji) with A = 4 omega (...): the pair scalar is bitwise the same
            // from both ends (commutative sums and products), so Newton's third law holds
            // bond by bond.
            2.0 * (aij + aji) * (vi * inp.volumes[j]) / l
        };
        acc[0] += s * eta[0];
        acc[1] += s * eta[1];
        acc[2] += s * eta[2];
    }
    acc
}

/// Elastic energy density `W_i = kappa_i theta_i^2 / 2 + b_i sum_j omega_ij (ed_ij - ep_ij)^2 V_j`
/// (J/m^3), with `kappa_i theta^2 / 2 = a_i theta^2 / c_i` (`a_i = kappa_i c_i / 2`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn energy_density<W: Weights, P: Plastic, D: Alive>(
    inp: Inputs,
    w: W,
    p: P,
    d: D,
    i: usize,
    theta: f64,
    a: f64,
    b: f64,
) -> f64 {
    let fam = inp.family;
    let yi = inp.y[i];
    let mut dev = 0.0;
    for k in fam.range(i) {
        if !d.alive(k) {
            continue;
        }
        let j = fam.neighbours()[k] as usize;
        let r = fam.rest_lengths()[k];
        let e = norm(sub(inp.y[j], yi)) - r;
        let ed = e - theta * r / 3.0 - p.pair(k).0;
        dev += w.pair(k, r).0 * ed * ed * inp.volumes[j];
    }
    a * theta * theta / inp.c_theta[i] + b * dev
}
