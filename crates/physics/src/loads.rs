//! External loads and boundary conditions: gravity, anchored particles (fixed, or moving rigidly
//! with a prescribed translation and rotation), mass-proportional damping.

use crate::error::PhysicsError;
use crate::math::{add, axpy, cross, mat_vec, norm, rotation, sub, Vec3};
use perifrac_checkpoint::{expect_count, CheckpointError, Reader, Writer};

/// Marker for a particle without an anchor.
const FREE: u32 = u32::MAX;

/// A prescribed rigid motion of anchored particles: translation at `velocity` (m/s) and
/// rotation at `angular` (rad/s, axis times rate) about an axis through `center` (m at time 0),
/// which moves with `velocity`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnchorMotion {
    /// Translation velocity (m/s).
    pub velocity: Vec3,
    /// Angular velocity (rad/s).
    pub angular: Vec3,
    /// A point on the rotation axis at time 0 (m).
    pub center: Vec3,
}

impl AnchorMotion {
    /// A translation at `velocity` (m/s); zero holds the particles fixed.
    pub fn translation(velocity: Vec3) -> Self {
        AnchorMotion {
            velocity,
            angular: [0.0; 3],
            center: [0.0; 3],
        }
    }

    /// True when the motion turns.
    #[inline(always)]
    pub fn rotates(&self) -> bool {
        self.angular != [0.0; 3]
    }

    /// Velocity (m/s) of a particle of this motion at `y` (m) at time `t` (s).
    #[inline(always)]
    pub fn velocity_at(&self, y: Vec3, t: f64) -> Vec3 {
        if !self.rotates() {
            return self.velocity;
        }
        let c = axpy(self.center, t, self.velocity);
        add(self.velocity, cross(self.angular, sub(y, c)))
    }

    /// Position (m) after `dt` (s) of a particle of this motion at `y` (m) at time `t` (s):
    /// the exact rigid motion, so a rotating anchor stays on its circle whatever the step.
    pub fn advance(&self, y: Vec3, t: f64, dt: f64) -> Vec3 {
        if !self.rotates() {
            return axpy(y, dt, self.velocity);
        }
        let c = axpy(self.center, t, self.velocity);
        let w = norm(self.angular);
        let r = rotation(self.angular, w * dt);
        add(axpy(c, dt, self.velocity), mat_vec(&r, sub(y, c)))
    }

    fn check(&self) -> Result<(), PhysicsError> {
        let all = [self.velocity, self.angular, self.center];
        if all.iter().flatten().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(PhysicsError::BadSetting(format!(
                "anchor motion {self:?} must be finite"
            )))
        }
    }
}

/// Loads chosen at setup. Initial velocities are set on the integrator.
#[derive(Debug, Clone, PartialEq)]
pub struct Loads {
    /// Gravitational acceleration (m/s^2), applied to every free particle.
    pub gravity: Vec3,
    /// Mass-proportional damping coefficient `c` (1/s): `dv/dt = ... - c v`.
    pub damping: f64,
    anchor_of: Vec<u32>,
    motions: Vec<AnchorMotion>,
}

impl Loads {
    /// No gravity, no damping, no anchors, for `n` particles.
    pub fn new(n: usize) -> Self {
        Loads {
            gravity: [0.0; 3],
            damping: 0.0,
            anchor_of: vec![FREE; n],
            motions: Vec::new(),
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
        self.anchor_motion(particles, AnchorMotion::translation(velocity))
    }

    /// Anchors `particles` to follow `motion` from time 0. A later call overrides an earlier
    /// one for the same particle.
    pub fn anchor_motion(
        &mut self,
        particles: &[u32],
        motion: AnchorMotion,
    ) -> Result<(), PhysicsError> {
        motion.check()?;
        let n = self.anchor_of.len();
        if let Some(&p) = particles.iter().find(|&&p| p as usize >= n) {
            return Err(PhysicsError::BadParticleIndex {
                what: "anchor",
                particle: p as usize,
                count: n,
            });
        }
        let id = self.motions.len() as u32;
        self.motions.push(motion);
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

    /// Writes which particles are anchored now (releases change it) for a checkpoint; the
    /// motions, gravity and damping come from the scene.
    pub fn save(&self, w: &mut Writer) {
        w.tag("loads");
        w.usize(self.motions.len());
        w.array(&self.anchor_of);
    }

    /// Reads what [`Loads::save`] wrote, checked against these loads' motions.
    pub fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        r.tag("loads")?;
        expect_count(
            "anchor motions",
            self.motions.len(),
            r.usize("anchor motions")?,
        )?;
        r.array_into("anchored particles", &mut self.anchor_of)?;
        let m = self.motions.len() as u32;
        if let Some(&a) = self.anchor_of.iter().find(|&&a| a != FREE && a >= m) {
            return Err(CheckpointError::Invalid {
                what: "anchored particles".into(),
                message: format!("anchor {a} of {m}"),
            });
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

    /// The motion particle `i` follows, if anchored.
    #[inline(always)]
    pub fn motion(&self, i: usize) -> Option<&AnchorMotion> {
        match self.anchor_of[i] {
            FREE => None,
            a => Some(&self.motions[a as usize]),
        }
    }

    /// True when some anchor motion (released or not) rotates: the integrators then take the
    /// path that moves anchored particles along exact circles.
    pub fn has_rotation(&self) -> bool {
        self.motions.iter().any(AnchorMotion::rotates)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{dot, norm};

    #[test]
    fn rotating_anchor_moves_on_its_circle_and_its_velocity_is_the_derivative() {
        let m = AnchorMotion {
            velocity: [0.1, 0.0, 0.0],
            angular: [2.0, 0.0, 0.0],
            center: [0.0, 0.5, 0.5],
        };
        let y0 = [0.3, 0.5, 1.0];
        // a quarter turn in one step: the rigid motion is exact, whatever the step
        let t = 0.25 * std::f64::consts::PI;
        let y1 = m.advance(y0, 0.0, t);
        let c1 = axpy(m.center, t, m.velocity);
        assert!((norm(sub(y1, c1)) - norm(sub(y0, m.center))).abs() < 1e-15);
        // x advanced with the translation, the radius turned from +z to -y
        assert!(norm(sub(y1, [0.3 + 0.1 * t, 0.0, 0.5])) < 1e-15, "{y1:?}");
        // velocity_at is the time derivative of advance: central difference, h = 1e-6 s,
        // truncation ~ h^2 |omega|^3 r = 4e-12 m/s
        let h = 1e-6;
        let fd = sub(m.advance(y1, t, h), m.advance(y1, t, -h)).map(|d| d / (2.0 * h));
        let v = m.velocity_at(y1, t);
        assert!(norm(sub(fd, v)) < 1e-9, "{fd:?} vs {v:?}");
        // the rotational part is perpendicular to the radius
        assert!(dot(sub(v, m.velocity), sub(y1, c1)).abs() < 1e-15);
        // a translation stays a translation, bit for bit
        let t2 = AnchorMotion::translation([1.0, 2.0, 3.0]);
        assert_eq!(t2.velocity_at(y0, 5.0), [1.0, 2.0, 3.0]);
        assert_eq!(t2.advance(y0, 5.0, 0.5), axpy(y0, 0.5, [1.0, 2.0, 3.0]));
        assert!(!t2.rotates() && m.rotates());
    }

    #[test]
    fn bad_motions_are_refused() {
        let mut loads = Loads::new(3);
        let bad = AnchorMotion {
            angular: [f64::NAN, 0.0, 0.0],
            ..AnchorMotion::translation([0.0; 3])
        };
        assert!(loads.anchor_motion(&[0], bad).is_err());
        assert!(loads.anchor(&[3], [0.0; 3]).is_err());
        assert!((0..3).all(|i| loads.motion(i).is_none()));
        loads.anchor(&[1], [0.0; 3]).unwrap();
        assert!(loads.motion(1).is_some() && !loads.has_rotation());
    }
}
