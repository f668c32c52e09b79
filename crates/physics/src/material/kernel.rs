//! The Chen bond loops, generic over the bond weight, the plastic extension and the damage mask.
//! Each variant is monomorphised, so the elastic loop carries no plastic or fracture branch.

use std::cell::RefCell;

use super::lanes::{theta_moment, Row};
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
    /// Particle `i`'s row of bond states (nonzero intact), `None` when every bond is.
    fn row(&self, family: &Family, i: usize) -> Option<&[u8]>;
}

/// No damage state: every bond is intact.
#[derive(Clone, Copy)]
pub(crate) struct AllAlive;

impl Alive for AllAlive {
    #[inline(always)]
    fn alive(&self, _k: usize) -> bool {
        true
    }

    #[inline(always)]
    fn row(&self, _family: &Family, _i: usize) -> Option<&[u8]> {
        None
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

    #[inline(always)]
    fn row(&self, family: &Family, i: usize) -> Option<&[u8]> {
        Some(&self.0[family.range(i)])
    }
}

/// One particle's own row of bond states in a damage check (1 intact, 0 broken), bond `k` at
/// `row[k - first]`: before the check marks any bond (2), intact is nonzero as in [`Mask`].
#[derive(Clone, Copy)]
struct RowMask<'a> {
    row: &'a [u8],
    first: usize,
}

impl Alive for RowMask<'_> {
    #[inline(always)]
    fn alive(&self, k: usize) -> bool {
        self.row[k - self.first] != 0
    }

    #[inline(always)]
    fn row(&self, _family: &Family, _i: usize) -> Option<&[u8]> {
        Some(self.row)
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
    dilatation_most::<W, P, D, MOMENT>(inp, w, p, d, i).0
}

/// [`dilatation`] and the greatest extension it summed (m; minus infinity with no bond).
#[inline(always)]
fn dilatation_most<W: Weights, P: Plastic, D: Alive, const MOMENT: bool>(
    inp: Inputs,
    w: W,
    p: P,
    d: D,
    i: usize,
) -> ((f64, f64), f64) {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let yi = inp.y[i];
    let (mut acc, mut u, mut m) = (0.0, 0.0, 0.0);
    let mut most = f64::NEG_INFINITY;
    for k in fam.range(i) {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let e = norm(sub(inp.y[j], yi)) - r;
        // a plain comparison: a NaN extension is left out (the step guard catches NaN)
        if e > most {
            most = e;
        }
        acc += dilatation_term(w, k, r, inp.volumes[j], e);
        if MOMENT {
            let wrv = w.pair_times_r(k, r).0 * inp.volumes[j];
            u += wrv * (e - p.pair(k).0);
            m += wrv * r;
        }
    }
    let theta = inp.c_theta[i] * acc;
    ((theta, u - theta * m / 3.0), most)
}

/// [`dilatation`] of an elastic particle fused with the damage check: walks `i`'s own bond
/// states `row` (1 intact), marks with 2 the intact bonds `brk` breaks at `inp.y` and leaves
/// them out of the sums, exactly as a check followed by [`dilatation`] would (the same terms in
/// the same order). Returns `(theta_i, S_i)`, the number of bonds it marked and the greatest
/// extension of its intact bonds (m).
///
/// The first walk sums as if nothing broke and keeps the greatest extension: when that is not
/// near breaking, no bond is (the test is monotone in the extension, also in floating point),
/// and the sums are the check's to the bit. Only a particle with a bond near breaking walks
/// again with the check: a branch a bond on the extension costs more than the second walk of
/// the few particles near a crack.
///
/// `lanes`, when given (the isotropic weight, `w`'s own), takes the first walk.
#[inline(always)]
pub(crate) fn dilatation_breaking<W: Weights, const MOMENT: bool>(
    inp: Inputs,
    w: W,
    lanes: Option<Row>,
    brk: &Breaker,
    i: usize,
    row: &mut [u8],
) -> ((f64, f64), u32, f64) {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let range = fam.range(i);
    let first = range.start;
    let (sums, most) = match lanes {
        Some(l) => {
            let (sums, most) = l.dilatation(i, Some(row));
            (theta_moment(inp.c_theta[i], sums, MOMENT), most)
        }
        None => {
            let mask = RowMask { row, first };
            dilatation_most::<W, NoPlastic, _, MOMENT>(inp, w, NoPlastic, mask, i)
        }
    };
    if !brk.near(most) {
        return (sums, 0, most);
    }
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
    ((theta, u - theta * m / 3.0), count, most)
}

/// Per-particle constants of the return map: `b_j`, `(Psi0_j, gamma_ratio_j)` and the
/// `[r_min + r_max, 1 / (r_min r_max), C (1 - 1e-6)]` of [`Yield::all_inside`].
#[derive(Clone, Copy)]
pub(crate) struct Yield<'a> {
    pub coef_b: &'a [f64],
    pub params: &'a [(f64, f64)],
    pub inside: &'a [[f64; 3]],
}

/// Relative margin of [`Yield::all_inside`]'s limit under the yield surface's: far more than
/// the rounding of the return map's own test (a few ulps of the extensions).
const INSIDE_MARGIN: f64 = 1e-6;

/// What the first loop of a plastic first pass sums over particle `i`'s intact bonds besides
/// the dilatation: the moment's parts `u = sum_j omega r (e - ep) V_j` and
/// `m = sum_j omega r^2 V_j`, and the bounds of [`Yield::all_inside`]: the largest
/// `|omega r| |e - ep| (r_min + r_max - r)` (m^2 times the weight) and the largest `|omega r|`.
#[derive(Clone, Copy, Default)]
struct OwnSums {
    u: f64,
    m: f64,
    x: f64,
    wr_max: f64,
}

impl OwnSums {
    /// Adds a bond: `wr = omega r`, neighbour volume `vj` (m^3), rest length `r` (m),
    /// `de = e - ep` (m), `rsum = r_min + r_max` of the particle (m).
    #[inline(always)]
    fn add(&mut self, wr: f64, vj: f64, r: f64, de: f64, rsum: f64) {
        let wrv = wr * vj;
        self.u += wrv * de;
        self.m += wrv * r;
        let x = wr.abs() * de.abs() * (rsum - r);
        // plain comparisons (not `f64::max`, whose NaN rule costs a blend): a NaN extension
        // leaves the bound as it was, and the NaN moment it makes is the step guard's to catch
        if x > self.x {
            self.x = x;
        }
        if wr.abs() > self.wr_max {
            self.wr_max = wr.abs();
        }
    }
}

impl Yield<'_> {
    /// Whether none of particle `i`'s bonds summed in `sums` can be outside the yield surface
    /// at dilatation `theta`, so that the return map would leave every one as it is. A bond is
    /// inside when `|omega r| |ed - ep| <= C r` with `C = sqrt(2 Psi0_i) / (4 b_i)`, and
    /// `|ed - ep| <= |e - ep| + |theta| r / 3`; on `[r_min, r_max]`, `1 / r` lies under its
    /// chord `(r_min + r_max - r) / (r_min r_max)`. So
    /// `max |omega r| |e - ep| (r_min + r_max - r) / (r_min r_max) + |theta| / 3 max |omega r|`
    /// at most `C` keeps every bond inside, with no division a bond; the limit is `C` less
    /// [`INSIDE_MARGIN`], more than the rounding of the map's own test. A NaN anywhere says
    /// no (the bonds are then mapped one by one).
    #[inline(always)]
    fn all_inside(&self, i: usize, sums: &OwnSums, theta: f64) -> bool {
        let [_, inv, limit] = self.inside[i];
        sums.x * inv + theta.abs() / 3.0 * sums.wr_max <= limit
    }

    /// `r_min + r_max` of particle `i`'s bonds (m).
    #[inline(always)]
    fn rsum(&self, i: usize) -> f64 {
        self.inside[i][0]
    }

    /// The return map (docs/model.md, Plasticity) of particle `i`'s end of a bond: `wr` its weight
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

/// Per particle the constants of [`Yield::all_inside`]: the sum and reciprocal product
/// of its least and greatest rest bond lengths, and `sqrt(2 Psi0) / (4 b)` less the margin
/// (infinite for an elastic particle; NaN, which never lets the loop be skipped, where
/// `Psi0 = b = 0`). A particle without bonds gets 0 for both lengths (it has no loop to skip).
pub(crate) fn yield_inside(fam: &Family, coef_b: &[f64], params: &[(f64, f64)]) -> Vec<[f64; 3]> {
    (0..fam.len())
        .map(|i| {
            let rl = &fam.rest_lengths()[fam.range(i)];
            let lo = rl.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = rl.iter().cloned().fold(0.0, f64::max);
            let limit = (2.0 * params[i].0).sqrt() / (4.0 * coef_b[i]) * (1.0 - INSIDE_MARGIN);
            if rl.is_empty() {
                [0.0, 0.0, limit]
            } else {
                [lo + hi, 1.0 / (lo * hi), limit]
            }
        })
        .collect()
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
/// `changed` 1 when it changed any (else 0). `S_i = u - theta_i m / 3` ([`OwnSums`]) as the
/// elastic pass forms it. When [`Yield::all_inside`] shows from the first loop that no bond
/// can yield, the second loop is skipped: its sums would be the first loop's to the bit, so
/// whether a particle skips changes no result. `hint` says which first loop to run: a row
/// whose own ends are all `+0.0` reads none of them; a particle that yielded in the last step
/// most likely yields again and goes straight to the second loop (the bound would be wasted).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dilatation_yield<W: Weights, D: Alive>(
    inp: Inputs,
    w: W,
    d: D,
    yp: Yield,
    i: usize,
    hint: RowHint,
    ep: &mut [[f64; 2]],
    buf: &mut RowBuffer,
    lanes: Option<Row>,
) -> [f64; 4] {
    if let Some((out, _)) = lanes_inside(inp, lanes, yp, i, hint, d.row(inp.family, i)) {
        return out;
    }
    let (theta, sums, _) = first_loop::<_, _, false>(inp, w, d, yp, i, hint, ep, buf);
    finish_yield(inp, w, |k| d.alive(k), yp, i, theta, sums, ep, buf)
}

/// A plastic first pass of particle `i` in lanes where that is quick and sure: a row whose
/// pairs are all `+0.0` (as the elastic loops read it) and that did not yield in the last step,
/// over the bonds `alive` keeps (`None`: all). Returns what [`dilatation_yield`] returns and
/// the greatest extension, when [`Yield::all_inside`] holds (then nothing changes, and the
/// sums are the first loop's to the bit: the same terms in the same order); `None` otherwise,
/// and the scalar walk decides. Not inlined: inlined, it cost the scalar loops of the rows that
/// yield 7% (the walk it is tried before).
#[inline(never)]
fn lanes_inside(
    inp: Inputs,
    lanes: Option<Row>,
    yp: Yield,
    i: usize,
    hint: RowHint,
    alive: Option<&[u8]>,
) -> Option<([f64; 4], f64)> {
    let l = lanes.filter(|_| hint.clean && hint.pairs_clean && !hint.yielded)?;
    let ([acc, u, m], most, x) = l.dilatation_bounded(i, alive, yp.rsum(i));
    let (theta, moment) = theta_moment(inp.c_theta[i], [acc, u, m], true);
    // the weight is isotropic: |omega r| = delta on every bond (the bound is the same with it
    // where the row has no bond: theta is then 0)
    let sums = OwnSums {
        u,
        m,
        x,
        wr_max: l.delta().abs(),
    };
    yp.all_inside(i, &sums, theta)
        .then_some(([theta, moment, 0.0, 0.0], most))
}

/// What a plastic first pass knows of particle `i` before its first loop.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowHint {
    /// Every own end of the row is `+0.0`.
    pub clean: bool,
    /// Every pair of the row, both ends, is `+0.0`.
    pub pairs_clean: bool,
    /// The particle changed one of its own ends in the last step.
    pub yielded: bool,
}

/// [`yield_sums`] for `hint`: [`OwnSums`] only where the bound may save the second loop, and
/// with `BREAKING` the greatest elastic stretch its damage check needs.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn first_loop<W: Weights, D: Alive, const BREAKING: bool>(
    inp: Inputs,
    w: W,
    d: D,
    yp: Yield,
    i: usize,
    hint: RowHint,
    ep: &[[f64; 2]],
    buf: &mut RowBuffer,
) -> (f64, Option<OwnSums>, f64) {
    macro_rules! sums {
        ($clean:literal, $sums:literal) => {{
            let (theta, s, most) = if BREAKING && !hint.pairs_clean {
                yield_sums::<_, _, $clean, $sums, true>(inp, w, d, yp, i, ep, buf)
            } else {
                yield_sums::<_, _, $clean, $sums, false>(inp, w, d, yp, i, ep, buf)
            };
            (theta, $sums.then_some(s), most)
        }};
    }
    match (hint.clean, hint.yielded) {
        (_, true) => sums!(false, false),
        (true, false) => sums!(true, true),
        (false, false) => sums!(false, true),
    }
}

/// The first loop of [`dilatation_yield`] over the bonds `d` keeps: `theta_i`, the
/// [`OwnSums`] and the greatest elastic stretch `e - min(ep_ij, ep_ji)` with `PAIRS` (the
/// greatest extension `e` without, which is the same where every pair is `+0.0`; m, minus
/// infinity with no bond). `buf` keeps each bond's `(e, omega r)`. `CLEAN`: every own end in
/// `ep` is `+0.0`, and none is read for the sums (`e - 0.0` is `e` to the bit). Without `SUMS`
/// the sums are left at 0.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn yield_sums<W: Weights, D: Alive, const CLEAN: bool, const SUMS: bool, const PAIRS: bool>(
    inp: Inputs,
    w: W,
    d: D,
    yp: Yield,
    i: usize,
    ep: &[[f64; 2]],
    buf: &mut RowBuffer,
) -> (f64, OwnSums, f64) {
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let range = fam.range(i);
    let first = range.start;
    let yi = inp.y[i];
    let rsum = yp.rsum(i);
    let mut acc = 0.0;
    let mut sums = OwnSums::default();
    let mut most = f64::NEG_INFINITY;
    for k in range {
        if !d.alive(k) {
            continue;
        }
        let j = nb[k] as usize;
        let r = rl[k];
        let e = norm(sub(inp.y[j], yi)) - r;
        let stretch = if PAIRS {
            let [a, b] = ep[k - first];
            e - if a < b { a } else { b }
        } else {
            e
        };
        if stretch > most {
            most = stretch;
        }
        let wr = w.pair_times_r(k, r).0;
        if let Some(b) = buf.get_mut(k - first) {
            *b = [e, wr];
        }
        let vj = inp.volumes[j];
        acc += dilatation_term(w, k, r, vj, e);
        if SUMS {
            let own = if CLEAN { 0.0 } else { ep[k - first][0] };
            sums.add(wr, vj, r, e - own, rsum);
        }
    }
    (inp.c_theta[i] * acc, sums, most)
}

/// What [`dilatation_yield`] returns after its first loop: with `sums` that pass
/// [`Yield::all_inside`], `S_i = u - theta_i m / 3` from them and nothing changed; otherwise
/// its second loop, the return map of `i`'s own end of the bonds `alive` keeps, and the same
/// `S_i` from the [`OwnSums`] moments `u` (with the new extensions) and `m` after it, summed as
/// the first loop sums them (so the same bits where nothing changed).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn finish_yield<W: Weights>(
    inp: Inputs,
    w: W,
    alive: impl Fn(usize) -> bool,
    yp: Yield,
    i: usize,
    theta: f64,
    sums: Option<OwnSums>,
    ep: &mut [[f64; 2]],
    buf: &RowBuffer,
) -> [f64; 4] {
    if let Some(s) = sums.filter(|s| yp.all_inside(i, s, theta)) {
        return [theta, s.u - theta * s.m / 3.0, 0.0, 0.0];
    }
    let fam = inp.family;
    let range = fam.range(i);
    let first = range.start;
    let yi = inp.y[i];
    let (mut u, mut m, mut least, mut changed) = (0.0, 0.0, 0.0f64, false);
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
        let (_, new) = yp.map(i, wr, || w.pair(k, r).0, theta, e, r, *slot);
        if store_changed(slot, new) {
            least = least.min(new);
            changed = true;
        }
        let wrv = wr * inp.volumes[j];
        u += wrv * (e - new);
        m += wrv * r;
    }
    [
        theta,
        u - theta * m / 3.0,
        least,
        f64::from(u8::from(changed)),
    ]
}

/// [`dilatation_yield`] fused with the damage check: `row` is `i`'s own bond states (1 intact),
/// the bonds `brk` breaks at `inp.y` with the pairs `ep` as they were (whose least value is
/// `floor`) are marked 2 and left out, exactly as a check before [`dilatation_yield`] would.
/// Returns what [`dilatation_yield`] does, the number of bonds it marked and an upper bound (m)
/// on its intact bonds' `e - ep`. As in [`dilatation_breaking`], a first walk sums as if
/// nothing broke, and only a particle with a bond near breaking walks again with the check. `hint` as for [`dilatation_yield`].
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn dilatation_yield_breaking<W: Weights>(
    inp: Inputs,
    w: W,
    brk: &Breaker,
    floor: f64,
    yp: Yield,
    i: usize,
    hint: RowHint,
    row: &mut [u8],
    ep: &mut [[f64; 2]],
    buf: &mut RowBuffer,
    lanes: Option<Row>,
) -> ([f64; 4], u32, f64) {
    if let Some((out, most)) = lanes_inside(inp, lanes, yp, i, hint, Some(row)) {
        // every pair is +0.0: the greatest elastic stretch is the greatest extension
        if !brk.near(most) {
            return (out, 0, most);
        }
    }
    let fam = inp.family;
    let nb = fam.neighbours();
    let rl = fam.rest_lengths();
    let range = fam.range(i);
    let first = range.start;
    let mask = RowMask { row, first };
    let (theta, sums, most) = first_loop::<_, _, true>(inp, w, mask, yp, i, hint, ep, buf);
    // e - ep <= e - min(ep_ij, ep_ji) <= most for both ends of every bond, also in floating
    // point (subtraction rounds monotonically)
    if !brk.near(most) {
        let out = finish_yield(inp, w, |k| mask.alive(k), yp, i, theta, sums, ep, buf);
        return (out, 0, most);
    }
    let yi = inp.y[i];
    let rsum = yp.rsum(i);
    let mut acc = 0.0;
    let mut sums = OwnSums::default();
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
        let wr = w.pair_times_r(k, r).0;
        if let Some(b) = buf.get_mut(k - first) {
            *b = [e, wr];
        }
        let vj = inp.volumes[j];
        acc += dilatation_term(w, k, r, vj, e);
        sums.add(wr, vj, r, e - epij, rsum);
    }
    let theta = inp.c_theta[i] * acc;
    let alive = |k: usize| row[k - first] == 1;
    let sums = if hint.yielded { None } else { Some(sums) };
    let out = finish_yield(inp, w, alive, yp, i, theta, sums, ep, buf);
    (out, count, most)
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
            // one reciprocal a bond in place of two divisions (`isotropic_pair`)
            let ep = ep_of(k, j, e, r);
            let dil = W::SPLIT.then(|| w.dil_pair(k, r));
            let ends = [[pi, qi, bi], [pj, qj, coef_b[j]]];
            isotropic_pair(delta, r, l, ends, ep, dil, vi * inp.volumes[j])
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

/// The pair scalar `s` (the force on `i` is `s eta` summed) of a bond with the isotropic weight
/// `omega = delta / r` both ways: rest length `r` and length `l` (m), `ends` the two ends'
/// `[p, q, b]`, plastic extensions `(ep_ij, ep_ji)` (m), the fitted dilatation weights
/// `(d_ij, d_ji)` when used, and `vv = V_i V_j` (m^6). `r (A_ij + A_ji) / 4` needs no division,
/// and one reciprocal of `r l` serves both the weight and the direction. Every sum and product
/// pairs the two ends' terms commutatively, so `s` is bitwise the same from both ends. The
/// scalar loops' own formula, the vector loops' (`lanes.rs`) model and their tails'.
#[inline(always)]
pub(crate) fn isotropic_pair(
    delta: f64,
    r: f64,
    l: f64,
    ends: [[f64; 3]; 2],
    (epij, epji): (f64, f64),
    dil: Option<(f64, f64)>,
    vv: f64,
) -> f64 {
    let [[pi, qi, bi], [pj, qj, bj]] = ends;
    let e = l - r;
    let inv = 1.0 / (r * l);
    let bsum = bi * (e - epij) + bj * (e - epji);
    let t = match dil {
        Some((dij, dji)) => r * (dij * pi + dji * pj) + delta * (bsum - (qi + qj) * r),
        None => delta * ((pi + pj) + bsum - (qi + qj) * r),
    };
    2.0 * t * vv * inv
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::Discretization;
    use perifrac_topology::primitives::box_data;
    use perifrac_topology::TetMesh;

    /// [`dilatation_yield`] of a particle: `(i, its pairs, hint, buffer)`.
    type Pass<'a> = &'a dyn Fn(usize, &mut [[f64; 2]], RowHint, &mut RowBuffer) -> [f64; 4];
    /// [`finish_yield`] without sums (the return-map loop forced): `(i, theta, its pairs,
    /// buffer)`.
    type Walk<'a> = &'a dyn Fn(usize, f64, &mut [[f64; 2]], &RowBuffer) -> [f64; 4];
    /// [`yield_sums`]' sums of a particle: `(i, its pairs, buffer)`.
    type Sums<'a> = &'a dyn Fn(usize, &[[f64; 2]], &mut RowBuffer) -> OwnSums;

    /// A small pseudo-random generator (xorshift), uniform on `[-1, 1)`.
    struct Noise(u64);

    impl Noise {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    /// The first pass's shortcut, [`Yield::all_inside`], skips the return-map loop only where
    /// that loop would change nothing, and the result does not depend on the path: over
    /// particles of a 4-cell block deformed by a shear, a swelling and noise, with random
    /// plastic extensions and yield limits spread around the deviatoric stress they see
    /// (isotropic and per-bond weights), [`dilatation_yield`] gives the same `theta`, moment,
    /// least value, flag and extensions, bit for bit, whatever its [`RowHint`] (a clean row of
    /// `+0.0` read as clean or not, the bound tried or not) and as the return-map loop forced.
    #[test]
    fn the_first_pass_skips_only_return_maps_that_change_nothing() {
        let (v, t) = box_data([0.0; 3], [0.04; 3], [4; 3]);
        let (mesh, _) = TetMesh::new(v, t).unwrap();
        let delta = 1.5 * mesh.mean_edge_length();
        let (disc, _) = Discretization::from_tets(
            &mesh.rest_barycentres(),
            &mesh.rest_volumes(),
            mesh.neighbours(),
            delta,
        )
        .unwrap();
        let fam = disc.family();
        let n = disc.len();
        let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
        let y: Vec<Vec3> = disc
            .rest_positions()
            .iter()
            .map(|p| {
                // a shear g and a swelling s as large: theta matters to the bound
                let (g, s) = (2e-3, 1.0 + 2e-3);
                [
                    s * p[0] + g * p[2] + 2e-5 * noise.next(),
                    s * p[1] + 2e-5 * noise.next(),
                    s * p[2] + 2e-5 * noise.next(),
                ]
            })
            .collect();
        let c_theta = vec![9.0 / (4.0 * std::f64::consts::PI * delta.powi(4)); n];
        let inp = Inputs {
            family: fam,
            y: &y,
            volumes: disc.volumes(),
            c_theta: &c_theta,
        };
        let b = 15.0 * 80e9 / (2.0 * std::f64::consts::PI * delta.powi(5));
        let coef_b = vec![b; n];
        // A_dev = 4 omega b ed with omega r = delta reaches about 4 delta b g / 2 under the
        // shear g = 2e-3: yield limits from a tenth to ten times that, a third of the
        // particles elastic
        let a_shear = 4.0 * delta * b * 1e-3;
        let params: Vec<(f64, f64)> = (0..n)
            .map(|i| match i % 3 {
                0 => (f64::INFINITY, f64::INFINITY),
                _ => {
                    let a = a_shear * 10f64.powf(noise.next());
                    (0.5 * a * a, 0.05)
                }
            })
            .collect();
        let inside = yield_inside(fam, &coef_b, &params);
        let yp = Yield {
            coef_b: &coef_b,
            params: &params,
            inside: &inside,
        };
        // plastic extensions: every fourth row all +0.0; every fourth the bonds' extensions
        // to within a few per cent (the elastic part e - ep is then small, and the swelling's
        // theta r / 3 decides whether a bond yields); the rest random, as large as the shear's
        let mut ep = vec![[0.0; 2]; fam.num_bonds()];
        for i in (0..n).filter(|i| i % 4 != 0) {
            for k in fam.range(i) {
                let r = fam.rest_lengths()[k];
                ep[k][0] = if i % 4 == 3 {
                    let e = norm(sub(y[fam.neighbours()[k] as usize], y[i])) - r;
                    e * (1.0 + 0.03 * noise.next())
                } else {
                    1e-3 * r * noise.next()
                };
            }
        }
        let weights: Vec<f64> = (0..fam.num_bonds())
            .map(|k| delta / fam.rest_lengths()[k] * (1.0 + 0.3 * noise.next()))
            .collect();
        let rev = fam.reverse_index();
        let per_bond = PerBond {
            w: &weights,
            rev: &rev,
        };
        let mut counts = [0usize; 3];
        let mut check = |w: Pass, walk: Walk, sums: Sums| {
            let mut buf = [[0.0; 2]; ROW_BUFFER];
            for i in 0..n {
                let r = fam.range(i);
                let bits = |o: [f64; 4], e: &[[f64; 2]]| {
                    let mut b: Vec<u64> = o.iter().map(|v| v.to_bits()).collect();
                    b.extend(e.iter().map(|p| p[0].to_bits()));
                    b
                };
                // the bound's path, then the others the hint may pick: the same bits
                let clean = i % 4 == 0;
                let mut a = ep[r.clone()].to_vec();
                let hint = RowHint {
                    clean,
                    pairs_clean: clean,
                    yielded: false,
                };
                let got = w(i, &mut a, hint, &mut buf);
                for (clean, yielded) in [(false, false), (false, true), (clean, true)] {
                    let mut d = ep[r.clone()].to_vec();
                    let hint = RowHint {
                        clean,
                        pairs_clean: clean,
                        yielded,
                    };
                    let other = w(i, &mut d, hint, &mut buf);
                    assert!(
                        bits(got, &a) == bits(other, &d),
                        "particle {i}: hint ({clean}, {yielded}) differs"
                    );
                }
                // the return-map loop forced: the same extensions, flag, least value
                // and moment, bit for bit
                let mut c = ep[r.clone()].to_vec();
                let s = sums(i, &c, &mut buf);
                let forced = walk(i, got[0], &mut c, &buf);
                let changed = forced[3] != 0.0;
                assert!(
                    bits(got, &a) == bits(forced, &c),
                    "particle {i}: differs from the loop"
                );
                let skipped = yp.all_inside(i, &s, got[0]);
                counts[if skipped {
                    0
                } else if changed {
                    1
                } else {
                    2
                }] += 1;
            }
        };
        macro_rules! run {
            ($w:expr) => {{
                let w = $w;
                check(
                    &|i, e, hint, buf| {
                        dilatation_yield(inp, w, AllAlive, yp, i, hint, e, buf, None)
                    },
                    &|i, theta, e, buf| finish_yield(inp, w, |_| true, yp, i, theta, None, e, buf),
                    &|i, e, buf| {
                        yield_sums::<_, _, false, true, false>(inp, w, AllAlive, yp, i, e, buf).1
                    },
                );
            }};
        }
        run!(Isotropic { delta });
        run!(per_bond);
        // measured: 310 of 768 particle-passes skipped, 406 walked and changed, 52 walked for
        // nothing: every path is taken
        eprintln!("skipped, changed, walked for nothing: {counts:?}");
        assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
    }
}
