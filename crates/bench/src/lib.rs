//! Speed against error for perifrac: `perifrac bench accuracy | stability | speed`.
//!
//! [`accuracy`] runs peridynamic cases beside references (closed forms and the project's own
//! finite elements, shown converged) over resolution and horizon sweeps and reports each run's
//! wall time, steps, bonds and error; [`stability`] runs hard cases and says whether each
//! survived, stopped with a message or failed; [`speed`] times the force loop; [`contact`]
//! measures contact between particles; [`look`] measures the cut surface (roughness, crack
//! directions, fragment sizes, validity); [`fracture`] runs the Kalthoff-Winkler impact against
//! its experiment. Results come as
//! [`Table`]s (Markdown) and [`Plot`]s (PNG through plotters). This crate is a harness: it uses
//! the physics, fem, topology and scene crates and is used only by the command line.

#![warn(missing_docs)]

pub mod accuracy;
mod bar;
mod bars;
pub mod contact;
mod error;
pub mod events;
mod facets;
mod fit;
pub mod fracture;
pub mod look;
mod plot;
pub mod preview;
pub mod shells;
pub mod speed;
pub mod stability;
mod table;

pub use bars::Bars;
pub use error::BenchError;
pub use facets::{Facets, Panel};
pub use plot::{Plot, Series, FONT_PATHS};
pub use table::Table;

/// How much of a benchmark to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effort {
    /// The smallest resolutions only, for tests of the harness itself (seconds).
    Tiny,
    /// The sweeps BENCHMARKS.md reports (minutes on two cores).
    Full,
}
