//! The fitted dilatation of Xu's model (issue 18; `XuOptions::fitted_dilatation`). Xu's
//! normalised weights `w_ij = wt_ij / sum_j wt_ij V_j` read `theta_i - 1 = sum_j w_ij V_j
//! (tau_ij - 1)`, which under a small uniform strain is `M_i : eps` with the family's moment
//! `M_i = sum_j w_ij V_j n n`: `I / 3` on a full family, but on a family cut unevenly (edges,
//! corners) a shear then reads as a volume change. The fit replaces `w_ij` in the dilatation by
//! `d_ij = wt_ij (n n : L_i) / 3` with one symmetric tensor `L_i` per particle such that
//! `sum_j d_ij V_j n n = I / 3` over the intact family (as `fit.rs` does for Chen's model):
//! every uniform small strain then gives `theta_i - 1 = tr(eps) / 3` on every particle, and
//! `sum_j d_ij V_j = tr(I / 3) = 1` keeps `theta` at 1 at rest. The bond term keeps the
//! normalised `w_ij`.
//!
//! Stored per directed bond, over the particle's normalisation `inv_i = 1 / sum_j wt_ij V_j`:
//! `f_ij = d_ij / (inv_i r_ij)`, which is `wt_ij / r_ij` (`wr`) times the fit's factor
//! `g_ij = (n n : L_i) / (3 inv_i)` (1 for a family symmetric enough), so the force loop's pressure
//! term `p_i wr_ij` becomes `p_i f_ij`. A factor past [`FIT_BOUND`] in magnitude blends the
//! particle towards the normalised weights as Chen's fit does. A particle that loses a bond goes
//! back on the normalised weights over its intact bonds: fitted again there, a family just cut by
//! a crack takes the largest factors on the few bonds left and its pressure holds the crack shut
//! (docs/DECISIONS.md, "The fitted dilatation in Xu's model").
//!
//! Springs that bound the dilatation term's Hessian by Cauchy-Schwarz,
//! `(sum_j d_ij V_j a_j)^2 <= S_i sum_j |d_ij| V_j a_j^2` with `S_i = sum_j |d_ij| V_j` (more than
//! 1 where the fit's corner weights are negative), are `V_i V_j lambda_i g_i''(1) S_i |d_ij| /
//! r^2`: the explicit fallback estimate of the stable step takes them; the implicit step matrix
//! keeps the normalised weights' springs, a better preconditioner (measured).

// Small dense systems: index loops read as the formulas do.
#![allow(clippy::needless_range_loop)]

use super::chen::{FIT_BOUND, FIT_RIDGE};
use super::fit::{fit_tensors, mandel, Spread, ISOTROPIC_TARGET};
use crate::family::Family;
use crate::math::{sub, Vec3};
use crate::par::{for_each_row, for_rows_mut};

/// The fitted pressure weights of one Xu model.
#[derive(Debug, Clone)]
pub(crate) struct XuFit {
    /// Per directed bond `k` of `i` to `j`: `[f_ij, f_ji]` (1/m), the owner's weight and the
    /// reverse bond's, so the force loop reads both in one stream.
    pairs: Vec<[f64; 2]>,
    /// Per particle, `S_i = sum_j |d_ij| V_j` over the intact bonds (1 with no negative
    /// weight; 0 without bonds).
    spread: Vec<f64>,
    /// The reverse of each directed bond.
    rev: Vec<u32>,
    /// Per particle, its factor of largest magnitude `d_ij / w_ij` at setup.
    correction: Spread,
}

/// What one fit reads of the model.
#[derive(Clone, Copy)]
pub(crate) struct FitInputs<'a> {
    /// The family.
    pub family: &'a Family,
    /// Rest positions (m).
    pub x: &'a [Vec3],
    /// Particle volumes (m^3).
    pub volumes: &'a [f64],
    /// `wt / r` per directed bond (1/m).
    pub wr: &'a [f64],
    /// `1 / sum_j wt_ij V_j` over the intact bonds (1/m^3; 0 without any).
    pub inv_norm: &'a [f64],
    /// The bonds' states (non-zero: intact), `None` when nothing can break.
    pub alive: Option<&'a [u8]>,
}

impl FitInputs<'_> {
    #[inline]
    fn alive(&self, k: usize) -> bool {
        self.alive.is_none_or(|a| a[k] != 0)
    }
}

/// Writes `f_ij` of every bond of particle `i` into `row` from its fitted tensor `l`, or,
/// once it has lost a bond, the normalised weights. Returns the factor of largest magnitude (1
/// when none passes 1) and `S_i`.
fn fit_row(inp: FitInputs, i: usize, l: &[f64; 6], row: &mut [f64]) -> (f64, f64) {
    let fam = inp.family;
    let (nb, rl) = (fam.neighbours(), fam.rest_lengths());
    let inv = inp.inv_norm[i];
    let range = fam.range(i);
    if !range.clone().all(|k| inp.alive(k)) {
        // a particle that lost a bond is back on the normalised weights
        return (1.0, normalised_row(inp, i, row));
    }
    let direction = |k: usize| -> Vec3 {
        let j = nb[k] as usize;
        sub(inp.x[j], inp.x[i]).map(|c| c / rl[k])
    };
    // `L_i` of `fit.rs`'s fit with `omega = wt / r` (its moment `sum_j omega r V q q^T` is Xu's
    // `sum_j wt V q q^T`) and target I, ridged towards `L = 3 inv I`, the normalised weights
    let c = 3.0 * inv;
    // the fit's factors over the normalised weights, and the largest departure from 1
    let mut far: f64 = 0.0;
    for (slot, k) in row.iter_mut().zip(range.clone()) {
        let q = mandel(direction(k));
        let g = (0..6).map(|p| q[p] * l[p]).sum::<f64>() / c;
        *slot = g;
        far = far.max((g - 1.0).abs());
    }
    // |1 + a (g - 1)| <= 1 + a |g - 1| <= FIT_BOUND
    let blend = if far > FIT_BOUND - 1.0 {
        (FIT_BOUND - 1.0) / far
    } else {
        1.0
    };
    let (mut most, mut spread) = (1.0f64, 0.0);
    for (slot, k) in row.iter_mut().zip(range) {
        let g = 1.0 + blend * (*slot - 1.0);
        *slot = inp.wr[k] * g;
        spread += (*slot * rl[k]).abs() * inp.volumes[nb[k] as usize];
        if g.abs() > most.abs() {
            most = g;
        }
    }
    (most, inv * spread)
}

/// Writes the normalised weights' `wr` into particle `i`'s `row` and returns `S_i` (1 to
/// rounding; 0 without intact bonds).
fn normalised_row(inp: FitInputs, i: usize, row: &mut [f64]) -> f64 {
    let fam = inp.family;
    let (nb, rl) = (fam.neighbours(), fam.rest_lengths());
    let mut spread = 0.0;
    for (slot, k) in row.iter_mut().zip(fam.range(i)) {
        *slot = inp.wr[k];
        if inp.alive(k) {
            spread += (*slot * rl[k]).abs() * inp.volumes[nb[k] as usize];
        }
    }
    inp.inv_norm[i] * spread
}

impl XuFit {
    /// Fits every particle over its intact bonds.
    pub(crate) fn new(inp: FitInputs) -> XuFit {
        let fam = inp.family;
        let mut fit = XuFit {
            pairs: vec![[0.0; 2]; fam.num_bonds()],
            spread: vec![0.0; fam.len()],
            rev: fam.reverse_index(),
            correction: Spread::of(Vec::new()),
        };
        let most = fit.set_all(inp);
        fit.correction = Spread::of(most);
        fit
    }

    /// Fits every particle whose bonds are all intact, and puts the others on the normalised
    /// weights (at setup, and after a checkpoint's damage is read back: the same bits as the
    /// weights left as the bonds broke, each particle's being a function of its intact bonds
    /// alone). Returns each particle's factor of largest magnitude.
    pub(crate) fn set_all(&mut self, inp: FitInputs) -> Vec<f64> {
        let fam = inp.family;
        let c: Vec<f64> = inp.inv_norm.iter().map(|inv| 3.0 * inv).collect();
        let one_target = vec![0u16; fam.len()];
        let target = (&[ISOTROPIC_TARGET][..], one_target.as_slice());
        let (delta, wr) = (0.0, Some(inp.wr));
        let l = fit_tensors(fam, inp.x, inp.volumes, wr, delta, &c, target, FIT_RIDGE);
        let mut own = vec![0.0; fam.num_bonds()];
        let mut per = vec![(1.0, 0.0); fam.len()];
        for_rows_mut(
            fam.offsets(),
            &mut per,
            &mut own,
            &|first, per: &mut [(f64, f64)], own: &mut [f64]| {
                let base = fam.offsets()[first] as usize;
                for (i, slot) in (first..).zip(per.iter_mut()) {
                    let r = fam.range(i);
                    *slot = fit_row(inp, i, &l[i], &mut own[r.start - base..r.end - base]);
                }
            },
        );
        let rev = &self.rev;
        for_each_row(
            fam.offsets(),
            &mut self.pairs,
            &|i, row: &mut [[f64; 2]]| {
                for (slot, k) in row.iter_mut().zip(fam.range(i)) {
                    *slot = [own[k], own[rev[k] as usize]];
                }
            },
        );
        for (s, p) in self.spread.iter_mut().zip(&per) {
            *s = p.1;
        }
        per.into_iter().map(|p| p.0).collect()
    }

    /// Puts particle `i`, which lost a bond, back on the normalised weights: its own bonds and
    /// their reverses.
    pub(crate) fn unfit(&mut self, inp: FitInputs, i: usize, buf: &mut Vec<f64>) {
        let range = inp.family.range(i);
        buf.clear();
        buf.resize(range.len(), 0.0);
        self.spread[i] = normalised_row(inp, i, buf);
        for (k, &f) in range.zip(buf.iter()) {
            self.pairs[k][0] = f;
            self.pairs[self.rev[k] as usize][1] = f;
        }
    }

    /// `[f_ij, f_ji]` per directed bond (1/m).
    pub(crate) fn pairs(&self) -> &[[f64; 2]] {
        &self.pairs
    }

    /// `S_i` of particle `i`.
    #[inline]
    pub(crate) fn spread(&self, i: usize) -> f64 {
        self.spread[i]
    }

    /// The factors' spread at setup: per particle, its `d_ij / w_ij` of largest magnitude.
    pub(crate) fn correction(&self) -> Spread {
        self.correction
    }

    /// Heap bytes.
    pub(crate) fn memory_bytes(&self) -> usize {
        16 * self.pairs.len() + 8 * self.spread.len() + 4 * self.rev.len()
    }
}
