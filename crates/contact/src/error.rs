//! Errors of collider setup and setup checks.

use thiserror::Error;

/// What went wrong building or checking colliders. `collider` names the collider as
/// `"ground 1"` or `"ball 0"` (its index in the list given to [`crate::Colliders::new`]).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ContactError {
    /// A coordinate or coefficient is NaN or infinite.
    #[error("{collider}: {what} must be finite, got {value}")]
    NonFinite {
        /// The collider (or `"gravity"`).
        collider: String,
        /// Which value.
        what: &'static str,
        /// The offending value (the first non-finite component for vectors).
        value: f64,
    },
    /// A value that must be strictly positive is not (ball radius, dynamic ball mass).
    #[error("{collider}: {what} must be > 0, got {value}")]
    NotPositive {
        /// The collider.
        collider: String,
        /// Which value.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A coefficient that must be non-negative is negative (stiffness, damping, friction).
    #[error("{collider}: {what} must be >= 0, got {value}")]
    Negative {
        /// The collider.
        collider: String,
        /// Which value.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A ground plane's normal has zero length.
    #[error("{collider}: normal must be nonzero, got {normal:?}")]
    ZeroNormal {
        /// The collider.
        collider: String,
        /// The normal as given.
        normal: [f64; 3],
    },
    /// A particle centre lies inside a collider at the start (below a ground plane or inside a
    /// ball); `depth` (m) is how far inside.
    #[error("particle {particle} starts inside {collider} (its centre is {depth} m inside)")]
    Overlap {
        /// The collider.
        collider: String,
        /// Particle index.
        particle: usize,
        /// Depth of the particle centre inside the collider (m, >= 0).
        depth: f64,
    },
    /// A dynamic ball's centre starts below a ground plane.
    #[error("{ball} starts with its centre {depth} m below {ground}")]
    BallInGround {
        /// The ball, e.g. `"ball 0"`.
        ball: String,
        /// The ground, e.g. `"ground 1"`.
        ground: String,
        /// Depth of the ball centre below the plane (m, >= 0).
        depth: f64,
    },
    /// A closed surface given to [`crate::Colliders::balls_inside_surface`] is unusable.
    #[error("surface: {0}")]
    BadSurface(String),
}
