//! Grounds and balls ([`Colliders`]) as an [`Influence`]: penalty contact with damping and
//! friction on the particles, the balls' own motion, and the dynamic balls as the implicit
//! step's extra bodies.

use std::any::Any;

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_contact::{Colliders, ContactStats};
use perifrac_physics::math::Vec3;
use perifrac_physics::External;

use super::Influence;

/// The colliders and the particles' contact radii.
pub struct CollidersInfluence {
    colliders: Colliders,
    /// Contact radius of each particle (m).
    radii: Vec<f64>,
    /// What the last step found.
    stats: ContactStats,
    /// The curvature hint before it is added to the others' (N/m per particle).
    hint: Vec<f64>,
}

impl CollidersInfluence {
    /// `colliders` acting on particles of contact radii `radii` (m).
    pub fn new(colliders: Colliders, radii: Vec<f64>) -> CollidersInfluence {
        CollidersInfluence {
            colliders,
            radii,
            stats: ContactStats::default(),
            hint: Vec::new(),
        }
    }

    /// The colliders.
    pub fn colliders(&self) -> &Colliders {
        &self.colliders
    }

    /// The colliders, mutably (to stop a ball).
    pub fn colliders_mut(&mut self) -> &mut Colliders {
        &mut self.colliders
    }

    /// What the last step found.
    pub fn stats(&self) -> ContactStats {
        self.stats
    }
}

impl Influence for CollidersInfluence {
    fn name(&self) -> &'static str {
        "colliders"
    }

    fn add_forces(&mut self, ext: &mut External<'_>) {
        self.stats = self.colliders.step(
            ext.dt,
            ext.positions,
            ext.velocities,
            ext.masses,
            &self.radii,
            ext.forces,
        );
    }

    fn begin(&mut self, dt: f64, y0: &[Vec3], v0: &[Vec3], m: &[f64]) -> Result<(), String> {
        self.colliders
            .begin_implicit(dt, y0, v0, m, &self.radii)
            .map_err(|e| e.to_string())
    }

    fn bodies(&self) -> usize {
        self.colliders.implicit_bodies()
    }

    fn body_guess(&self, out: &mut [Vec3]) {
        out.copy_from_slice(self.colliders.implicit_body_targets());
    }

    fn body_curvature(&self, out: &mut [f64]) {
        out.copy_from_slice(self.colliders.implicit_body_diagonal());
    }

    fn potential(
        &mut self,
        q: &[Vec3],
        c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        self.colliders.implicit_potential(q, c, grad)
    }

    fn end(&mut self, q: &[Vec3], c: &[Vec3], v: &[Vec3]) {
        self.stats = self.colliders.end_implicit(q, c, v);
    }

    fn add_curvature(&mut self, y0: &[Vec3], out: &mut [f64]) {
        self.hint.resize(out.len(), 0.0);
        let c = self.colliders.implicit_body_start();
        self.colliders
            .implicit_stiffness_hint(y0, c, &mut self.hint);
        for (o, h) in out.iter_mut().zip(&self.hint) {
            *o += h;
        }
    }

    fn save_trial(&self, w: &mut Writer) {
        self.colliders.save(w);
    }

    fn restore_trial(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        self.colliders.restore(r)
    }

    fn save(&self, w: &mut Writer) {
        self.colliders.save(w);
    }

    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        self.colliders.restore(r)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
