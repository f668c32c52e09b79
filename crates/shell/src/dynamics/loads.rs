//! Forces from outside on a shell's vertices (tractions, pressures, body forces), each raised
//! over its ramp and removed at its end time, with the work they do. They are dead loads: set
//! at rest, they keep their direction as the shell moves. A vertex fracture adds carries none,
//! so a load's total stays what it was set to.

use perifrac_physics::math::{add, dot, scale, Vec3};

use crate::error::ShellError;

/// One load: the vertices it pushes and the force (N) on each at full strength.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellLoad {
    /// The vertices it acts on.
    pub vertices: Vec<u32>,
    /// The force on each at full strength (N).
    pub forces: Vec<Vec3>,
    /// Rise time (s); 0: at once.
    pub ramp: f64,
    /// End time (s); infinity: never.
    pub until: f64,
}

impl ShellLoad {
    /// Its strength at time `t` (s), from 0 to 1.
    pub fn strength(&self, t: f64) -> f64 {
        if t >= self.until {
            0.0
        } else if self.ramp > 0.0 {
            (t / self.ramp).min(1.0)
        } else {
            1.0
        }
    }

    /// Checks the vertices exist (`n` of them), the forces are finite and as many, the ramp is
    /// finite and not negative and the end time positive.
    pub(crate) fn check(&self, n: usize) -> Result<(), ShellError> {
        let bad = |what: &'static str, value: f64| ShellError::BadSetting {
            what,
            expected: "as the load's other settings need",
            value,
        };
        if self.vertices.len() != self.forces.len() {
            return Err(bad("load forces per vertex", self.forces.len() as f64));
        }
        if let Some(&v) = self.vertices.iter().find(|&&v| v as usize >= n) {
            return Err(bad("loaded vertex index", f64::from(v)));
        }
        if let Some(f) = self
            .forces
            .iter()
            .find(|f| !f.iter().all(|c| c.is_finite()))
        {
            return Err(bad("load force (N)", f[0]));
        }
        if !(self.ramp.is_finite() && self.ramp >= 0.0) {
            return Err(bad("load ramp (s)", self.ramp));
        }
        if self.until.is_nan() || self.until <= 0.0 {
            return Err(bad("load end time (s)", self.until));
        }
        Ok(())
    }
}

/// The loads on a shell and the work they have done.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Loads {
    pub loads: Vec<ShellLoad>,
    /// Work done so far (J).
    pub work: f64,
    /// The loaded vertices' positions (m) before an implicit step, load by load.
    before: Vec<Vec3>,
}

impl Loads {
    /// Calls `act(vertex, force)` for every loaded vertex with its force (N) at time `t` (s),
    /// skipping the loads at zero strength.
    fn each(&self, t: f64, mut act: impl FnMut(usize, Vec3)) {
        for l in &self.loads {
            let s = l.strength(t);
            if s != 0.0 {
                for (&i, &f) in l.vertices.iter().zip(&l.forces) {
                    act(i as usize, scale(f, s));
                }
            }
        }
    }

    /// Adds `dt / m` times the force at time `t` (s) to the velocity of every free loaded
    /// vertex: half a kick of the loads over `dt` (s).
    pub fn kick(&self, t: f64, dt: f64, v: &mut [Vec3], masses: &[f64], pinned: &[bool]) {
        self.each(t, |i, f| {
            if !pinned[i] {
                v[i] = add(v[i], scale(f, dt / masses[i]));
            }
        });
    }

    /// Adds the work of a drift of `dt` (s) at velocities `v` from time `t` (s), the force
    /// taken as the mean of its values at both ends.
    pub fn drift_work(&mut self, t: f64, dt: f64, v: &[Vec3]) {
        let mut work = 0.0;
        for end in [t, t + dt] {
            self.each(end, |i, f| work += 0.5 * dt * dot(f, v[i]));
        }
        self.work += work;
    }

    /// Adds `c / m` times the force at time `t` (s) to `target` of every free loaded vertex
    /// (the implicit step's target, `c = beta h^2`).
    pub fn shift(&self, t: f64, c: f64, target: &mut [Vec3], masses: &[f64], pinned: &[bool]) {
        self.each(t, |i, f| {
            if !pinned[i] {
                target[i] = add(target[i], scale(f, c / masses[i]));
            }
        });
    }

    /// At the end of an implicit step to time `t` (s): adds each free loaded vertex's load
    /// acceleration to `acc` and `c` times that to `v` (`c = gamma h` times the damping's
    /// factor).
    pub fn finish(
        &self,
        t: f64,
        c: f64,
        v: &mut [Vec3],
        acc: &mut [Vec3],
        masses: &[f64],
        pinned: &[bool],
    ) {
        self.each(t, |i, f| {
            if !pinned[i] {
                let a = scale(f, 1.0 / masses[i]);
                acc[i] = add(acc[i], a);
                v[i] = add(v[i], scale(a, c));
            }
        });
    }

    /// The largest load force (N) on a vertex at time `t` (s): each load's own, not their sum.
    pub fn largest(&self, t: f64) -> f64 {
        let mut most: f64 = 0.0;
        self.each(t, |_, f| most = most.max(dot(f, f).sqrt()));
        most
    }

    /// Keeps the loaded vertices' positions `x` (m) before an implicit step.
    pub fn remember(&mut self, x: &[Vec3]) {
        self.before.clear();
        for l in &self.loads {
            self.before
                .extend(l.vertices.iter().map(|&i| x[i as usize]));
        }
    }

    /// Adds the work of the implicit step that ends at time `t` (s) at positions `x` (m), from
    /// those [`Loads::remember`] kept: the loads then (as the step applies them) times the
    /// displacement.
    pub fn step_work(&mut self, t: f64, x: &[Vec3]) {
        let mut work = 0.0;
        let mut before = self.before.iter();
        for l in &self.loads {
            let s = l.strength(t);
            for ((&i, &f), x0) in l.vertices.iter().zip(&l.forces).zip(before.by_ref()) {
                let d = [0, 1, 2].map(|k| x[i as usize][k] - x0[k]);
                work += s * dot(f, d);
            }
        }
        self.work += work;
    }
}
