//! External loads and boundary conditions: gravity, anchored particles (fixed or moving with a
//! prescribed velocity), mass-proportional damping.

use crate::error::PhysicsError;
use crate::math::Vec3;

/// Marker for a particle without an anchor.
const FREE: u32 = u32::MAX;

/// Loads chosen at setup. Initial velocities are set on the integrator.
#[derive(Debug, Clone, PartialEq)]
pub struct Loads {
    /// Gravitational acceleration (m/s^2), applied to every free particle.
    pub gravity: Vec3,
    /// Mass-proportional damping coefficient `c` (1/s): `dv/dt = ... - c v`.
    pub damping: f64,
    anchor_of: Vec<u32>,
    anchor_velocity: Vec<Vec3>,
}

impl Loads {
    /// No gravity, no damping, no anchors, for `n` particles.
    pub fn new(n: usize) -> Self {
        Loads {
            gravity: [0.0; 3],
            damping: 0.0,
            anchor_of: vec![FREE; n],
            anchor_velocity: Vec::new(),
        }
    }

    /// Sets gravity (m/s^2).
    pub fn with_gravity(mut self, g: Vec3) -> Self {
        self.gravity = g;
        self
    }

    /// Sets mass-proportional damping (1/s, >= 0).
    pub fn with_damping(mut self, c: f64) -> Result<Self, PhysicsError> {
        if !(c.is_finite() && c >= 0.0) {
            return Err(PhysicsError::BadSetting(format!(
                "damping {c} 1/s must be finite and >= 0"
            )));
        }
        self.damping = c;
        Ok(self)
    }

    /// Anchors `particles` to move with constant `velocity` (m/s; zero: fixed). A later call
    /// overrides an earlier one for the same particle.
    pub fn anchor(&mut self, particles: &[u32], velocity: Vec3) -> Result<(), PhysicsError> {
        let n = self.anchor_of.len();
        if let Some(&p) = particles.iter().find(|&&p| p as usize >= n) {
            return Err(PhysicsError::BadParticleIndex {
                what: "anchor",
                particle: p as usize,
                count: n,
            });
        }
        let id = self.anchor_velocity.len() as u32;
        self.anchor_velocity.push(velocity);
        for &p in particles {
            self.anchor_of[p as usize] = id;
        }
        Ok(())
    }

    /// Frees `particles` from any anchor (out-of-range indices are an error).
    pub fn release(&mut self, particles: &[u32]) -> Result<(), PhysicsError> {
        let n = self.anchor_of.len();
        if let Some(&p) = particles.iter().find(|&&p| p as usize >= n) {
            return Err(PhysicsError::BadParticleIndex {
                what: "release",
                particle: p as usize,
                count: n,
            });
        }
        for &p in particles {
            self.anchor_of[p as usize] = FREE;
        }
        Ok(())
    }

    /// Number of particles these loads were made for.
    pub fn len(&self) -> usize {
        self.anchor_of.len()
    }

    /// True when made for zero particles.
    pub fn is_empty(&self) -> bool {
        self.anchor_of.is_empty()
    }

    /// Prescribed velocity of particle `i` (m/s), if anchored.
    #[inline(always)]
    pub fn anchored(&self, i: usize) -> Option<Vec3> {
        match self.anchor_of[i] {
            FREE => None,
            a => Some(self.anchor_velocity[a as usize]),
        }
    }
}
