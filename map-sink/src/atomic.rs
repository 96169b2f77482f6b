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
    StagedFile::write(path, contents)?.commit()
}

/// A file written and synced under its temporary name, to be renamed into place later:
/// several files staged first and committed one right after the other replace a set of
/// results within the milliseconds of their renames, not within the time it takes to
/// write them. Dropped uncommitted, the temporary file is removed.
#[derive(Debug)]
pub struct StagedFile {
    path: PathBuf,
    tmp: Option<PathBuf>,
}

impl StagedFile {
    /// Writes `contents` to `path`'s temporary name and syncs it; `path` is left as it was.
    pub fn write(path: &Path, contents: &[u8]) -> Result<Self, SinkError> {
        let tmp = tmp_path(path);
        if let Err(e) = write_synced(&tmp, contents) {
            let _ = fs::remove_file(&tmp);
            return Err(e);
        }
        Ok(Self {
            path: path.to_path_buf(),
            tmp: Some(tmp),
        })
    }

    /// Where the contents are until committed (a reader may read them there).
    pub fn staged_at(&self) -> Option<&Path> {
        self.tmp.as_deref()
    }

    /// Renames the temporary file over the file's name, as [`write_atomic`] does.
    pub fn commit(mut self) -> Result<(), SinkError> {
        let Some(tmp) = self.tmp.take() else {
            return Ok(());
        };
        if let Err(e) = fs::rename(&tmp, &self.path) {
            let _ = fs::remove_file(&tmp);
            return Err(SinkError::io("rename into place", &self.path, e));
        }
        sync_parent(&self.path);
        Ok(())
    }
}

impl Drop for StagedFile {
    fn drop(&mut self) {
        if let Some(tmp) = self.tmp.take() {
            let _ = fs::remove_file(tmp);
        }
    }
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
    fn a_staged_file_replaces_the_old_one_only_when_committed() -> Result<(), SinkError> {
        let dir = std::env::temp_dir().join(format!("map-sink-staged-{}", std::process::id()));
        fs::create_dir_all(&dir).map_err(|e| SinkError::io("create", &dir, e))?;
        let path = dir.join("result.txt");
        write_atomic(&path, b"old\n")?;
        let staged = StagedFile::write(&path, b"new\n")?;
        let read = |p: &Path| fs::read(p).unwrap_or_default();
        assert_eq!(read(&path), b"old\n");
        assert_eq!(staged.staged_at().map(read), Some(b"new\n".to_vec()));
        staged.commit()?;
        assert_eq!(read(&path), b"new\n");
        assert!(!tmp_path(&path).exists());
        // Dropped without a commit: the old file stays and nothing is left behind.
        drop(StagedFile::write(&path, b"newer\n")?);
        assert_eq!(read(&path), b"new\n");
        assert!(!tmp_path(&path).exists());
        let _ = fs::remove_dir_all(&dir);
        Ok(())
    }
}
