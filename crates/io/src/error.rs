//! The error type shared by every reader and writer.

use std::path::{Path, PathBuf};

/// Everything that can go wrong while reading or writing a mesh file.
///
/// Every variant names the file; parse errors also carry the 1-based line.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The operating system refused an operation on `file`.
    #[error("{}: {cause}", file.display())]
    Io {
        /// The file being read or written.
        file: PathBuf,
        /// The underlying error; quoted in the message, so not also returned as the error's
        /// `source()` (printing the cause chain repeats nothing).
        cause: std::io::Error,
    },
    /// The contents of `file` do not follow the format at `line` (1-based).
    #[error("{}:{line}: {message}", file.display())]
    Parse {
        /// The file being read.
        file: PathBuf,
        /// 1-based line where the problem was found.
        line: usize,
        /// What was expected and what was found.
        message: String,
    },
    /// A format problem where no line number is available (binary PLY, errors from tobj).
    #[error("{}: {message}", file.display())]
    Format {
        /// The file being read.
        file: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The file extension is not one this function handles.
    #[error("{}: unknown file extension (known: {known})", file.display())]
    UnknownExtension {
        /// The offending path.
        file: PathBuf,
        /// The extensions that are understood, for the message.
        known: &'static str,
    },
    /// The file is a variant of a known format that is not supported (binary Gmsh, binary VTK).
    #[error("{}: unsupported: {what}", file.display())]
    Unsupported {
        /// The file being read.
        file: PathBuf,
        /// Which variant, and what to do instead.
        what: String,
    },
    /// A companion file is missing (a `.node` for a `.ele`, or the reverse).
    #[error("{}: not found (needed to read {})", missing.display(), from.display())]
    MissingSibling {
        /// The file that was looked for.
        missing: PathBuf,
        /// The file that was asked for.
        from: PathBuf,
    },
    /// The data handed to a writer is inconsistent (index out of range, wrong array length).
    #[error("{}: cannot write: {message}", file.display())]
    InvalidData {
        /// The file that was to be written.
        file: PathBuf,
        /// What is inconsistent.
        message: String,
    },
}

impl IoError {
    /// Wraps an `std::io::Error` with the path it concerns.
    pub fn io(file: &Path, cause: std::io::Error) -> IoError {
        IoError::Io {
            file: file.to_path_buf(),
            cause,
        }
    }

    /// A parse error at `line` of `file`.
    pub fn parse(file: &Path, line: usize, message: impl Into<String>) -> IoError {
        IoError::Parse {
            file: file.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    /// A writer refusing inconsistent data.
    pub fn invalid(file: &Path, message: impl Into<String>) -> IoError {
        IoError::InvalidData {
            file: file.to_path_buf(),
            message: message.into(),
        }
    }
}

/// Reads a whole file into memory, attaching the path to any error.
pub(crate) fn read_all(file: &Path) -> Result<Vec<u8>, IoError> {
    std::fs::read(file).map_err(|e| IoError::io(file, e))
}

impl IoError {
    /// Appends ` ({extra})` to a parse error's message (e.g. which item of a section was being
    /// read); other errors are returned unchanged. `extra` is only built on the error path.
    pub(crate) fn context(self, extra: impl FnOnce() -> String) -> IoError {
        match self {
            IoError::Parse {
                file,
                line,
                message,
            } => IoError::Parse {
                file,
                line,
                message: format!("{message} ({})", extra()),
            },
            other => other,
        }
    }
}
