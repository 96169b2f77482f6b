//! Why a line was skipped and why a log was refused.

use std::path::PathBuf;

use crate::format::LogFormat;

/// A line of a log that could not be used; the reader skips it and goes on.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {reason}")]
pub struct LineError {
    /// 1-based line number.
    pub line: u64,
    pub reason: String,
}

impl LineError {
    pub(crate) fn new(line: u64, reason: impl Into<String>) -> Self {
        Self {
            line,
            reason: reason.into(),
        }
    }
}

/// What reading the next record of a log can go wrong with.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// A malformed line: report it, skip it, read on.
    #[error(transparent)]
    Line(#[from] LineError),
    /// The file itself cannot be read any more: stop.
    #[error("cannot read the log: {0}")]
    Io(#[from] std::io::Error),
}

/// Why a log cannot be replayed at all.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    #[error("cannot open {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file is not a log of the given format, or has no scan where one must be.
    #[error("{path} is not a {format} log: {reason}")]
    NotThisFormat {
        path: PathBuf,
        format: LogFormat,
        reason: String,
    },
}

/// Why [`crate::check_format`] refused some data.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    #[error("cannot read the log: {0}")]
    Io(#[from] std::io::Error),
    /// Not a log of the format; the text says why.
    #[error("{0}")]
    Mismatch(String),
}
