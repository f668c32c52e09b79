//! Errors of the benchmark harness.

use thiserror::Error;

/// What stops a benchmark. A variant that wraps another crate's error quotes it in its message
/// and keeps it in a `cause` field, not as the error's `source()`, so printing the cause chain
/// repeats nothing.
#[derive(Debug, Error)]
pub enum BenchError {
    /// The peridynamic side refused a setting or diverged.
    #[error("{case}: {cause}")]
    Physics {
        /// The case, e.g. `cantilever 20x2x2 k=1.5`.
        case: String,
        /// The physics crate's error.
        cause: perifrac_physics::PhysicsError,
    },
    /// The finite-element reference failed.
    #[error("{case}: {cause}")]
    Fem {
        /// The case.
        case: String,
        /// The fem crate's error.
        cause: perifrac_fem::FemError,
    },
    /// A mesh could not be built.
    #[error("{case}: {message}")]
    Mesh {
        /// The case.
        case: String,
        /// What went wrong.
        message: String,
    },
    /// A scene (the speed benchmark's TOML) was refused.
    #[error("{case}: {message}")]
    Scene {
        /// The case.
        case: String,
        /// What went wrong.
        message: String,
    },
    /// An accuracy case name that is none of `accuracy::CASES`.
    #[error("unknown accuracy case {0:?}; the cases are {cases}", cases = crate::accuracy::CASES.join(", "))]
    UnknownCase(String),
    /// A thread pool could not be built.
    #[error("a thread pool: {message}")]
    Threads {
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
