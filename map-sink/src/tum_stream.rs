//! A trajectory file appended as the run goes, which stops, not the run, when it cannot be
//! written.

use std::path::{Path, PathBuf};

use slam_geom::Pose2;

use crate::error::SinkError;
use crate::tum::TumWriter;
use slam_eval::IncompleteOutput;

#[derive(Debug)]
enum State {
    /// No pose yet: no file, so a run without truth (or without dead reckoning) leaves no
    /// empty file suggesting otherwise.
    Unstarted,
    Writing(TumWriter),
    /// A write failed: the file keeps its whole lines and takes no more.
    Stopped,
}

/// One of the per-scan trajectory files (`trajectory_online.tum`, `dead_reckoning.tum`,
/// `ground_truth.tum`). A full disk stops the file at its last whole line (see
/// [`TumWriter::append`]); the poses still go to the rest of the run (scoring, the final
/// trajectory, the picture), which is worth more than one more line of this file.
#[derive(Debug)]
pub struct TumStream {
    path: PathBuf,
    state: State,
}

impl TumStream {
    /// A stream whose file is made with its first pose.
    pub fn lazy(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
            state: State::Unstarted,
        }
    }

    /// A stream whose file is made (or emptied) now.
    pub fn start(path: &Path) -> Result<Self, SinkError> {
        Ok(Self {
            path: path.to_path_buf(),
            state: State::Writing(TumWriter::create(path)?),
        })
    }

    /// Appends one pose. The first failure stops the stream and is returned, once; a
    /// stopped stream drops every later pose.
    pub fn append(&mut self, stamp_ns: u64, pose: Pose2) -> Option<IncompleteOutput> {
        if let State::Unstarted = self.state {
            match TumWriter::create(&self.path) {
                Ok(writer) => self.state = State::Writing(writer),
                Err(e) => {
                    self.state = State::Stopped;
                    return Some(IncompleteOutput::new(self.name(), "not written", &e));
                }
            }
        }
        let State::Writing(writer) = &mut self.state else {
            return None;
        };
        let error = writer.append(stamp_ns, pose).err()?;
        let what = format!("stopped after {} lines", writer.lines());
        self.state = State::Stopped;
        Some(IncompleteOutput::new(self.name(), &what, &error))
    }

    /// Forces what was written onto the disk, for the end of a run; the error of a stream
    /// whose lines may not all be on the disk.
    pub fn sync(&self) -> Option<IncompleteOutput> {
        let State::Writing(writer) = &self.state else {
            return None;
        };
        let error = writer.sync().err()?;
        Some(IncompleteOutput::new(self.name(), "not synced", &error))
    }

    /// The file's name.
    pub fn name(&self) -> &str {
        self.path
            .file_name()
            .and_then(|name| name.to_str())
            .unwrap_or_default()
    }
}
