//! Time integrators.

pub mod explicit;

pub use explicit::{Explicit, ExplicitConfig, External, TimeStep};
