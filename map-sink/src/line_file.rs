//! A text file appended line by line that never ends in part of a line.

use std::fs::{File, OpenOptions};
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::error::SinkError;

/// A file of lines, each handed to the kernel whole, in one write.
///
/// A killed process therefore leaves only whole lines. A full disk takes what fits of a
/// line and refuses the rest: the file is then cut back to its last whole line and the
/// error returned, so the caller can stop writing it. Only a power cut can still leave a
/// last line short.
#[derive(Debug)]
pub struct LineFile {
    // Deliberately unbuffered: a BufWriter would hold lines back and could split one across
    // two writes, so a killed run would lose lines or leave half of one.
    file: File,
    path: PathBuf,
    /// Bytes of the whole lines written.
    whole: u64,
    lines: u64,
}

impl LineFile {
    /// Creates (or empties) the file at `path`.
    pub fn create(path: &Path) -> Result<Self, SinkError> {
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)
            .map_err(|e| SinkError::io("create", path, e))?;
        Ok(Self {
            file,
            path: path.to_path_buf(),
            whole: 0,
            lines: 0,
        })
    }

    /// Appends `line` (which must end with its newline) in one write. When the write fails,
    /// the part of it that went in is taken back and the error returned.
    pub fn append(&mut self, line: &str) -> Result<(), SinkError> {
        if let Err(e) = self.file.write_all(line.as_bytes()) {
            // Shrinking takes no space, so this works on a full disk too.
            let _ = self.file.set_len(self.whole);
            let _ = self.file.seek(SeekFrom::Start(self.whole));
            return Err(SinkError::io("append to", &self.path, e));
        }
        self.whole += line.len() as u64;
        self.lines += 1;
        Ok(())
    }

    /// The lines written whole.
    pub fn lines(&self) -> u64 {
        self.lines
    }

    /// Forces what was written onto the disk.
    pub fn sync(&self) -> Result<(), SinkError> {
        self.file
            .sync_all()
            .map_err(|e| SinkError::io("sync", &self.path, e))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_counted_and_kept_whole() -> Result<(), SinkError> {
        let dir = std::env::temp_dir().join(format!("map-sink-line-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| SinkError::io("create", &dir, e))?;
        let path = dir.join("a.txt");
        let mut file = LineFile::create(&path)?;
        file.append("one\n")?;
        file.append("two\n")?;
        assert_eq!(file.lines(), 2);
        file.sync()?;
        let text = std::fs::read_to_string(&path).map_err(|e| SinkError::io("read", &path, e))?;
        assert_eq!(text, "one\ntwo\n");
        let _ = std::fs::remove_dir_all(&dir);
        Ok(())
    }
}
