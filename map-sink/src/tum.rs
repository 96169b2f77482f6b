//! TUM trajectory files (the format is slam-geom's), written as a run grows and read back
//! for scoring and tests.

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use slam_geom::{Pose2, TumPose, format_tum_line, parse_tum};

use crate::error::SinkError;

/// Appends poses to a TUM file, each line flushed to the kernel as it is written.
///
/// Durability: a trajectory is *appended* line by line instead of being written to a
/// temporary name and renamed like the other results, because a killed run must keep the
/// poses it had. Each line goes to the kernel in one `write` call on an unbuffered file, so
/// a killed process leaves only whole lines; a power cut or a full disk can still cut the
/// last line short, which is why [`read_tum`] skips a final line without a newline.
#[derive(Debug)]
pub struct TumWriter {
    // Deliberately unbuffered: a BufWriter would hold lines back and could split one across
    // two writes, so a killed run would lose poses or leave half a line.
    file: File,
    path: PathBuf,
}

impl TumWriter {
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
        })
    }

    /// Appends one pose as one line, in one write.
    pub fn append(&mut self, stamp_ns: u64, pose: Pose2) -> Result<(), SinkError> {
        let line = format_tum_line(stamp_ns, &pose);
        self.file
            .write_all(line.as_bytes())
            .map_err(|e| SinkError::io("append to", &self.path, e))
    }

    /// Forces what was written onto the disk, for the end of a run.
    pub fn sync(&self) -> Result<(), SinkError> {
        self.file
            .sync_all()
            .map_err(|e| SinkError::io("sync", &self.path, e))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Reads a TUM file (see [`slam_geom::parse_tum`]: a last line cut short by a crash is
/// dropped); a malformed line is an error naming it.
pub fn read_tum(path: &Path) -> Result<Vec<TumPose>, SinkError> {
    let text = fs::read_to_string(path).map_err(|e| SinkError::io("read", path, e))?;
    let poses = parse_tum(&text).map_err(|e| SinkError::Malformed {
        path: path.to_path_buf(),
        line: e.line,
        reason: e.problem.to_string(),
    })?;
    Ok(poses.into_iter().map(|(_, pose)| pose).collect())
}
