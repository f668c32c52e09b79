//! The scene's `[[load]]` tables: tractions, pressures and body forces on regions, as fixed
//! forces on particles (dead loads, in the rest frame), each raised over its ramp and removed at
//! its end time. Their work is kept, so that a run's energy balance closes.

use std::any::Any;

use perifrac_checkpoint::{CheckpointError, Reader, Writer};
use perifrac_physics::math::{add, dot, scale, sub, Vec3};
use perifrac_physics::{External, Solver};

use super::Influence;

/// One load: the particles it pushes and the force (N) on each at full strength.
#[derive(Debug, Clone)]
pub struct RegionLoad {
    /// Particles it acts on.
    pub particles: Vec<u32>,
    /// Force on each at full strength (N).
    pub forces: Vec<Vec3>,
    /// Rise time (s); 0: at once.
    pub ramp: f64,
    /// End time (s); infinity: never.
    pub until: f64,
}

impl RegionLoad {
    /// Its strength at time `t` (s), from 0 to 1.
    fn strength(&self, t: f64) -> f64 {
        if t >= self.until {
            0.0
        } else if self.ramp > 0.0 {
            (t / self.ramp).min(1.0)
        } else {
            1.0
        }
    }
}

/// The scene's loads as one [`Influence`]: their forces in explicit steps, their potential in
/// implicit ones, and the work they have done.
#[derive(Debug, Clone)]
pub struct Loads {
    loads: Vec<RegionLoad>,
    /// Time (s) of the positions last seen.
    time: f64,
    /// Each load's strength at the positions last seen.
    strength: Vec<f64>,
    /// The loaded particles' positions last seen (m), load by load.
    last: Vec<Vec3>,
    /// Work done so far (J).
    work: f64,
    /// The end of the step being taken: its time (s) and each load's strength then.
    end_time: f64,
    end_strength: Vec<f64>,
}

impl Loads {
    /// The loads, acting on a body at rest at `rest` (m) from time 0. No force acts in the
    /// first half of the first step, as with every force from outside the material.
    pub fn new(loads: Vec<RegionLoad>, rest: &[Vec3]) -> Self {
        let last = loads
            .iter()
            .flat_map(|l| l.particles.iter().map(|&p| rest[p as usize]))
            .collect();
        let n = loads.len();
        Loads {
            loads,
            time: 0.0,
            strength: vec![0.0; n],
            last,
            work: 0.0,
            end_time: 0.0,
            end_strength: vec![0.0; n],
        }
    }

    /// Work the loads have done on the body so far (J).
    pub fn work(&self) -> f64 {
        self.work
    }

    /// The loads.
    pub fn loads(&self) -> &[RegionLoad] {
        &self.loads
    }

    /// Sets the step's end to time `t` (s) and each load's strength then.
    fn end_at(&mut self, t: f64) {
        self.end_time = t;
        for (s, l) in self.end_strength.iter_mut().zip(&self.loads) {
            *s = l.strength(t);
        }
    }

    /// Moves to positions `y` at the step's end: adds the work done since the positions last
    /// seen (the trapezoid of the forces at both ends, as velocity Verlet applies them) and
    /// keeps `y`.
    fn advance(&mut self, y: &[Vec3]) {
        let mut k = 0;
        let ends = self.strength.iter().zip(&self.end_strength);
        for (l, (&before, &after)) in self.loads.iter().zip(ends) {
            let mean = 0.5 * (before + after);
            for (&p, f) in l.particles.iter().zip(&l.forces) {
                let x = y[p as usize];
                self.work += mean * dot(*f, sub(x, self.last[k]));
                self.last[k] = x;
                k += 1;
            }
        }
        self.strength.copy_from_slice(&self.end_strength);
        self.time = self.end_time;
    }

    fn write(&self, w: &mut Writer) {
        w.f64(self.time);
        w.f64(self.work);
        w.array(&self.strength);
        w.array(&self.last);
    }

    fn read(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        self.time = r.f64("loads' time")?;
        self.work = r.f64("loads' work")?;
        r.array_into("loads' strengths", &mut self.strength)?;
        r.array_into("loaded particles' positions", &mut self.last)?;
        Ok(())
    }
}

impl Influence for Loads {
    fn name(&self) -> &'static str {
        "loads"
    }

    fn before_step(&mut self, solver: &dyn Solver) {
        self.time = solver.time();
    }

    fn add_forces(&mut self, ext: &mut External<'_>) {
        // the forces at the end of this (sub-)step
        self.end_at(self.time + ext.dt);
        for (l, &s) in self.loads.iter().zip(&self.end_strength) {
            if s == 0.0 {
                continue;
            }
            for (&p, f) in l.particles.iter().zip(&l.forces) {
                let i = p as usize;
                ext.forces[i] = add(ext.forces[i], scale(*f, s));
            }
        }
        self.advance(ext.positions);
    }

    fn begin(&mut self, dt: f64, _y0: &[Vec3], _v0: &[Vec3], _m: &[f64]) -> Result<(), String> {
        self.end_at(self.time + dt);
        Ok(())
    }

    fn potential(
        &mut self,
        q: &[Vec3],
        _c: &[Vec3],
        grad: Option<(&mut [Vec3], &mut [Vec3])>,
    ) -> f64 {
        // -F . (q - q0) over the step, F at the step's end strength
        let mut u = 0.0;
        let mut k = 0;
        let mut gq = grad.map(|(gq, _)| gq);
        for (l, &s) in self.loads.iter().zip(&self.end_strength) {
            for (&p, f) in l.particles.iter().zip(&l.forces) {
                let i = p as usize;
                let force = scale(*f, s);
                u -= dot(force, sub(q[i], self.last[k]));
                if let Some(g) = gq.as_deref_mut() {
                    g[i] = sub(g[i], force);
                }
                k += 1;
            }
        }
        u
    }

    fn end(&mut self, q: &[Vec3], _c: &[Vec3], _v: &[Vec3]) {
        // the implicit step applies the end strength over the whole step
        self.strength.copy_from_slice(&self.end_strength);
        self.advance(q);
    }

    fn save_trial(&self, w: &mut Writer) {
        self.write(w);
    }

    fn restore_trial(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        self.read(r)
    }

    fn save(&self, w: &mut Writer) {
        self.write(w);
    }

    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        self.read(r)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
