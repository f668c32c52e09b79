//! Peridynamic particles at tet barycentres, families as CSR bonds, the Chen elastoplastic
//! state-based model with fracture, explicit integration and its stable-step estimate
//! (`docs/model.md` sections 1, 2, 4 and 6).
//!
//! The crate takes plain arrays (barycentres, volumes, face adjacency) and knows nothing of the
//! topology or io crates. Units are SI throughout. The pieces are chosen once at setup:
//! a [`Discretization`] (particles and families), a [`ForceModel`] ([`ChenModel`], with plastic
//! and damage state only when a material asks for them) and an integrator ([`Explicit`]).
//!
//! ```
//! use perifrac_physics::*;
//! // four tets in a row (face-adjacent neighbours), 1 cm apart, 1 cm^3 each
//! let x: Vec<Vec3> = (0..4).map(|i| [0.01 * i as f64, 0.0, 0.0]).collect();
//! let vol = vec![1e-6; 4];
//! let m = NO_NEIGHBOUR;
//! let adj = vec![[1, m, m, m], [0, 2, m, m], [1, 3, m, m], [2, m, m, m]];
//! let (disc, report) = Discretization::from_tets(&x, &vol, &adj, 0.025)?;
//! assert!(report.isolated.is_empty());
//! let steel = ChenMaterial::from_young_poisson(200e9, 0.25, 7800.0)?;
//! let model = ChenModel::new(disc, &[steel])?;
//! let config = ExplicitConfig { dt: TimeStep::Auto { safety: 0.8 }, guard_fraction: 0.5 };
//! let mut sim = Explicit::new(model, &x, 0.025, Loads::new(4), config)?;
//! sim.velocities_mut()[3] = [1.0, 0.0, 0.0];
//! let broken = sim.step()?; // bonds broken in this step, as (i, j) with i < j
//! assert!(broken.is_empty());
//! # Ok::<(), PhysicsError>(())
//! ```

#![warn(missing_docs)]

pub mod anisotropy;
pub mod crack_energy;
pub mod energy;
pub mod environment;
pub mod error;
pub mod family;
pub mod fracture;
pub mod ghost;
pub mod integrate;
pub mod loads;
pub mod material;
pub mod math;
mod par;
pub mod particles;
pub mod plastic;
pub mod stable_step;
pub mod state;

pub use environment::{Environment, External, ImplicitEnvironment, NoEnvironment};
pub use error::PhysicsError;
pub use family::{Family, FamilyReport, NO_NEIGHBOUR};
pub use fracture::Damage;
pub use ghost::{
    FaceKind, GhostFaces, GhostFit, GhostLayer, GhostPlane, GhostReport, Ghosted, GHOST_GAIN_BOUND,
    GHOST_SHORTEST_BOND,
};
pub use integrate::{
    EventSearch, EventSearchConfig, Explicit, ExplicitConfig, Implicit, ImplicitConfig, Integrator,
    IntegratorKind, QuasiNewton, Searched, Simulation, Solver, SolverStats, StepInfo, TimeStep,
    VelocityVerlet,
};
pub use loads::{AnchorMotion, Loads};
pub use material::{
    Basis, ChenMaterial, ChenModel, ChenOptions, Correction, Curve, ForceModel, FractureParams,
    QuasiNewtonModel, Spread, XuAnisotropy, XuKernelShape, XuMaterial, XuModel, XuModuli,
    XuOptions, YieldParams,
};
pub use math::{Real, Vec3};
pub use particles::Discretization;
pub use stable_step::{
    lanczos_frequency, lanczos_frequency_of, max_frequency, stable_frequency,
    stable_frequency_memo, EstimateMemo, FrequencyEstimate, MemoKey,
};
pub use state::State;
