//! Time integrators and the simulation they advance.

pub mod event_search;
pub mod explicit;
pub mod implicit;
pub mod simulation;
mod step_matrix;

pub use event_search::{EventSearch, EventSearchConfig, Searched};
pub use explicit::{Explicit, ExplicitConfig, TimeStep, VelocityVerlet};
pub use implicit::{Implicit, ImplicitConfig, QuasiNewton, StepInfo};
pub use simulation::{Integrator, IntegratorKind, Simulation, Solver, SolverStats};
