//! What a path is as a bag: a rosbag2 directory whose metadata names its storage, files
//! and topics, or a bare storage file; and whether an MCAP file holds ROS 2 messages.

use std::io::BufReader;
use std::path::{Path, PathBuf};

use super::error::BagError;
use super::mcap_storage::{McapSource, summary_channels};
use super::metadata::{METADATA_FILE, Metadata, Storage, Topic};
use super::sqlite_storage::SqliteSource;
use super::storage::{Channel, MessageSource};
use super::stream::BAG_FILE_INPUT;
use super::topics::topics_of;

/// Where a bag's messages are.
pub(super) struct Located {
    pub(super) storage: Storage,
    pub(super) files: Vec<PathBuf>,
    /// The topics the bag declares; `None` when only reading it tells (an MCAP file
    /// without a summary).
    pub(super) topics: Option<Vec<Topic>>,
}

/// The storage and files of the bag at `path`, and the topics it declares.
pub(super) fn locate(path: &Path) -> Result<Located, BagError> {
    if path.is_dir() {
        locate_directory(path)
    } else {
        locate_file(path)
    }
}

/// A rosbag2 directory: what its metadata says, each file it names there and openable.
fn locate_directory(path: &Path) -> Result<Located, BagError> {
    if !path.join(METADATA_FILE).exists() {
        return Err(BagError::NoMetadata {
            path: path.to_path_buf(),
        });
    }
    let metadata = Metadata::read(path)?;
    for file in &metadata.files {
        if !file.exists() {
            return Err(BagError::MissingFile {
                metadata: path.join(METADATA_FILE),
                file: file.clone(),
            });
        }
        open_bag_file(path, file)?;
    }
    Ok(Located {
        storage: metadata.storage,
        files: metadata.files,
        topics: Some(metadata.topics),
    })
}

/// A bare `.mcap` or `.db3`: its topics from the MCAP summary or the database.
fn locate_file(path: &Path) -> Result<Located, BagError> {
    let storage = Storage::of_file(path).ok_or_else(|| BagError::NotABag {
        path: path.to_path_buf(),
    })?;
    let file = open_bag_file(path, path)?;
    let channels = match storage {
        Storage::Mcap => summary_channels(BufReader::new(file)),
        Storage::Sqlite3 => Some(SqliteSource::open(path)?.channels()),
    };
    Ok(Located {
        storage,
        files: vec![path.to_path_buf()],
        topics: channels.map(|channels| topics_of(&channels)),
    })
}

/// Opens `file` of the bag at `bag` as [`BAG_FILE_INPUT`].
fn open_bag_file(bag: &Path, file: &Path) -> Result<std::fs::File, BagError> {
    BAG_FILE_INPUT
        .open(file, stage_kit::input::Links::Follow)
        .map_err(|cause| BagError::File {
            bag: bag.to_path_buf(),
            cause,
        })
}

/// Whether the MCAP file at `path` holds ROS 2 messages (a channel in the `cdr` message
/// encoding, as rosbag2 writes every one) rather than a run of slam-record; `None` when it
/// cannot be read far enough to tell.
pub fn is_ros2_mcap(path: &Path) -> Option<bool> {
    let open = || {
        BAG_FILE_INPUT
            .open(path, stage_kit::input::Links::Follow)
            .ok()
    };
    let is_ros2 = |channel: &Channel| channel.encoding == "cdr";
    if let Some(channels) = summary_channels(BufReader::new(open()?))
        && !channels.is_empty()
    {
        return Some(channels.iter().any(is_ros2));
    }
    // No summary (a file cut short): its first message tells.
    let mut source = McapSource::new(BufReader::new(open()?));
    let message = source.next_message()?.ok()?;
    Some(is_ros2(&message.channel))
}
