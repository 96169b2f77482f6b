//! Why a saved map directory was refused.

use std::path::PathBuf;

/// Why [`crate::SavedMap::load`] refused a directory; each names the file at fault.
#[derive(Debug, thiserror::Error)]
pub enum MapLoadError {
    /// A file the map needs is not there.
    #[error("{} is missing: not a saved map (a run's output directory holds landmarks.json, map.yaml and map.pgm)", path.display())]
    Missing { path: PathBuf },
    /// A file is there but could not be read, is no regular file or is too large.
    #[error(transparent)]
    Input(#[from] stage_kit::InputError),
    /// A file ends before its content does.
    #[error("{} is truncated: {reason}", path.display())]
    Truncated { path: PathBuf, reason: String },
    /// A file is of another kind than its name says.
    #[error("{} is not what a saved map holds there: {reason}", path.display())]
    Foreign { path: PathBuf, reason: String },
    /// A landmarks file of a version this program does not read.
    #[error("{}: {reason}", path.display())]
    Version { path: PathBuf, reason: String },
    /// A file of the right kind with a field that cannot be used.
    #[error("{}: {reason}", path.display())]
    Malformed { path: PathBuf, reason: String },
    /// The image does not fit its description: another size or another file than the map's
    /// other files say (files of different runs put together).
    #[error("{} does not match the map: {reason}", path.display())]
    ImageMismatch { path: PathBuf, reason: String },
}
