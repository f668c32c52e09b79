//! Descriptions of colliders as the scene gives them.

use crate::params::ContactParams;
use crate::Vec3;

/// How a ball moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BallMotion {
    /// Prescribed constant velocity (m/s); particles do not push it back.
    Kinematic {
        /// Velocity (m/s).
        velocity: Vec3,
    },
    /// Rigid ball (no rotation) under gravity, the reaction of the particles it touches, and
    /// contact with the ground planes.
    Dynamic {
        /// Mass (kg, > 0).
        mass: f64,
        /// Initial velocity (m/s).
        velocity: Vec3,
    },
}

/// A ground plane: the half-space below `point` with outward normal `normal`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundDesc {
    /// A point on the plane (m).
    pub point: Vec3,
    /// Outward normal (pointing out of the ground, into free space); any nonzero length,
    /// normalised by [`crate::Colliders::new`].
    pub normal: Vec3,
    /// Contact coefficients against particles. Also the base of the ball-ground contact of
    /// dynamic balls (see [`crate::Colliders::ball_ground_stiffness`]).
    pub params: ContactParams,
}

/// A ball collider.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallDesc {
    /// Initial centre (m).
    pub center: Vec3,
    /// Radius (m, > 0).
    pub radius: f64,
    /// Kinematic or dynamic.
    pub motion: BallMotion,
    /// Contact coefficients against particles.
    pub params: ContactParams,
}
