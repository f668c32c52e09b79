//! Bond breaking (MODEL.md section 2, Fracture): `sw = (e - ep) / delta` against the threshold
//! `s_crit (1 + alpha phi)`, from either side, tension only, permanent and in both directions.

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use crate::family::Family;
use crate::material::kernel::Plastic;
use crate::math::{norm, sub, Vec3};
use crate::par::{for_rows_mut, map_particles};

/// Damage state: which bonds are intact, and the per-particle counts behind `phi`.
#[derive(Debug, Clone)]
pub struct Damage {
    /// Per directed bond: 1 intact, 0 broken, 2 broken in the current check (0 after it).
    state: Vec<u8>,
    initial: Vec<u32>,
    intact: Vec<u32>,
    s_crit: Vec<f64>,
    alpha: Vec<f64>,
    threshold: Vec<f64>,
    new_count: Vec<u32>,
    /// Largest `sw / threshold - 1` over the bonds the last check broke (0 when none broke).
    overshoot: f64,
}

impl Damage {
    /// All bonds intact; `s_crit` and `alpha` per particle (infinite `s_crit`: never breaks).
    pub(crate) fn new(family: &Family, s_crit: Vec<f64>, alpha: Vec<f64>) -> Self {
        let n = family.len();
        let initial: Vec<u32> = (0..n).map(|i| family.range(i).len() as u32).collect();
        Damage {
            state: vec![1; family.num_bonds()],
            intact: initial.clone(),
            initial,
            s_crit,
            alpha,
            threshold: vec![0.0; n],
            new_count: vec![0; n],
            overshoot: 0.0,
        }
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

    /// Writes the bond states for a checkpoint (the per-particle counts follow from them).
    pub(crate) fn save(&self, w: &mut Writer) {
        w.tag("damage");
        w.array(&self.state);
    }

    /// Reads what [`Damage::save`] wrote and recounts the intact bonds of every particle.
    pub(crate) fn restore(
        &mut self,
        family: &Family,
        r: &mut Reader,
    ) -> Result<(), CheckpointError> {
        r.tag("damage")?;
        r.array_into("bond states", &mut self.state)?;
        if let Some(&b) = self.state.iter().find(|&&b| b > 1) {
            return Err(CheckpointError::Invalid {
                what: "bond states".into(),
                message: format!("state {b} is neither intact (1) nor broken (0)"),
            });
        }
        for (i, c) in self.intact.iter_mut().enumerate() {
            *c = self.state[family.range(i)]
                .iter()
                .map(|&b| u32::from(b))
                .sum();
        }
        Ok(())
    }

    /// Number of intact directed bonds.
    pub fn intact_bonds(&self) -> usize {
        self.intact.iter().map(|&c| c as usize).sum()
    }

    /// Heap bytes.
    pub fn memory_bytes(&self) -> usize {
        let Damage {
            state,
            initial,
            intact,
            s_crit,
            alpha,
            threshold,
            new_count,
            overshoot: _,
        } = self;
        state.len()
            + (initial.len() + intact.len() + new_count.len()) * 4
            + (s_crit.len() + alpha.len() + threshold.len()) * 8
    }

    /// Breaks bonds at positions `y` (m), horizon `delta` (m), plastic extensions `p`; appends
    /// the newly broken pairs `(i, j)`, `i < j`, in increasing order.
    pub(crate) fn check<P: Plastic>(
        &mut self,
        family: &Family,
        y: &[Vec3],
        delta: f64,
        p: P,
        broken: &mut Vec<(u32, u32)>,
    ) {
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
        let threshold = &self.threshold;
        let inv_delta = 1.0 / delta;
        for_rows_mut(
            family.offsets(),
            &mut self.new_count,
            &mut self.state,
            &|first, counts: &mut [u32], state: &mut [u8]| {
                let base = family.offsets()[first] as usize;
                for (o, count) in counts.iter_mut().enumerate() {
                    let i = first + o;
                    let yi = y[i];
                    *count = 0;
                    for k in family.range(i) {
                        if state[k - base] != 1 {
                            continue;
                        }
                        let j = family.neighbours()[k] as usize;
                        let e = norm(sub(y[j], yi)) - family.rest_lengths()[k];
                        if e <= 0.0 {
                            continue;
                        }
                        let (epij, epji) = p.pair(k);
                        if (e - epij) * inv_delta > threshold[i]
                            || (e - epji) * inv_delta > threshold[j]
                        {
                            state[k - base] = 2;
                            *count += 1;
                        }
                    }
                }
            },
        );
        self.overshoot = 0.0;
        for i in 0..family.len() {
            if self.new_count[i] == 0 {
                continue;
            }
            self.intact[i] -= self.new_count[i];
            for k in family.range(i) {
                if self.state[k] == 2 {
                    self.state[k] = 0;
                    let j = family.neighbours()[k];
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
