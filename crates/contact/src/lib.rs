//! Penalty contact of peridynamic particles against parry3d colliders (docs/model.md section 7).
//!
//! Particles are spheres (`[f64; 3]` centres in m, contact radii in m, masses in kg) handed in as
//! plain slices; colliders are ground half-spaces and balls, stored as parry3d shapes with their
//! poses. A ball is kinematic (prescribed constant velocity) or dynamic (mass, gravity, the
//! reaction of the particles it touches, and contact with the ground planes).
//!
//! [`Colliders::step`] adds penalty, damping and Coulomb friction forces into the caller's force
//! array inside the caller's velocity-Verlet step; see its documentation for the call order.
//!
//! For an implicit integrator, [`Colliders::begin_implicit`], [`Colliders::implicit_potential`]
//! and [`Colliders::end_implicit`] give contact as an incremental potential over the particles'
//! end positions and the dynamic balls' end centres (damping and friction as lagged
//! dissipative potentials).
//!
//! [`SelfContact`] pushes apart particles of the body that share no intact bond (fragments,
//! the faces of a crack), from a Verlet list of nearby pairs, as forces and as a penalty
//! potential. This crate
//! does not know the physics crate.

mod colliders;
mod desc;
mod error;
mod implicit;
mod incremental;
mod kernel;
mod math;
mod pairs;
mod params;
mod persist;
mod step;
mod surface;

pub use colliders::{BallState, Colliders, GroundState};
pub use desc::{BallDesc, BallMotion, GroundDesc};
pub use error::ContactError;
pub use pairs::{Bonds, SelfContact, SelfContactParams, SelfContactStats, MAX_TOUCHING};
pub use params::ContactParams;
pub use step::ContactStats;

/// A point or vector in 3D (m, m/s or N depending on use).
pub type Vec3 = [f64; 3];
