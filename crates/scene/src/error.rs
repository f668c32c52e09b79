//! Typed errors of scene loading, setup and running.

use std::path::PathBuf;
use thiserror::Error;

/// Everything that can stop a scene from loading or running.
///
/// A variant that wraps another crate's error quotes it in its message and keeps it in a
/// `cause` field, not as the error's `source()`, so printing the cause chain repeats nothing.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file cannot be read.
    #[error("cannot read scene {file}: {cause}")]
    Read {
        /// The scene file.
        file: PathBuf,
        /// The OS error.
        cause: std::io::Error,
    },
    /// TOML syntax, an unknown key or a wrong type, at a line and column.
    #[error("{file}:{line}:{column}: {message}")]
    Parse {
        /// The scene file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// A value out of range or inconsistent with another.
    #[error("{file}: {key}: {message}")]
    Invalid {
        /// The scene file.
        file: PathBuf,
        /// The key path, e.g. `material[0].density`.
        key: String,
        /// What is wrong, with the value.
        message: String,
    },
    /// The mesh could not be read or built.
    #[error("{file}: mesh: {message}")]
    Mesh {
        /// The scene file.
        file: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The physics setup refused the scene.
    #[error("{file}: {cause}")]
    Physics {
        /// The scene file.
        file: PathBuf,
        /// The physics crate's error.
        cause: perifrac_physics::PhysicsError,
    },
    /// The output directory cannot be used.
    #[error("output directory {dir}: {message}")]
    Output {
        /// The directory.
        dir: PathBuf,
        /// Why not.
        message: String,
    },
    /// The run would pass a budget (memory, steps, output, wall time; see
    /// [`crate::budget::Limits`]); the message quotes the estimate and the budget.
    #[error("{file}: {message}")]
    TooLarge {
        /// The scene file.
        file: PathBuf,
        /// The estimate against the budget it passes.
        message: String,
    },
    /// Writing a frame failed.
    #[error(transparent)]
    Io(#[from] perifrac_io::IoError),
    /// A checkpoint that cannot be resumed.
    #[error("{path}: {message}")]
    Checkpoint {
        /// The checkpoint file.
        path: PathBuf,
        /// Why not.
        message: String,
    },
    /// The run was interrupted (a signal); the frames written so far are kept and a
    /// checkpoint holds the state.
    #[error(
        "interrupted at t = {time:.6e} s (step {step}) after writing {frames} frame(s); \
         checkpoint in {checkpoint}"
    )]
    Interrupted {
        /// Simulated time (s).
        time: f64,
        /// Steps completed.
        step: u64,
        /// Frames written and kept.
        frames: usize,
        /// The checkpoint written.
        checkpoint: PathBuf,
    },
    /// The run stopped (an instability); the frames written so far are kept.
    #[error("stopped at t = {time:.6e} s (step {step}) after writing {frames} frame(s): {cause}")]
    Stopped {
        /// Simulated time (s).
        time: f64,
        /// Steps completed.
        step: u64,
        /// Frames written and kept.
        frames: usize,
        /// What the step reported.
        cause: crate::body::StepError,
    },
}

impl SceneError {
    /// Shorthand for [`SceneError::Invalid`].
    pub(crate) fn invalid(
        file: &std::path::Path,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError::Invalid {
            file: file.to_path_buf(),
            key: key.into(),
            message: message.into(),
        }
    }
}
