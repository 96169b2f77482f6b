//! A rosbag2 directory's `metadata.yaml`: which storage, which files, which topics.
//!
//! Only what the replay needs is read; every other key (durations, QoS profiles, type
//! hashes, custom data) is left alone, so bags of every rosbag2 version (1 to 9) read.

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// The metadata file of a bag directory.
pub const METADATA_FILE: &str = "metadata.yaml";

/// A metadata file: a few kilobytes, more for a bag of thousands of topics or files.
pub const METADATA_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "bag metadata",
    limit_name: "lidar_replay::rosbag::METADATA_INPUT",
    max_bytes: 16 << 20,
};

/// How a bag's messages are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    Mcap,
    Sqlite3,
}

impl Storage {
    /// The storage of a file, by its extension (`.mcap`, `.db3`).
    pub fn of_file(path: &Path) -> Option<Self> {
        match path.extension()?.to_str()? {
            "mcap" => Some(Self::Mcap),
            "db3" => Some(Self::Sqlite3),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Mcap => "mcap",
            Self::Sqlite3 => "sqlite3",
        }
    }
}

/// A topic of a bag and its type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topic {
    pub name: String,
    /// `sensor_msgs/msg/LaserScan`, ...
    pub type_name: String,
    /// Messages on it, when the bag says.
    pub messages: Option<u64>,
}

/// What a bag directory's metadata says.
#[derive(Debug, Clone, PartialEq)]
pub struct Metadata {
    pub storage: Storage,
    /// The storage files, in order, as paths beside the metadata.
    pub files: Vec<PathBuf>,
    pub topics: Vec<Topic>,
}

/// Why a bag's metadata cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum MetadataError {
    #[error(transparent)]
    Input(#[from] stage_kit::InputError),
    #[error("{path} is not rosbag2 metadata: {reason}")]
    Invalid { path: PathBuf, reason: String },
    #[error("{path}: storage '{storage}' is not one lidar-replay reads (mcap, sqlite3)")]
    Storage { path: PathBuf, storage: String },
    #[error(
        "{path}: the bag is compressed ({mode} {format}); decompress it first \
         (`ros2 bag convert`, or `rosbags-convert`)"
    )]
    Compressed {
        path: PathBuf,
        mode: String,
        format: String,
    },
    #[error("{path} names {file}, which is not a file name in the bag's directory")]
    BadFileName { path: PathBuf, file: String },
}

#[derive(Deserialize)]
struct File {
    rosbag2_bagfile_information: Information,
}

#[derive(Deserialize)]
struct Information {
    #[serde(default)]
    storage_identifier: String,
    #[serde(default)]
    relative_file_paths: Vec<String>,
    #[serde(default)]
    topics_with_message_count: Vec<TopicCount>,
    #[serde(default)]
    compression_format: String,
    #[serde(default)]
    compression_mode: String,
}

#[derive(Deserialize)]
struct TopicCount {
    topic_metadata: TopicMetadata,
    #[serde(default)]
    message_count: Option<u64>,
}

#[derive(Deserialize)]
struct TopicMetadata {
    name: String,
    #[serde(rename = "type")]
    type_name: String,
}

impl Metadata {
    /// Reads `DIR/metadata.yaml` (a regular file within [`METADATA_INPUT`]).
    pub fn read(dir: &Path) -> Result<Self, MetadataError> {
        let path = dir.join(METADATA_FILE);
        let text = METADATA_INPUT.read_to_string(&path)?;
        Self::parse(&text, dir, &path)
    }

    /// The metadata in `text`, its files placed in `dir`; `path` names it in errors.
    pub fn parse(text: &str, dir: &Path, path: &Path) -> Result<Self, MetadataError> {
        let invalid = |reason: String| MetadataError::Invalid {
            path: path.to_path_buf(),
            reason,
        };
        let file: File = serde_yaml_ng::from_str(text).map_err(|e| invalid(e.to_string()))?;
        let info = file.rosbag2_bagfile_information;
        if !info.compression_mode.is_empty() || !info.compression_format.is_empty() {
            return Err(MetadataError::Compressed {
                path: path.to_path_buf(),
                mode: info.compression_mode,
                format: info.compression_format,
            });
        }
        let storage = match info.storage_identifier.as_str() {
            "mcap" => Storage::Mcap,
            "sqlite3" => Storage::Sqlite3,
            // rosbag2 of Foxy and Galactic leaves it empty for SQLite3; the files say.
            "" => info
                .relative_file_paths
                .first()
                .and_then(|file| Storage::of_file(Path::new(file)))
                .ok_or_else(|| invalid("no storage_identifier".into()))?,
            other => {
                return Err(MetadataError::Storage {
                    path: path.to_path_buf(),
                    storage: other.to_owned(),
                });
            }
        };
        if info.relative_file_paths.is_empty() {
            return Err(invalid("relative_file_paths names no file".into()));
        }
        let files = info
            .relative_file_paths
            .iter()
            .map(|file| {
                // Some writers put the bag's directory before the name; the file is beside
                // the metadata either way, and never elsewhere.
                let name = Path::new(file)
                    .file_name()
                    .filter(|name| *name != ".." && *name != ".");
                name.map(|name| dir.join(name))
                    .ok_or_else(|| MetadataError::BadFileName {
                        path: path.to_path_buf(),
                        file: file.clone(),
                    })
            })
            .collect::<Result<_, _>>()?;
        let topics = info
            .topics_with_message_count
            .into_iter()
            .map(|topic| Topic {
                name: topic.topic_metadata.name,
                type_name: topic.topic_metadata.type_name,
                messages: topic.message_count,
            })
            .collect();
        Ok(Self {
            storage,
            files,
            topics,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the `rosbags` writer and `ros2 bag record` write (abridged).
    const JAZZY: &str = "rosbag2_bagfile_information:
  version: 9
  storage_identifier: mcap
  duration:
    nanoseconds: 423997024000
  starting_time:
    nanoseconds_since_epoch: 1134864629895182000
  message_count: 3977
  topics_with_message_count:
    - topic_metadata:
        name: /scan
        type: sensor_msgs/msg/LaserScan
        serialization_format: cdr
        offered_qos_profiles: \"- history: 3\\n  depth: 0\"
        type_description_hash: RIHS01_64c1
      message_count: 1988
    - topic_metadata:
        name: /odom
        type: nav_msgs/msg/Odometry
        serialization_format: cdr
        offered_qos_profiles: []
      message_count: 1988
  compression_format: \"\"
  compression_mode: \"\"
  relative_file_paths:
    - my_bag_0.mcap
  files:
    - path: my_bag_0.mcap
      message_count: 3977
  custom_data: ~
  ros_distro: jazzy
";

    fn parse(text: &str) -> Result<Metadata, MetadataError> {
        Metadata::parse(text, Path::new("/bags/my_bag"), Path::new("metadata.yaml"))
    }

    #[test]
    fn the_storage_files_and_topics_are_read() {
        let metadata = parse(JAZZY).unwrap();
        assert_eq!(metadata.storage, Storage::Mcap);
        assert_eq!(
            metadata.files,
            [PathBuf::from("/bags/my_bag/my_bag_0.mcap")]
        );
        assert_eq!(metadata.topics.len(), 2);
        assert_eq!(metadata.topics[0].name, "/scan");
        assert_eq!(metadata.topics[0].type_name, "sensor_msgs/msg/LaserScan");
        assert_eq!(metadata.topics[1].messages, Some(1988));
    }

    #[test]
    fn an_old_bag_without_a_storage_name_is_known_by_its_files() {
        let foxy = "rosbag2_bagfile_information:\n  version: 4\n  storage_identifier: ''\n  \
                    relative_file_paths: [bag/bag_0.db3]\n  topics_with_message_count: []\n";
        let metadata = parse(foxy).unwrap();
        assert_eq!(metadata.storage, Storage::Sqlite3);
        // The directory a writer put before the name is the bag's own.
        assert_eq!(metadata.files, [PathBuf::from("/bags/my_bag/bag_0.db3")]);
    }

    #[test]
    fn what_cannot_be_replayed_is_refused_by_name() {
        let compressed = JAZZY
            .replace("compression_format: \"\"", "compression_format: zstd")
            .replace("compression_mode: \"\"", "compression_mode: FILE");
        assert_eq!(
            parse(&compressed).unwrap_err().to_string(),
            "metadata.yaml: the bag is compressed (FILE zstd); decompress it first \
             (`ros2 bag convert`, or `rosbags-convert`)"
        );
        let other = JAZZY.replace("storage_identifier: mcap", "storage_identifier: bag_v1");
        assert!(parse(&other).unwrap_err().to_string().contains("'bag_v1'"));
        let escape = JAZZY.replace("- my_bag_0.mcap", "- ..");
        assert!(matches!(
            parse(&escape),
            Err(MetadataError::BadFileName { .. })
        ));
        let none = JAZZY
            .replace("- my_bag_0.mcap", "[]")
            .replace("relative_file_paths:\n", "relative_file_paths: ");
        assert!(parse(&none).is_err());
        assert!(parse("just: text").unwrap_err().to_string().starts_with(
            "metadata.yaml is not rosbag2 metadata: missing field `rosbag2_bagfile_information`"
        ));
    }
}
