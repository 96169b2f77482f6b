//! Whole-file writes that a crash cannot leave half done.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::SinkError;

/// Writes `contents` to `path` through `path` + `.tmp`: the temporary file is written and
/// synced before it is renamed over `path`, so a reader (or a crash) sees either the old
/// file or the complete new one, never a prefix.
/// On failure (a full disk) the temporary file is removed, so none is left half-written.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), SinkError> {
    let tmp = tmp_path(path);
    let written = write_synced(&tmp, contents).and_then(|()| {
        fs::rename(&tmp, path).map_err(|e| SinkError::io("rename into place", path, e))
    });
    if written.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    written?;
    sync_parent(path);
    Ok(())
}

/// Writes `contents` into a new file at `tmp` and syncs it.
fn write_synced(tmp: &Path, contents: &[u8]) -> Result<(), SinkError> {
    let mut file = File::create(tmp).map_err(|e| SinkError::io("create", tmp, e))?;
    file.write_all(contents)
        .map_err(|e| SinkError::io("write", tmp, e))?;
    // Without the sync a crash soon after the rename can leave the new name pointing at an
    // empty file on file systems that reorder metadata before data.
    file.sync_all().map_err(|e| SinkError::io("sync", tmp, e))
}

/// The temporary name `write_atomic` uses for `path`: same directory, so the rename never
/// crosses file systems.
pub fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Makes the rename itself durable. Best effort: some file systems refuse to sync a
/// directory, and the file's content is already safe either way.
fn sync_parent(path: &Path) {
    if let Some(dir) = path.parent()
        && let Ok(dir) = File::open(if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        })
    {
        let _ = dir.sync_all();
    }
}
