//! Bond breaking (docs/model.md section 2, Fracture): `sw = (e - ep) / delta` against the threshold
//! `s_crit (1 + alpha phi)`, from either side, tension only, permanent and in both directions.

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use crate::family::Family;
use crate::material::kernel::Plastic;
use crate::math::{norm, sub, Vec3};
use crate::par::{for_rows, map_particles};

/// Damage state: which bonds are intact, and the per-particle counts behind `phi`.
#[derive(Debug, Clone)]
pub struct Damage {
    /// Per directed bond: 1 intact, 0 broken, 2 broken in the current check (0 after it).
    state: Vec<u8>,
    /// The particles before this one are counted in `phi`; a bond with an end from it on (a
    /// passive particle's, a ghost's) breaks as any other but counts towards no `phi`.
    counted: usize,
    initial: Vec<u32>,
    intact: Vec<u32>,
    s_crit: Vec<f64>,
    alpha: Vec<f64>,
    threshold: Vec<f64>,
    new_count: Vec<u32>,
    /// Largest `sw / threshold - 1` over the bonds the last check broke (0 when none broke).
    overshoot: f64,
    /// Per particle, the largest `sw / threshold` its intact bonds reached at any check
    /// (an upper bound with plastic extensions).
    peak: Vec<f64>,
}

impl Damage {
    /// All bonds intact; `s_crit` and `alpha` per particle (infinite `s_crit`: never breaks).
    pub(crate) fn new(family: &Family, s_crit: Vec<f64>, alpha: Vec<f64>) -> Self {
        Self::with_counted(family, s_crit, alpha, family.len())
    }

    /// [`Damage::new`] with only the bonds between the first `counted` particles counted in
    /// `phi` (a ghost layer's real particles: its ghosts' bonds break but are not damage, and a
    /// ghost's `phi` stays 0).
    pub(crate) fn with_counted(
        family: &Family,
        s_crit: Vec<f64>,
        alpha: Vec<f64>,
        counted: usize,
    ) -> Self {
        let n = family.len();
        let nb = family.neighbours();
        let initial: Vec<u32> = (0..n)
            .map(|i| {
                if i >= counted {
                    return 0;
                }
                family
                    .range(i)
                    .filter(|&k| (nb[k] as usize) < counted)
                    .count() as u32
            })
            .collect();
        Damage {
            state: vec![1; family.num_bonds()],
            counted,
            intact: initial.clone(),
            initial,
            s_crit,
            alpha,
            threshold: vec![0.0; n],
            new_count: vec![0; n],
            overshoot: 0.0,
            peak: vec![0.0; n],
        }
    }

    /// Sets the threshold `s_crit` (1) of particle `i` (a threshold set from a fracture energy,
    /// once the model's families are known).
    pub(crate) fn set_s_crit(&mut self, i: usize, s_crit: f64) {
        self.s_crit[i] = s_crit;
    }

    /// Damage `phi_i = 1 - n_i / N_i` (0 for a particle that never had bonds).
    pub fn phi(&self, i: usize) -> f64 {
        if self.initial[i] == 0 {
            0.0
        } else {
            1.0 - self.intact[i] as f64 / self.initial[i] as f64
        }
    }

    /// Intact flag per directed bond (1 intact, 0 broken).
    pub fn bond_state(&self) -> &[u8] {
        &self.state
    }

    /// Per particle, the largest share of its threshold, `sw / (s_crit (1 + alpha phi))`, that
    /// any of its bonds reached at a check so far (1). A bond that broke reached 1 or more.
    /// With plastic extensions the value is an upper bound.
    pub fn peak_share(&self) -> &[f64] {
        &self.peak
    }

    /// Whether particle `i` can break bonds (a finite `s_crit`).
    pub fn can_break(&self, i: usize) -> bool {
        self.s_crit[i].is_finite()
    }

    /// Writes the bond states and the peak shares for a checkpoint (the per-particle counts
    /// follow from the states).
    pub(crate) fn save(&self, w: &mut Writer) {
        w.tag("damage");
        w.array(&self.state);
        w.array(&self.peak);
    }

    /// Reads what [`Damage::save`] wrote and recounts the intact bonds of every particle.
    pub(crate) fn restore(
        &mut self,
        family: &Family,
        r: &mut Reader,
    ) -> Result<(), CheckpointError> {
        r.tag("damage")?;
        r.array_into("bond states", &mut self.state)?;
        r.array_into("peak shares", &mut self.peak)?;
        if let Some(&b) = self.state.iter().find(|&&b| b > 1) {
            return Err(CheckpointError::Invalid {
                what: "bond states".into(),
                message: format!("state {b} is neither intact (1) nor broken (0)"),
            });
        }
        self.recount(family);
        Ok(())
    }

    /// Recounts every particle's intact counted bonds from the states.
    fn recount(&mut self, family: &Family) {
        let (nb, counted) = (family.neighbours(), self.counted);
        for (i, c) in self.intact.iter_mut().enumerate() {
            *c = if i >= counted {
                0
            } else {
                family
                    .range(i)
                    .filter(|&k| self.state[k] == 1 && (nb[k] as usize) < counted)
                    .count() as u32
            };
        }
    }

    /// Cuts the particles `newly` (none counted in `phi`) out of every family: their bonds and
    /// their reverses become broken. Such bonds count towards no `phi`, so the counts stay.
    pub(crate) fn isolate(&mut self, family: &Family, newly: &[u32]) {
        let nb = family.neighbours();
        for &p in newly {
            let p = p as usize;
            for k in family.range(p) {
                let j = nb[k] as usize;
                if let Some(r) = family.range(j).find(|&r| nb[r] as usize == p) {
                    self.state[r] = 0;
                }
                self.state[k] = 0;
            }
        }
    }

    /// The states of the bonds of `real` (a family whose particle `i`'s row is the first
    /// `real.range(i).len()` bonds of `ext`'s row `i`, as a ghost layer extends it) copied
    /// from `ext_damage` over `ext` into this damage state over `real`, the counts and the
    /// overshoot with them: `phi` over the real bonds, as `ext_damage` counts it when it
    /// counts the real particles alone.
    pub(crate) fn copy_real(&mut self, real: &Family, ext: &Family, ext_damage: &Damage) {
        for i in 0..real.len() {
            let (r, e) = (real.range(i), ext.range(i).start);
            let n = r.len();
            self.state[r.clone()].copy_from_slice(&ext_damage.state[e..e + n]);
            self.intact[i] = self.state[r].iter().map(|&b| u32::from(b)).sum();
        }
        self.overshoot = ext_damage.overshoot;
        self.peak.copy_from_slice(&ext_damage.peak[..real.len()]);
    }

    /// Sets the overshoot to 0, as a check that broke nothing does.
    pub(crate) fn clear_overshoot(&mut self) {
        self.overshoot = 0.0;
    }

    /// A damage state over `real`, all bonds intact, with the thresholds of this one's first
    /// `real.len()` particles (see [`Damage::copy_real`]).
    pub(crate) fn for_real(&self, real: &Family) -> Damage {
        let n = real.len();
        Damage::new(real, self.s_crit[..n].to_vec(), self.alpha[..n].to_vec())
    }

    /// Number of intact directed bonds.
    pub fn intact_bonds(&self) -> usize {
        self.intact.iter().map(|&c| c as usize).sum()
    }

    /// Heap bytes.
    pub fn memory_bytes(&self) -> usize {
        let Damage {
            state,
            counted: _,
            initial,
            intact,
            s_crit,
            alpha,
            threshold,
            new_count,
            overshoot: _,
            peak,
        } = self;
        state.len()
            + (initial.len() + intact.len() + new_count.len()) * 4
            + (s_crit.len() + alpha.len() + threshold.len() + peak.len()) * 8
    }

    /// Breaks bonds at positions `y` (m), horizon `delta` (m), plastic extensions `p` of which
    /// none is less than `floor` (m, at most 0; 0 without plasticity); appends the newly broken
    /// pairs `(i, j)`, `i < j`, in increasing order.
    pub(crate) fn check<P: Plastic>(
        &mut self,
        family: &Family,
        y: &[Vec3],
        delta: f64,
        (p, floor): (P, f64),
        broken: &mut Vec<(u32, u32)>,
    ) {
        // zero-sized: no storage
        let mut none = vec![(); family.len()];
        let mut no_bonds = vec![(); family.num_bonds()];
        // (e - ep) <= (e - floor) for every plastic extension ep, also in floating point, so a
        // bond whose (e - floor) is below the least threshold cannot break.
        let out = (&mut none[..], &mut no_bonds[..]);
        self.visit_check(family, delta, out, &|i, row, _: &mut [()], brk| {
            let first = family.range(i).start;
            let yi = y[i];
            let mut count = 0;
            // e - floor bounds e - ep from above
            let mut most = 0.0f64;
            for k in family.range(i) {
                if row[k - first] != 1 {
                    continue;
                }
                let j = family.neighbours()[k] as usize;
                let e = norm(sub(y[j], yi)) - family.rest_lengths()[k];
                most = most.max(e - floor);
                // Bonds far from breaking skip the plastic extensions' loads.
                if brk.near(e - floor) && brk.breaks(i, j, e, p.pair(k)) {
                    row[k - first] = 2;
                    count += 1;
                }
            }
            ((), count, most)
        });
        self.finish_check(family, y, delta, p, broken);
    }

    /// The bond pass of a check, `visit`'s: for each particle `i`,
    /// `visit(i, row, bond_row, breaker)` walks `i`'s own bond states `row` (1 intact, 0
    /// broken), marks with 2 the intact bonds that [`Breaker::breaks`] says go now, and returns
    /// what it computed for `i` (stored in `out.0[i]`) with the number it marked and an upper
    /// bound (m) on its intact bonds' `e - ep` (for [`Damage::peak_share`]); `bond_row` is
    /// `i`'s slice of the per-bond `out.1`, the visitor's own. Since the criterion is symmetric
    /// both ends of a bond decide alike, so a force model can fuse the check into a bond loop of
    /// its own and skip the bonds it breaks there. [`Damage::finish_check`] must follow.
    pub(crate) fn visit_check<T: Send, B: Send, F>(
        &mut self,
        family: &Family,
        delta: f64,
        out: (&mut [T], &mut [B]),
        visit: &F,
    ) where
        F: Fn(usize, &mut [u8], &mut [B], &Breaker) -> (T, u32, f64) + Sync,
    {
        {
            let (s_crit, alpha) = (&self.s_crit, &self.alpha);
            let (initial, intact) = (&self.initial, &self.intact);
            map_particles(&mut self.threshold, |i| {
                let phi = if initial[i] == 0 {
                    0.0
                } else {
                    1.0 - intact[i] as f64 / initial[i] as f64
                };
                s_crit[i] * (1.0 + alpha[i] * phi)
            });
        }
        let brk = Breaker {
            threshold: &self.threshold,
            // A serial minimum, one read per particle: one parallel call fewer per step.
            least: self.threshold.iter().cloned().fold(f64::INFINITY, f64::min),
            inv_delta: 1.0 / delta,
        };
        let offsets = family.offsets();
        let n = family.len();
        let inv_delta = 1.0 / delta;
        let threshold = &self.threshold;
        let per_particle = ((&mut self.new_count[..], &mut self.peak[..]), out.0);
        for_rows(
            offsets,
            n,
            per_particle,
            (&mut self.state[..], out.1),
            &|first,
              ((counts, peaks), outs): ((&mut [u32], &mut [f64]), &mut [T]),
              (state, bonds): (&mut [u8], &mut [B])| {
                let base = offsets[first] as usize;
                let slots = counts.iter_mut().zip(peaks.iter_mut()).zip(outs.iter_mut());
                for (o, ((count, peak), slot)) in slots.enumerate() {
                    let i = first + o;
                    let r = r_of(family, i, base);
                    let (value, c, most) = visit(i, &mut state[r.clone()], &mut bonds[r], &brk);
                    *slot = value;
                    *count = c;
                    *peak = peak.max(most * inv_delta / threshold[i]);
                }
            },
        );
    }

    /// Ends a check after [`Damage::visit_check`]: the bonds marked 2 become broken (0), their
    /// pairs `(i, j)`, `i < j`, are appended to `broken` in increasing order, and the overshoot
    /// is measured at positions `y` (m) with the plastic extensions `p` the check used (the
    /// marked bonds' own: a visitor changes no broken bond's).
    pub(crate) fn finish_check<P: Plastic>(
        &mut self,
        family: &Family,
        y: &[Vec3],
        delta: f64,
        p: P,
        broken: &mut Vec<(u32, u32)>,
    ) {
        let inv_delta = 1.0 / delta;
        self.overshoot = 0.0;
        for i in 0..family.len() {
            if self.new_count[i] == 0 {
                continue;
            }
            for k in family.range(i) {
                if self.state[k] == 2 {
                    self.state[k] = 0;
                    let j = family.neighbours()[k];
                    // only bonds between counted particles move `phi`
                    if i < self.counted && (j as usize) < self.counted {
                        self.intact[i] -= 1;
                    }
                    if j as usize > i {
                        broken.push((i as u32, j));
                    }
                    // how far past its threshold the bond went, from the side that broke it
                    let e = norm(sub(y[j as usize], y[i])) - family.rest_lengths()[k];
                    let (epij, epji) = p.pair(k);
                    let over = ((e - epij) * inv_delta / self.threshold[i])
                        .max((e - epji) * inv_delta / self.threshold[j as usize])
                        - 1.0;
                    self.overshoot = self.overshoot.max(over);
                }
            }
        }
    }

    /// Largest relative overshoot `sw / threshold - 1` of the bonds the last check broke, from
    /// the end that broke each (0 when none broke): how late the step saw them go.
    pub fn last_overshoot(&self) -> f64 {
        self.overshoot
    }
}

/// Particle `i`'s bonds as indices into a block's slice that starts at bond `base`.
fn r_of(family: &Family, i: usize, base: usize) -> std::ops::Range<usize> {
    let r = family.range(i);
    r.start - base..r.end - base
}

/// The breaking criterion of one check: thresholds per particle and `1 / delta`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Breaker<'a> {
    threshold: &'a [f64],
    /// The least threshold of all particles.
    least: f64,
    inv_delta: f64,
}

impl Breaker<'_> {
    /// Whether the bond from `i` to `j` with extension `e` (m) and plastic extensions
    /// `(ep_ij, ep_ji)` (m) breaks: in tension, `(e - ep) / delta` past either end's threshold.
    /// Symmetric: the bond's other end gets the same answer.
    #[inline(always)]
    pub(crate) fn breaks(&self, i: usize, j: usize, e: f64, (epij, epji): (f64, f64)) -> bool {
        // Non-short-circuit `&` and `|`: the signs of tiny extensions go either way from bond
        // to bond, which a branch would follow badly.
        (e > 0.0)
            & (((e - epij) * self.inv_delta > self.threshold[i])
                | ((e - epji) * self.inv_delta > self.threshold[j]))
    }

    /// [`Breaker::breaks`] without plastic extension, which first compares the stretch with
    /// the least threshold: most bonds are far below it, and they then cost neither the
    /// thresholds' loads nor a branch that could go either way.
    #[inline(always)]
    pub(crate) fn breaks_elastic(&self, i: usize, j: usize, e: f64) -> bool {
        self.near(e) && self.breaks(i, j, e, (0.0, 0.0))
    }

    /// Whether a stretch of `e` (m), an upper bound on a bond's elastic extension, passes the
    /// least threshold: if not, the bond cannot break.
    #[inline(always)]
    pub(crate) fn near(&self, e: f64) -> bool {
        e * self.inv_delta > self.least
    }
}
