//! The one error type of the crate.

use std::io;
use std::path::PathBuf;

/// Why recording or reading a run failed.
#[derive(Debug, thiserror::Error)]
pub enum SinkError {
    /// A file system operation failed; `action` says which, `path` on what.
    // The cause is the source, not part of the message: `{:#}` would print it twice.
    #[error("cannot {action} {}", path.display())]
    Io {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A [`RecorderOptions`](crate::RecorderOptions) value is out of range.
    #[error("invalid recorder option: {0}")]
    InvalidOption(String),
    /// A trajectory could not be scored against the relations (the error names the file
    /// and line).
    #[error(transparent)]
    Score(#[from] slam_eval::EvalError),
    /// The occupancy grid could not be built.
    #[error(transparent)]
    Grid(#[from] back_end::occupancy_grid::GridError),
    /// The saved map's grid cannot be the start of this run's.
    #[error("cannot map on the saved map: {0}")]
    PriorGrid(#[from] crate::prior_grid::PriorGridError),
    /// The grid's PNG could not be encoded.
    #[error("cannot encode the grid as PNG: {0}")]
    Png(String),
    /// The metrics could not be serialised (only non-string map keys could cause it).
    #[error("cannot serialise the metrics or the landmarks: {0}")]
    Json(#[from] serde_json::Error),
}

impl SinkError {
    /// Wraps an I/O error with what was being done and to which file.
    pub(crate) fn io(action: &'static str, path: impl Into<PathBuf>, source: io::Error) -> Self {
        Self::Io {
            action,
            path: path.into(),
            source,
        }
    }
}
