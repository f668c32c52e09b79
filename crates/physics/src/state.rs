//! The state an integrator advances: positions, velocities and the clock.

use perifrac_checkpoint::{CheckpointError, Reader, Writer};

use crate::math::Vec3;

/// Positions (m), velocities (m/s), simulated time (s) and the step counter of a particle
/// system. Integrators advance it; the force model never owns it.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Current positions `y_i` (m).
    pub positions: Vec<Vec3>,
    /// Current velocities `v_i` (m/s).
    pub velocities: Vec<Vec3>,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
}

impl State {
    /// At rest at `rest` (m), time 0.
    pub fn at_rest(rest: &[Vec3]) -> Self {
        State {
            positions: rest.to_vec(),
            velocities: vec![[0.0; 3]; rest.len()],
            time: 0.0,
            steps: 0,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Writes positions, velocities, time and step count for a checkpoint.
    pub fn save(&self, w: &mut Writer) {
        w.tag("state");
        w.array(&self.positions);
        w.array(&self.velocities);
        w.f64(self.time);
        w.u64(self.steps);
    }

    /// Reads what [`State::save`] wrote; the particle count must be this state's.
    pub fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("state")?;
        r.array_into("positions", &mut self.positions)?;
        r.array_into("velocities", &mut self.velocities)?;
        self.time = r.f64("time")?;
        self.steps = r.u64("steps")?;
        Ok(())
    }
}
