//! Why a bag cannot be replayed at all, found by the survey before anything is published.

use std::path::PathBuf;

use super::metadata::{METADATA_FILE, MetadataError};
use super::mount::MountError;
use super::sqlite_storage::SqliteError;

/// Why a bag cannot be replayed at all. Each names the bag (or its file) and what is
/// wrong; the underlying error is part of the message.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("{path} is a directory without {METADATA_FILE}: not a rosbag2 bag")]
    NoMetadata { path: PathBuf },
    #[error(transparent)]
    Metadata(#[from] MetadataError),
    /// A file the metadata names is not there.
    #[error("{metadata} names {file}, which is missing")]
    MissingFile { metadata: PathBuf, file: PathBuf },
    /// A bag file that cannot be opened, is not a regular file, or is too large.
    #[error("{bag}")]
    File {
        bag: PathBuf,
        #[source]
        cause: stage_kit::InputError,
    },
    #[error("{path} is not a bag file (.mcap or .db3, or a bag directory)")]
    NotABag { path: PathBuf },
    #[error("{0}")]
    Sqlite(#[from] SqliteError),
    #[error("{path}: {reason}")]
    Topics { path: PathBuf, reason: String },
    #[error("{path} is damaged before its first scan (after {messages} messages): {cause}")]
    Damaged {
        path: PathBuf,
        messages: u64,
        cause: String,
    },
    #[error("{path}: no scan on {topic} it can replay {within}{problem}")]
    NoScan {
        path: PathBuf,
        topic: String,
        within: String,
        problem: String,
    },
    #[error("{path}: {cause}")]
    Mount { path: PathBuf, cause: MountError },
    #[error("stopped while checking {path}")]
    Stopped { path: PathBuf },
}
