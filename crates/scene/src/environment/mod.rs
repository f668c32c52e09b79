//! What acts on a solid's particles from outside the material, as a list the driver holds:
//! colliders (grounds and balls), contact between fragments, and any load a scene adds. Each
//! is an [`Influence`] in its own file; a new one plugs in with [`crate::Driver::add_influence`]
//! and no edit to the driver. The list is physics' [`Environment`] for a step: explicit steps
//! ask each for its forces, implicit ones sum their potentials, in list order, so the sums and
//! the bits are the same for any thread count.

mod colliders;
mod loads;
mod self_contact;

use std::any::Any;
use std::time::{Duration, Instant};

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_physics::math::Vec3;
use perifrac_physics::{Environment, External, ImplicitEnvironment, PhysicsError, Solver};

pub use colliders::CollidersInfluence;
pub use loads::{Loads, RegionLoad};
pub use self_contact::SelfContactInfluence;

/// One thing acting on the particles from outside the material. Every method but
/// [`Influence::add_forces`] and [`Influence::potential`] has a default that does nothing.
pub trait Influence: Any + Send {
    /// A name for checkpoints and messages.
    fn name(&self) -> &'static str;

    /// Before a step, with the solver as it stands (a pair list is rebuilt here).
    fn before_step(&mut self, _solver: &dyn Solver) {}

    /// Adds forces (N) into `ext.forces` for an explicit step.
    fn add_forces(&mut self, ext: &mut External<'_>);

    /// Starts an implicit step of `dt` (s) from positions `y0` (m) and velocities `v0` (m/s).
    fn begin(&mut self, _dt: f64, _y0: &[Vec3], _v0: &[Vec3], _m: &[f64]) -> Result<(), String> {
        Ok(())
    }

    /// Extra bodies this influence solves for in an implicit step (dynamic balls).
    fn bodies(&self) -> usize {
        0
    }

    /// A first guess of its bodies' end positions (m).
    fn body_guess(&self, _out: &mut [Vec3]) {}

    /// A positive curvature per body (N/m) for the preconditioner.
    fn body_curvature(&self, _out: &mut [f64]) {}

    /// Its potential (J) at particle end positions `q` and its bodies' end positions `c` (m);
    /// with `grad`, adds the gradients (N) into the two slices.
    fn potential(
        &mut self,
        q: &[Vec3],
        c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64;

    /// The implicit step was accepted at `q`, `c`, with end velocities `v` (m/s).
    fn end(&mut self, _q: &[Vec3], _c: &[Vec3], _v: &[Vec3]) {}

    /// Adds into `out` an upper bound of the curvature (N/m) it puts on each particle at `y0`.
    fn add_curvature(&mut self, _y0: &[Vec3], _out: &mut [f64]) {}

    /// After the step, with the bonds (pairs) it broke.
    fn after_step(&mut self, _broken: &[(u32, u32)]) {}

    /// Writes the state a trial step changes, so the event search can undo it.
    fn save_trial(&self, _w: &mut Writer) {}

    /// Reads what [`Influence::save_trial`] wrote.
    fn restore_trial(&mut self, _r: &mut Reader) -> Result<(), CheckpointError> {
        Ok(())
    }

    /// Writes its state for a checkpoint.
    fn save(&self, _w: &mut Writer) {}

    /// Reads what [`Influence::save`] wrote, into an influence built by the same setup.
    fn restore(&mut self, _r: &mut Reader) -> Result<(), CheckpointError> {
        Ok(())
    }

    /// Itself, for typed access ([`Influences::get`]).
    fn as_any(&self) -> &dyn Any;

    /// Itself, mutably.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// The influences acting on a body, in the order they act.
#[derive(Default)]
pub struct Influences {
    list: Vec<Box<dyn Influence>>,
    /// Wall time in their explicit forces and around the step (pair lists).
    time: Duration,
}

impl Influences {
    /// Adds `influence` after the others.
    pub fn push(&mut self, influence: Box<dyn Influence>) {
        self.list.push(influence);
    }

    /// The first influence of type `T`.
    pub fn get<T: Influence>(&self) -> Option<&T> {
        self.list.iter().find_map(|i| i.as_any().downcast_ref())
    }

    /// The first influence of type `T`, mutably.
    pub fn get_mut<T: Influence>(&mut self) -> Option<&mut T> {
        self.list
            .iter_mut()
            .find_map(|i| i.as_any_mut().downcast_mut())
    }

    /// Takes the wall time (s) spent in contact since the last call.
    pub(crate) fn take_time(&mut self) -> Duration {
        std::mem::take(&mut self.time)
    }

    /// Before a step.
    pub(crate) fn before_step(&mut self, solver: &dyn Solver) {
        let t = Instant::now();
        for i in &mut self.list {
            i.before_step(solver);
        }
        self.time += t.elapsed();
    }

    /// After a step that broke `broken`.
    pub(crate) fn after_step(&mut self, broken: &[(u32, u32)]) {
        let t = Instant::now();
        for i in &mut self.list {
            i.after_step(broken);
        }
        self.time += t.elapsed();
    }

    /// Writes every influence's state, each under its name.
    pub(crate) fn save(&self, w: &mut Writer) {
        w.usize(self.list.len());
        for i in &self.list {
            w.tag(i.name());
            i.save(w);
        }
    }

    /// Reads what [`Influences::save`] wrote into the same list.
    pub(crate) fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        let n = r.usize("influences")?;
        if n != self.list.len() {
            return Err(CheckpointError::Invalid {
                what: "influences".into(),
                message: format!(
                    "the checkpoint has {n} (colliders, contact, loads) and this scene {}",
                    self.list.len()
                ),
            });
        }
        for i in &mut self.list {
            r.tag(i.name())?;
            i.restore(r)?;
        }
        Ok(())
    }

    /// Where each influence's bodies start in the implicit step's body array.
    fn body_ranges(&self) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let mut at = 0;
        self.list.iter().map(move |i| {
            let n = i.bodies();
            at += n;
            at - n..at
        })
    }
}

impl Environment for Influences {
    fn add_forces(&mut self, mut ext: External<'_>) {
        let t = Instant::now();
        for i in &mut self.list {
            i.add_forces(&mut ext);
        }
        self.time += t.elapsed();
    }

    fn implicit(&mut self) -> Option<&mut dyn ImplicitEnvironment> {
        Some(self)
    }

    fn save(&self, w: &mut Writer) {
        for i in &self.list {
            i.save_trial(w);
        }
    }

    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        for i in &mut self.list {
            i.restore_trial(r)?;
        }
        Ok(())
    }
}

/// The influences as one incremental potential; each one's bodies are its slice of the step's.
impl ImplicitEnvironment for Influences {
    fn begin(
        &mut self,
        dt: f64,
        y0: &[Vec3],
        v0: &[Vec3],
        masses: &[f64],
    ) -> Result<(), PhysicsError> {
        for i in &mut self.list {
            i.begin(dt, y0, v0, masses)
                .map_err(|e| PhysicsError::BadSetting(format!("{}: {e}", i.name())))?;
        }
        Ok(())
    }

    fn bodies(&self) -> usize {
        self.list.iter().map(|i| i.bodies()).sum()
    }

    fn body_guess(&self, out: &mut [Vec3]) {
        for (i, r) in self.list.iter().zip(self.body_ranges()) {
            i.body_guess(&mut out[r]);
        }
    }

    fn body_curvature(&self, out: &mut [f64]) {
        for (i, r) in self.list.iter().zip(self.body_ranges()) {
            i.body_curvature(&mut out[r]);
        }
    }

    fn potential(
        &mut self,
        q: &[Vec3],
        c: &[Vec3],
        mut grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        let mut energy = 0.0;
        let mut at = 0;
        for i in &mut self.list {
            let r = at..at + i.bodies();
            at = r.end;
            let g = grad
                .as_mut()
                .map(|(gq, gc)| (&mut **gq, &mut gc[r.clone()]));
            energy += i.potential(q, &c[r], g);
        }
        energy
    }

    fn end(&mut self, q: &[Vec3], c: &[Vec3], v: &[Vec3]) {
        let mut at = 0;
        for i in &mut self.list {
            let r = at..at + i.bodies();
            at = r.end;
            i.end(q, &c[r], v);
        }
    }

    fn particle_curvature(&mut self, y0: &[Vec3], out: &mut [f64]) {
        out.fill(0.0);
        for i in &mut self.list {
            i.add_curvature(y0, out);
        }
    }
}
