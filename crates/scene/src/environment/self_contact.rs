//! Contact between particles that share no intact bond ([`SelfContact`]) as an
//! [`Influence`]: fragments and the faces of cracks push each other apart. The pair list is
//! rebuilt before a step when a particle may have moved half the skin, asking the solver's
//! family and damage which pairs are bonded; the flags of the bonds a step broke are cleared
//! after it.

use std::any::Any;

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_contact::{Bonds, SelfContact, SelfContactStats};
use perifrac_physics::math::Vec3;
use perifrac_physics::{External, Family, Solver};

use super::Influence;

/// The pair list with the statistics of the run so far.
pub struct SelfContactInfluence {
    contact: SelfContact,
    /// The last step's pairs in contact and overlap.
    last: SelfContactStats,
    /// The most pairs in one step and the deepest overlap so far.
    deepest: SelfContactStats,
}

impl SelfContactInfluence {
    /// Contact by `contact`'s pairs.
    pub fn new(contact: SelfContact) -> SelfContactInfluence {
        SelfContactInfluence {
            contact,
            last: SelfContactStats::default(),
            deepest: SelfContactStats::default(),
        }
    }

    /// The pair list.
    pub fn contact(&self) -> &SelfContact {
        &self.contact
    }

    /// The last step's pairs in contact and deepest overlap.
    pub fn last(&self) -> SelfContactStats {
        self.last
    }

    /// The most pairs in one step and the deepest overlap (m, and as a share of its pair's
    /// contact distance) so far.
    pub fn deepest(&self) -> SelfContactStats {
        self.deepest
    }
}

impl Influence for SelfContactInfluence {
    fn name(&self) -> &'static str {
        "self contact"
    }

    fn before_step(&mut self, solver: &dyn Solver) {
        let model = solver.model();
        let family = model.discretization().family();
        let state = model.damage().map(|d| d.bond_state());
        let bonded = FamilyBonds { family, state };
        self.contact.prepare(
            solver.positions(),
            solver.velocities(),
            solver.dt(),
            &bonded,
        );
    }

    fn add_forces(&mut self, ext: &mut External<'_>) {
        self.last = self.contact.add_forces(
            ext.dt,
            ext.positions,
            ext.velocities,
            ext.masses,
            ext.forces,
        );
    }

    fn potential(
        &mut self,
        q: &[Vec3],
        _c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        self.contact.potential(q, grad.map(|(gq, _)| gq))
    }

    fn end(&mut self, q: &[Vec3], _c: &[Vec3], _v: &[Vec3]) {
        self.last = self.contact.stats_at(q);
    }

    fn add_curvature(&mut self, y0: &[Vec3], out: &mut [f64]) {
        self.contact.curvature_hint(y0, out);
    }

    fn after_step(&mut self, broken: &[(u32, u32)]) {
        self.contact.unbond(broken);
        let (d, l) = (&mut self.deepest, self.last);
        d.pairs = d.pairs.max(l.pairs);
        d.max_overlap = d.max_overlap.max(l.max_overlap);
        d.max_overlap_share = d.max_overlap_share.max(l.max_overlap_share);
    }

    fn save(&self, w: &mut Writer) {
        for st in [self.deepest, self.last] {
            w.usize(st.pairs);
            w.f64(st.max_overlap);
            w.f64(st.max_overlap_share);
        }
    }

    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        let mut read = || -> Result<SelfContactStats, CheckpointError> {
            Ok(SelfContactStats {
                pairs: r.usize("self contact pairs")?,
                max_overlap: r.f64("self contact overlap")?,
                max_overlap_share: r.f64("self contact overlap share")?,
            })
        };
        self.deepest = read()?;
        self.last = read()?;
        // The pair list is derived from positions and bonds: built again at the next step.
        self.contact.invalidate();
        Ok(())
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// The solver's bonds as the pair list asks for them: a pair is bonded when its bond is intact,
/// by the per-bond `state` (none: a model without fracture keeps every bond). Damage breaks
/// both directions of a bond together (`perifrac_physics::Damage`), so the direction from `i`
/// tells: no look into the other end's row.
struct FamilyBonds<'a> {
    family: &'a Family,
    state: Option<&'a [u8]>,
}

impl Bonds for FamilyBonds<'_> {
    fn flags(&self, i: u32, candidates: &[u32], out: &mut [u8]) {
        let start = self.family.range(i as usize).start;
        let row = self.family.row(i as usize);
        // The row and the candidates both increase: one walk along the row finds each
        // candidate's bond.
        let mut p = 0;
        for (o, &j) in out.iter_mut().zip(candidates) {
            while p < row.len() && row[p] < j {
                p += 1;
            }
            let bonded =
                p < row.len() && row[p] == j && self.state.is_none_or(|s| s[start + p] != 0);
            *o = u8::from(bonded);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Scene, Setup};

    /// The walk along the row gives what asking both directions pair by pair gives, with
    /// broken bonds and without.
    #[test]
    fn family_bonds_match_the_pairwise_answer() {
        let text = "[mesh]\nprimitive = \"box\"\nsize = [0.04, 0.04, 0.04]\ncells = [4, 4, 4]\n\n\
                    [[material]]\nyoung = 1e7\npoisson = 0.25\ndensity = 1000.0\n\n\
                    [simulation]\nduration = 1e-4\n";
        let scene = Scene::parse(text, std::path::Path::new("t.toml")).unwrap();
        let setup = Setup::new(&scene, None).unwrap();
        let family = setup.driver.solver().model().discretization().family();
        let n = family.len() as u32;
        // A third of the bonds broken, both directions together as damage breaks them.
        let state: Vec<u8> = (0..family.len())
            .flat_map(|i| {
                family
                    .row(i)
                    .iter()
                    .map(move |&j| u8::from(!(i as u32 + j).is_multiple_of(3)))
            })
            .collect();
        let pairwise = |state: Option<&[u8]>, i: u32, j: u32| {
            let one_way = |a: u32, b: u32| {
                let range = family.range(a as usize);
                match family.row(a as usize).binary_search(&b) {
                    Ok(k) => state.is_none_or(|s| s[range.start + k] != 0),
                    Err(_) => false,
                }
            };
            one_way(i, j) && one_way(j, i)
        };
        let (mut bonded, mut broken) = (0, 0);
        for state in [None, Some(&state[..])] {
            let bonds = FamilyBonds { family, state };
            for i in 0..n {
                // Every particle but itself, in increasing order.
                let candidates: Vec<u32> = (0..n).filter(|&j| j != i).collect();
                let mut out = vec![9u8; candidates.len()];
                bonds.flags(i, &candidates, &mut out);
                for (&j, &o) in candidates.iter().zip(&out) {
                    let want = pairwise(state, i, j);
                    assert_eq!(o, u8::from(want), "{i} {j}");
                    if want {
                        bonded += 1;
                    } else if family.row(i as usize).contains(&j) {
                        broken += 1;
                    }
                }
            }
        }
        assert!(bonded > 0 && broken > 0, "{bonded} {broken}");
    }
}
