//! Materials: parameters and the force-model interface the integrators drive.

pub mod basis;
pub mod chen;
pub(crate) mod fit;
mod guard;
pub(crate) mod kernel;
pub(crate) mod lanes;
pub mod params;
pub mod xu;
mod xu_fit;
pub(crate) mod xu_kernel;
pub mod xu_params;

pub use basis::{Basis, Curve};
pub use chen::{ChenModel, ChenOptions};
pub use fit::{Correction, Spread};
pub use params::{ChenMaterial, FractureParams, YieldParams};
pub use xu::{XuKernelShape, XuModel, XuOptions};
pub use xu_params::{XuAnisotropy, XuMaterial, XuModuli};

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use crate::fracture::Damage;
use crate::math::Vec3;
use crate::particles::Discretization;

/// A constitutive model over a fixed discretisation: the integrators see only this interface, so
/// other models (Xu's hyperelastic energy) and other integrators (implicit) plug in beside it.
/// Positions are in m, forces in N, energies in J.
pub trait ForceModel: Send {
    /// Number of particles.
    fn num_particles(&self) -> usize;

    /// The particles and their families.
    fn discretization(&self) -> &Discretization;

    /// Particle masses (kg).
    fn masses(&self) -> &[f64];

    /// Internal forces at positions `y`, advancing history-dependent state (plastic return map).
    fn update_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]);

    /// Internal forces at `y` with the current history, leaving every internal state unchanged
    /// (used by the stable-step estimate and diagnostics).
    fn trial_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]);

    /// Whether the internal forces at `y` are known to vanish without evaluating them, and an
    /// evaluation there would change no state that later results depend on: true only where
    /// the model can tell exactly (its own rest positions, bit for bit, with nothing that
    /// stresses it there). Lets the stable-step estimate and an integrator's start skip an
    /// evaluation; the default claims nothing.
    fn forces_vanish_at(&self, y: &[Vec3]) -> bool {
        let _ = y;
        false
    }

    /// Elastic (stored) energy at `y` with the current history (J).
    fn elastic_energy(&mut self, y: &[Vec3]) -> f64;

    /// Breaks bonds at `y` by the damage criterion and appends the newly broken pairs
    /// `(i, j)`, `i < j`, once each, to `broken`. Models without damage do nothing.
    fn break_bonds(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>);

    /// [`ForceModel::break_bonds`] then [`ForceModel::update_forces`] at the same `y`: the
    /// explicit step's pair, which a model may fuse into fewer walks over the bonds (with the
    /// same results).
    fn break_bonds_and_update_forces(
        &mut self,
        y: &[Vec3],
        broken: &mut Vec<(u32, u32)>,
        forces: &mut [Vec3],
    ) {
        self.break_bonds(y, broken);
        self.update_forces(y, forces);
    }

    /// Per-particle Silling-Askari bound `sqrt(2 rho / sum_j C_ij V_j)` minimised over particles (s).
    fn silling_askari_step(&self) -> f64;

    /// Heap bytes owned by the model (discretisation, state, buffers).
    fn memory_bytes(&self) -> usize;

    /// Damage state, when some material fractures.
    fn damage(&self) -> Option<&Damage> {
        None
    }

    /// Largest relative overshoot of the bonds the last [`ForceModel::break_bonds`] broke past
    /// their threshold (0 when none broke, or without damage).
    fn break_overshoot(&self) -> f64 {
        self.damage().map_or(0.0, Damage::last_overshoot)
    }

    /// Writes the history that steps change (plastic extension, damage, renormalisation, the
    /// last dilatations) for a checkpoint or a snapshot; constants come from the setup.
    fn save_state(&self, w: &mut Writer);

    /// Reads what [`ForceModel::save_state`] wrote, checked against this model's sizes.
    fn restore_state(&mut self, r: &mut Reader) -> Result<(), CheckpointError>;
}

impl<T: ForceModel + ?Sized> ForceModel for Box<T> {
    fn num_particles(&self) -> usize {
        (**self).num_particles()
    }
    fn discretization(&self) -> &Discretization {
        (**self).discretization()
    }
    fn masses(&self) -> &[f64] {
        (**self).masses()
    }
    fn update_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        (**self).update_forces(y, forces)
    }
    fn trial_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) {
        (**self).trial_forces(y, forces)
    }
    fn forces_vanish_at(&self, y: &[Vec3]) -> bool {
        (**self).forces_vanish_at(y)
    }
    fn elastic_energy(&mut self, y: &[Vec3]) -> f64 {
        (**self).elastic_energy(y)
    }
    fn break_bonds(&mut self, y: &[Vec3], broken: &mut Vec<(u32, u32)>) {
        (**self).break_bonds(y, broken)
    }
    fn break_bonds_and_update_forces(
        &mut self,
        y: &[Vec3],
        broken: &mut Vec<(u32, u32)>,
        forces: &mut [Vec3],
    ) {
        (**self).break_bonds_and_update_forces(y, broken, forces)
    }
    fn silling_askari_step(&self) -> f64 {
        (**self).silling_askari_step()
    }
    fn memory_bytes(&self) -> usize {
        (**self).memory_bytes()
    }
    fn damage(&self) -> Option<&Damage> {
        (**self).damage()
    }
    fn break_overshoot(&self) -> f64 {
        (**self).break_overshoot()
    }
    fn save_state(&self, w: &mut Writer) {
        (**self).save_state(w)
    }
    fn restore_state(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        (**self).restore_state(r)
    }
}

/// Refuses a checkpoint whose model has a history array (`what`) this one lacks, or lacks one
/// this one has: it was written for another scene.
pub(crate) fn same_features(what: &str, here: bool, there: bool) -> Result<(), CheckpointError> {
    if here == there {
        return Ok(());
    }
    Err(CheckpointError::Invalid {
        what: what.into(),
        message: format!(
            "the checkpoint {} it and this model {}",
            if there { "has" } else { "lacks" },
            if here { "has" } else { "lacks" }
        ),
    })
}

/// A model the implicit quasi-Newton step can drive: it has an energy whose negative gradient
/// its forces are, and a rest stiffness per bond for the step's constant matrix.
pub trait QuasiNewtonModel: ForceModel {
    /// Writes the rest stiffness `k_ij` (N/m) of every directed bond into `out` (one entry per
    /// bond, in CSR order), 0 for broken bonds: `sum_bonds k_ij (e_i - e_j)(e_i - e_j)^T`
    /// is the model's part of the step matrix.
    fn bond_stiffness(&self, out: &mut [f64]);

    /// Elastic energy (J) and internal forces (N) at `y` with the current history, leaving
    /// every internal state unchanged.
    fn energy_and_forces(&mut self, y: &[Vec3], forces: &mut [Vec3]) -> f64 {
        let e = self.elastic_energy(y);
        self.trial_forces(y, forces);
        e
    }
}
