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
    if let Err(e) = written {
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_write_replaces_the_old_file_whole_and_leaves_nothing_behind() -> Result<(), SinkError> {
        let dir = std::env::temp_dir().join(format!("map-sink-atomic-{}", std::process::id()));
        fs::create_dir_all(&dir).map_err(|e| SinkError::io("create", &dir, e))?;
        let path = dir.join("result.txt");
        write_atomic(&path, b"old\n")?;
        write_atomic(&path, b"new\n")?;
        assert_eq!(fs::read(&path).unwrap_or_default(), b"new\n");
        assert!(!tmp_path(&path).exists());
        // A file that cannot take the place of the old one (a directory stands there): the
        // directory stays and the temporary file is gone.
        let blocked = dir.join("blocked");
        fs::create_dir_all(blocked.join("inside")).map_err(|e| SinkError::io("create", &dir, e))?;
        assert!(write_atomic(&blocked, b"x\n").is_err());
        assert!(blocked.is_dir());
        assert!(!tmp_path(&blocked).exists());
        let _ = fs::remove_dir_all(&dir);
        Ok(())
    }
}
