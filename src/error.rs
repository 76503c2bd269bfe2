//! Errors, split by who has to act: bad input (exit status 2), or a failure
//! of the system around rtow: an output that cannot be written, threads that
//! cannot start (exit status 1).

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file that does not parse; `line`/`column` where the format has them.
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    /// A value that parses but is not a valid scene or setting; `field` names it.
    #[error("{field}: {message}")]
    Invalid { field: String, message: String },
    /// An error about the values of the scene read from `path`.
    #[error("{}: {error}", path.display())]
    InFile { path: PathBuf, error: Box<Error> },
    /// An unknown preset or unreadable input.
    #[error("{0}")]
    Input(String),
    /// A render that rejected too many samples (NaN, infinite, or out of the
    /// film's range): the scene is numerically degenerate (see
    /// `limits::MAX_REJECTED_FRACTION`); or any, under `OnRejected::Error`.
    #[error("{0}")]
    Degenerate(String),
    /// Writing an output failed.
    #[error("cannot write {path}: {message}")]
    Output { path: PathBuf, message: String },
    /// The operating system refused a resource (e.g. worker threads).
    #[error("{0}")]
    System(String),
    /// A signal (its number) stopped the run before it had anything to keep.
    #[error("{message}")]
    Interrupted { signal: i32, message: String },
}

impl Error {
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid { field: field.into(), message: message.into() }
    }

    /// The process exit status for this error: 2 for bad input, 1 for a
    /// failure to write output or to get a resource, 128 + the signal for
    /// an interrupted run.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Output { .. } | Error::System(_) => 1,
            Error::Interrupted { signal, .. } => 128 + signal,
            Error::InFile { error, .. } => error.exit_code(),
            _ => 2,
        }
    }

    /// The error without its file context (what it says about a value).
    pub fn root(&self) -> &Error {
        match self {
            Error::InFile { error, .. } => error.root(),
            e => e,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
