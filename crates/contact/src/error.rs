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
    /// A particle's contact sphere starts inside a collider (below a ground plane or inside a
    /// ball); `depth` (m) is how far it reaches in.
    #[error(
        "particle {particle} starts {depth:.3e} m inside {collider} (its contact sphere); \
         move them at least that far apart"
    )]
    Overlap {
        /// The collider.
        collider: String,
        /// Particle index.
        particle: usize,
        /// How far the contact sphere reaches into the collider (m, > 0).
        depth: f64,
    },
    /// A dynamic ball starts reaching into a ground plane.
    #[error("{ball} starts {depth:.3e} m inside {ground}; lift it at least that far")]
    BallInGround {
        /// The ball, e.g. `"ball 0"`.
        ball: String,
        /// The ground, e.g. `"ground 1"`.
        ground: String,
        /// How far the ball reaches below the plane (m, > 0).
        depth: f64,
    },
    /// A closed surface given to [`crate::Colliders::balls_inside_surface`] is unusable.
    #[error("surface: {0}")]
    BadSurface(String),
    /// A particle value given to [`crate::Colliders::begin_implicit`] is unusable.
    #[error("particle {particle}: {what} must be {expected}, got {value}")]
    BadParticle {
        /// Particle index (the lowest with a bad value).
        particle: usize,
        /// Which value: `"position"`, `"velocity"`, `"mass"` or `"contact radius"`.
        what: &'static str,
        /// What it must be, e.g. `"finite and > 0"`.
        expected: &'static str,
        /// The offending value (the first non-finite component for vectors).
        value: f64,
    },
    /// A setting of the implicit step is unusable.
    #[error("{what} must be {expected}, got {value}")]
    BadSetting {
        /// Which setting.
        what: &'static str,
        /// What it must be.
        expected: &'static str,
        /// The offending value.
        value: f64,
    },
    /// [`crate::Colliders::stop_ball`] was asked to stop a ball that cannot be stopped.
    #[error("{ball}: {reason}")]
    CannotStop {
        /// The ball, e.g. `"ball 0"`.
        ball: String,
        /// Why not.
        reason: String,
    },
    /// Self contact was given inconsistent inputs (array lengths).
    #[error("self contact: {0}")]
    BadSelfContact(String),
}
