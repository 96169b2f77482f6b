//! The messages of a bag's files as one stream, one file after the other, whatever their
//! storage; a file that cannot be opened or read on ends the stream.

use std::io::BufReader;
use std::path::{Path, PathBuf};

use super::mcap_storage::McapSource;
use super::metadata::Storage;
use super::sqlite_storage::SqliteSource;
use super::storage::{Damaged, MessageSource, RawMessage};

/// A storage file of a bag: read as a stream, so its size bounds nothing but what no bag
/// is (a sparse file of tebibytes).
pub const BAG_FILE_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "bag file",
    limit_name: "lidar_replay::rosbag::BAG_FILE_INPUT",
    max_bytes: 1 << 40,
};

/// The messages of a bag's files, one file after the other.
pub(super) struct Messages {
    storage: Storage,
    files: Vec<PathBuf>,
    next_file: usize,
    current: Option<Box<dyn MessageSource>>,
    /// Messages read so far, of every topic.
    read: u64,
    ended: bool,
}

impl std::fmt::Debug for Messages {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Messages")
            .field("files", &self.files)
            .field("read", &self.read)
            .finish()
    }
}

impl Messages {
    pub(super) fn new(storage: Storage, files: Vec<PathBuf>) -> Self {
        Self {
            storage,
            files,
            next_file: 0,
            current: None,
            read: 0,
            ended: false,
        }
    }

    /// Messages read so far, of every topic: the last one's index, counting from 1.
    pub(super) fn read(&self) -> u64 {
        self.read
    }

    /// The next message, `Err` once when a file cannot be opened or read on, `None` after
    /// the last file's last message or the error.
    pub(super) fn next(&mut self) -> Option<Result<RawMessage, Damaged>> {
        while !self.ended {
            let Some(current) = &mut self.current else {
                if let Err(e) = self.open_next()? {
                    return Some(Err(e));
                }
                continue;
            };
            match current.next_message() {
                Some(Ok(message)) => {
                    self.read += 1;
                    return Some(Ok(message));
                }
                Some(Err(e)) => return Some(Err(self.damaged(e))),
                None => self.current = None,
            }
        }
        None
    }

    /// Opens the next file; `None` when there is none left. Either way but success, the
    /// stream has ended.
    fn open_next(&mut self) -> Option<Result<(), Damaged>> {
        let Some(path) = self.files.get(self.next_file) else {
            self.ended = true;
            return None;
        };
        let opened = self.open(path);
        self.next_file += 1;
        Some(match opened {
            Ok(source) => {
                self.current = Some(source);
                Ok(())
            }
            Err(e) => {
                self.ended = true;
                Err(e)
            }
        })
    }

    fn open(&self, path: &Path) -> Result<Box<dyn MessageSource>, Damaged> {
        let file = BAG_FILE_INPUT
            .open(path, stage_kit::input::Links::Follow)
            .map_err(|e| Damaged(format!("{e:#}")))?;
        Ok(match self.storage {
            Storage::Mcap => Box::new(McapSource::new(BufReader::new(file))),
            Storage::Sqlite3 => {
                Box::new(SqliteSource::open(path).map_err(|e| Damaged(e.to_string()))?)
            }
        })
    }

    /// The damage of the file being read, named; the files after it are not read either.
    fn damaged(&mut self, e: Damaged) -> Damaged {
        self.ended = true;
        let file = self.files[self.next_file - 1].display();
        Damaged(format!("{file}: {}", e.0))
    }
}
