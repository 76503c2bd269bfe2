//! Errors, split by who has to act: bad input (exit status 2) or a failure
//! to write output (exit status 1).

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file that does not parse; `line`/`column` where the format has them.
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    /// A value that parses but is not a valid scene or setting; `field` names it.
    #[error("{field}: {message}")]
    Invalid { field: String, message: String },
    /// An unknown preset or unreadable input.
    #[error("{0}")]
    Input(String),
    /// A render whose samples were mostly NaN or infinite: the scene is
    /// numerically degenerate (see `limits::MAX_REJECTED_FRACTION`).
    #[error("{0}")]
    Degenerate(String),
    /// Writing an output failed.
    #[error("cannot write {path}: {message}")]
    Output { path: PathBuf, message: String },
}

impl Error {
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid { field: field.into(), message: message.into() }
    }

    /// The process exit status for this error: 2 for bad input, 1 for output.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Output { .. } => 1,
            _ => 2,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
