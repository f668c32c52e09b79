//! Errors of the benchmark harness.

use thiserror::Error;

/// What stops a benchmark.
#[derive(Debug, Error)]
pub enum BenchError {
    /// The peridynamic side refused a setting or diverged.
    #[error("{case}: {source}")]
    Physics {
        /// The case, e.g. `cantilever 20x2x2 k=1.5`.
        case: String,
        /// The physics crate's error.
        source: perifrac_physics::PhysicsError,
    },
    /// The finite-element reference failed.
    #[error("{case}: {source}")]
    Fem {
        /// The case.
        case: String,
        /// The fem crate's error.
        source: perifrac_fem::FemError,
    },
    /// A mesh could not be built.
    #[error("{case}: {message}")]
    Mesh {
        /// The case.
        case: String,
        /// What went wrong.
        message: String,
    },
    /// A plot could not be drawn or written.
    #[error("plot {file}: {message}")]
    Plot {
        /// The PNG file.
        file: String,
        /// What went wrong.
        message: String,
    },
}
