//! Why a trajectory or a relations file could not be scored.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    // The cause is the error's source, not part of its message: `{:#}` prints the chain,
    // and would print the cause twice.
    #[error("cannot read {}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// An input file that is no regular file, too large or unreadable.
    #[error(transparent)]
    Input(#[from] stage_kit::InputError),
    #[error("{}, line {line}: {reason}", path.display())]
    Malformed {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    #[error("{} has no {what}", path.display())]
    Empty { path: PathBuf, what: &'static str },
}
