//! TUM trajectory files (the format is slam-geom's), written as a run grows (slam-geom's
//! `read_tum` reads them back).

use std::path::Path;

use slam_geom::{Pose2, format_tum_line};

use crate::error::SinkError;
use crate::line_file::LineFile;

/// Appends poses to a TUM file, each line flushed to the kernel as it is written.
///
/// Durability: a trajectory is *appended* line by line instead of being written to a
/// temporary name and renamed like the other results, because a killed run must keep the
/// poses it had. The file never ends in part of a line, a full disk included (see
/// [`LineFile`]); only a power cut can leave a last line short, which is why
/// [`slam_geom::read_tum`] skips a final line without a newline.
#[derive(Debug)]
pub struct TumWriter {
    file: LineFile,
}

impl TumWriter {
    /// Creates (or empties) the file at `path`.
    pub fn create(path: &Path) -> Result<Self, SinkError> {
        Ok(Self {
            file: LineFile::create(path)?,
        })
    }

    /// Appends one pose as one line, in one write; on a failure the file keeps its whole
    /// lines and the error is returned.
    pub fn append(&mut self, stamp_ns: u64, pose: Pose2) -> Result<(), SinkError> {
        self.file.append(&format_tum_line(stamp_ns, &pose))
    }

    /// The lines written whole.
    pub fn lines(&self) -> u64 {
        self.file.lines()
    }

    /// Forces what was written onto the disk, for the end of a run.
    pub fn sync(&self) -> Result<(), SinkError> {
        self.file.sync()
    }

    pub fn path(&self) -> &Path {
        self.file.path()
    }
}
