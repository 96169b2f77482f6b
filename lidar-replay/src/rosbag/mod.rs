//! ROS 2 bags (rosbag2) as a log: a bag directory (its `metadata.yaml` and its MCAP or
//! SQLite3 files), or a bare `.mcap` / `.db3` file of ROS 2 messages.
//!
//! * Scans come from `sensor_msgs/msg/LaserScan` on one topic (`--scan-topic`, or the
//!   bag's only LaserScan topic), each with its own geometry, ranges in REP 117 form and
//!   stamped by its `header.stamp`.
//! * Odometry comes from `nav_msgs/msg/Odometry` (of the base frame) or from `/tf` (the odom
//!   frame to the base frame), [`OdometryFrom`]; the pose at each scan's stamp is
//!   interpolated between the readings around it and published right before the scan
//!   ([`pairing`]), with the message's covariance added to the replay's odometry model.
//! * The laser's mount is the chain of `/tf_static` transforms from the base frame to the
//!   scans' `frame_id` ([`mount`]), so that a run's trajectories are the base frame's.
//! * Messages go out in stamp order within the reordering window of CARMEN logs; what is
//!   late, repeats a stamp, is of another type or cannot be decoded is counted and
//!   skipped; a bag cut short replays up to the damage and says where it was cut.
//!
//! Before anything is published the bag is surveyed ([`open_bag_until`]): its topics
//! chosen, its first scan read, its static transforms gathered (those recorded before
//! the first scan or within [`STATIC_LOOKAHEAD_NS`] after it, where a recorder puts the
//! latched `/tf_static`); a bag that cannot be replayed is refused then, saying why.

mod cdr;
mod mcap_storage;
mod messages;
mod metadata;
mod mount;
mod pairing;
mod sqlite_storage;
mod storage;
#[cfg(test)]
mod tests;

use std::collections::{BTreeMap, VecDeque};
use std::io::BufReader;
use std::path::{Path, PathBuf};

use slam_geom::Pose2;

use crate::error::{LineError, Malformation, ReadError};
use crate::lines::StopFlag;
use crate::record::{LogRecord, OdometryRecord, ScanRecord};
use crate::reorder::{Entry, ReorderConfig, ReorderCounts, ReorderWindow};
pub use cdr::CdrError;
pub use messages::{LASER_SCAN, ODOMETRY, TF_MESSAGE, rep117_range};
pub use metadata::{METADATA_FILE, METADATA_INPUT, Metadata, MetadataError, Storage, Topic};
use mount::StaticTransforms;
pub use mount::{MAX_TILT_DEG, Mount, MountError};
use pairing::Pairing;
use storage::{Channel, Damaged, MessageSource, RawMessage};

/// A storage file of a bag: read as a stream, so its size bounds nothing but what no bag
/// is (a sparse file of tebibytes).
pub const BAG_FILE_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "bag file",
    limit_name: "lidar_replay::rosbag::BAG_FILE_INPUT",
    max_bytes: 1 << 40,
};

/// The first scan must come within this many messages; a bag without one is refused then
/// rather than read to its end.
pub const SNIFF_MESSAGES: u64 = 100_000;

/// Static transforms recorded up to this long (bag time) after the first scan still
/// place the laser.
pub const STATIC_LOOKAHEAD_NS: u64 = 2_000_000_000;

/// The topic of static transforms, and of the others.
pub const TF_STATIC_TOPIC: &str = "/tf_static";
pub const TF_TOPIC: &str = "/tf";

/// A scan waits for the odometry after its stamp behind at most this many others; beyond
/// it (odometry that stopped) the oldest goes out with the pose the readings held give.
const MAX_SCANS_WAITING: usize = 256;

/// Where a bag's odometry comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OdometryFrom {
    /// The Odometry topic if the bag has one, else `/tf`, else none.
    #[default]
    Auto,
    /// `nav_msgs/msg/Odometry` messages of the base frame.
    Odom,
    /// `/tf` transforms from the odom frame to the base frame.
    Tf,
}

impl std::str::FromStr for OdometryFrom {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(Self::Auto),
            "odom" => Ok(Self::Odom),
            "tf" => Ok(Self::Tf),
            other => Err(format!(
                "unknown odometry source '{other}' (auto, odom or tf)"
            )),
        }
    }
}

/// What to replay of a bag.
#[derive(Debug, Clone, PartialEq)]
pub struct BagOptions {
    /// The LaserScan topic; `None`: the bag's only one.
    pub scan_topic: Option<String>,
    pub odometry: OdometryFrom,
    /// The Odometry topic; `None`: the bag's only one.
    pub odometry_topic: Option<String>,
    /// The robot's frame (REP 105): the odometry's child frame, the mount's parent.
    pub base_frame: String,
    /// The odometry's frame, for odometry from `/tf`.
    pub odom_frame: String,
    pub reorder: ReorderConfig,
}

impl Default for BagOptions {
    fn default() -> Self {
        Self {
            scan_topic: None,
            odometry: OdometryFrom::Auto,
            odometry_topic: None,
            base_frame: "base_link".into(),
            odom_frame: "odom".into(),
            reorder: ReorderConfig::default(),
        }
    }
}

/// Why a bag cannot be replayed at all. Each names the bag (or its file) and what is
/// wrong; the underlying error is part of the message.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("{path} is a directory without {METADATA_FILE}: not a rosbag2 bag")]
    NoMetadata { path: PathBuf },
    #[error(transparent)]
    Metadata(#[from] MetadataError),
    /// A file the metadata names is not there.
    #[error("{metadata} names {file}, which is missing")]
    MissingFile { metadata: PathBuf, file: PathBuf },
    /// A bag file that cannot be opened, is not a regular file, or is too large.
    #[error("{bag}")]
    File {
        bag: PathBuf,
        #[source]
        cause: stage_kit::InputError,
    },
    #[error("{path} is not a bag file (.mcap or .db3, or a bag directory)")]
    NotABag { path: PathBuf },
    #[error("{0}")]
    Sqlite(#[from] sqlite_storage::SqliteError),
    #[error("{path}: {reason}")]
    Topics { path: PathBuf, reason: String },
    #[error("{path} is damaged before its first scan (after {messages} messages): {cause}")]
    Damaged {
        path: PathBuf,
        messages: u64,
        cause: String,
    },
    #[error("{path}: no scan on {topic} it can replay {within}{problem}")]
    NoScan {
        path: PathBuf,
        topic: String,
        within: String,
        problem: String,
    },
    #[error("{path}: {cause}")]
    Mount { path: PathBuf, cause: MountError },
    #[error("stopped while checking {path}")]
    Stopped { path: PathBuf },
}

/// Where the odometry of a replay comes from, once chosen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OdometryStream {
    /// An Odometry topic.
    Topic(String),
    /// `/tf`, odom frame to base frame.
    Tf,
}

/// What the survey of a bag found and chose.
#[derive(Debug, Clone, PartialEq)]
pub struct BagInfo {
    pub path: PathBuf,
    pub storage: Storage,
    pub files: Vec<PathBuf>,
    /// The topics the bag declares (its metadata, its MCAP summary or its database; else
    /// those seen in the survey).
    pub topics: Vec<Topic>,
    pub scan_topic: String,
    /// The first scan's frame.
    pub scan_frame: String,
    pub odometry: Option<OdometryStream>,
    pub mount: Mount,
    pub base_frame: String,
    pub odom_frame: String,
}

impl BagInfo {
    pub fn has_odometry(&self) -> bool {
        self.odometry.is_some()
    }

    /// What the replay will publish, for the console.
    pub fn describe(&self) -> Vec<String> {
        let files = match self.files.len() {
            1 => "1 file".to_owned(),
            n => format!("{n} files"),
        };
        let odometry = match &self.odometry {
            Some(OdometryStream::Topic(topic)) => {
                format!("odometry from {topic} ({} in its frame)", self.base_frame)
            }
            Some(OdometryStream::Tf) => format!(
                "odometry from {TF_TOPIC} ({} to {})",
                self.odom_frame, self.base_frame
            ),
            None => "no odometry in the bag".to_owned(),
        };
        let mut lines = vec![format!(
            "rosbag2 ({}, {files}): scans from {} (frame {}), {odometry}",
            self.storage.name(),
            self.scan_topic,
            self.scan_frame
        )];
        lines.push(match &self.mount {
            Mount::AtBase => format!("the scans are in {} itself", self.base_frame),
            Mount::Found {
                robot_from_sensor: m,
                ..
            } => format!(
                "laser mount from {TF_STATIC_TOPIC}: {} -> {} at x {:.3} m, y {:.3} m, yaw \
                 {:.1} deg; trajectories are {}'s",
                self.base_frame,
                self.scan_frame,
                m.x,
                m.y,
                m.yaw.to_degrees(),
                self.base_frame
            ),
            Mount::Missing => format!(
                "no {TF_STATIC_TOPIC} transform from {} to {}: the laser is taken to sit at \
                 {}'s origin",
                self.base_frame, self.scan_frame, self.base_frame
            ),
        });
        lines
    }
}

/// `/scan (sensor_msgs/msg/LaserScan), /odom (nav_msgs/msg/Odometry)`.
fn list_topics(topics: &[Topic]) -> String {
    if topics.is_empty() {
        return "none".into();
    }
    topics
        .iter()
        .map(|topic| format!("{} ({})", topic.name, topic.type_name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Where a bag's messages are.
struct Located {
    storage: Storage,
    files: Vec<PathBuf>,
    /// The topics the bag declares; `None` when only reading it tells (an MCAP file
    /// without a summary).
    topics: Option<Vec<Topic>>,
}

/// The storage and files of the bag at `path`, and the topics it declares.
fn locate(path: &Path) -> Result<Located, BagError> {
    let file_error = |cause| BagError::File {
        bag: path.to_path_buf(),
        cause,
    };
    if path.is_dir() {
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
            BAG_FILE_INPUT
                .open(file, stage_kit::input::Links::Follow)
                .map_err(file_error)?;
        }
        return Ok(Located {
            storage: metadata.storage,
            files: metadata.files,
            topics: Some(metadata.topics),
        });
    }
    let storage = Storage::of_file(path).ok_or_else(|| BagError::NotABag {
        path: path.to_path_buf(),
    })?;
    let file = BAG_FILE_INPUT
        .open(path, stage_kit::input::Links::Follow)
        .map_err(file_error)?;
    let channels = match storage {
        Storage::Mcap => mcap_storage::summary_channels(BufReader::new(file)),
        Storage::Sqlite3 => Some(sqlite_storage::SqliteSource::open(path)?.channels()),
    };
    Ok(Located {
        storage,
        files: vec![path.to_path_buf()],
        topics: channels.map(|channels| topics_of(&channels)),
    })
}

/// One topic per name, in the order first declared.
fn topics_of(channels: &[Channel]) -> Vec<Topic> {
    let mut topics: Vec<Topic> = Vec::new();
    for channel in channels {
        if !topics.iter().any(|topic| topic.name == channel.topic) {
            topics.push(Topic {
                name: channel.topic.clone(),
                type_name: channel.type_name.clone(),
                messages: None,
            });
        }
    }
    topics
}

/// The topic of `type_name` named `given`, or the only one of that type. `Err` says why
/// none can be chosen, listing the bag's topics.
fn choose_topic(
    topics: &[Topic],
    type_name: &str,
    given: Option<&str>,
    option: &str,
) -> Result<Option<String>, String> {
    if let Some(name) = given {
        return match topics.iter().find(|topic| topic.name == name) {
            Some(topic) if topic.type_name == type_name => Ok(Some(name.to_owned())),
            Some(topic) => Err(format!(
                "{name} ({option}) is {}, not {type_name}; the bag's topics: {}",
                topic.type_name,
                list_topics(topics)
            )),
            None => Err(format!(
                "the bag has no topic {name} ({option}); its topics: {}",
                list_topics(topics)
            )),
        };
    }
    let of_type: Vec<&Topic> = topics
        .iter()
        .filter(|topic| topic.type_name == type_name)
        .collect();
    match of_type[..] {
        [] => Ok(None),
        [only] => Ok(Some(only.name.clone())),
        _ => Err(format!(
            "the bag has {} {type_name} topics ({}): choose one with {option}",
            of_type.len(),
            of_type
                .iter()
                .map(|topic| topic.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// The scan and odometry topics of a bag with `topics`.
fn choose(
    topics: &[Topic],
    options: &BagOptions,
) -> Result<(String, Option<OdometryStream>), String> {
    let scan_topic = choose_topic(
        topics,
        LASER_SCAN,
        options.scan_topic.as_deref(),
        "--scan-topic",
    )?
    .ok_or_else(|| {
        format!(
            "the bag has no {LASER_SCAN} topic to replay; its topics: {}",
            list_topics(topics)
        )
    })?;
    let has_tf = topics
        .iter()
        .any(|topic| topic.name == TF_TOPIC && topic.type_name == TF_MESSAGE);
    let odometry_topic = || {
        choose_topic(
            topics,
            ODOMETRY,
            options.odometry_topic.as_deref(),
            "--odom-topic",
        )
    };
    let odometry = match options.odometry {
        OdometryFrom::Odom => Some(OdometryStream::Topic(odometry_topic()?.ok_or_else(
            || {
                format!(
                    "--odom-source odom: the bag has no {ODOMETRY} topic; its topics: {}",
                    list_topics(topics)
                )
            },
        )?)),
        OdometryFrom::Tf if has_tf => Some(OdometryStream::Tf),
        OdometryFrom::Tf => {
            return Err(format!(
                "--odom-source tf: the bag has no {TF_TOPIC} topic of {TF_MESSAGE}; its \
                 topics: {}",
                list_topics(topics)
            ));
        }
        OdometryFrom::Auto => match odometry_topic()? {
            Some(topic) => Some(OdometryStream::Topic(topic)),
            None if has_tf => Some(OdometryStream::Tf),
            None => None,
        },
    };
    Ok((scan_topic, odometry))
}

/// The messages of a bag's files, one file after the other.
struct Messages {
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
    fn new(storage: Storage, files: Vec<PathBuf>) -> Self {
        Self {
            storage,
            files,
            next_file: 0,
            current: None,
            read: 0,
            ended: false,
        }
    }

    fn open(&self, path: &Path) -> Result<Box<dyn MessageSource>, Damaged> {
        let file = BAG_FILE_INPUT
            .open(path, stage_kit::input::Links::Follow)
            .map_err(|e| Damaged(format!("{e:#}")))?;
        Ok(match self.storage {
            Storage::Mcap => Box::new(mcap_storage::McapSource::new(BufReader::new(file))),
            Storage::Sqlite3 => Box::new(
                sqlite_storage::SqliteSource::open(path).map_err(|e| Damaged(e.to_string()))?,
            ),
        })
    }

    fn next(&mut self) -> Option<Result<RawMessage, Damaged>> {
        while !self.ended {
            let Some(current) = &mut self.current else {
                let Some(path) = self.files.get(self.next_file) else {
                    self.ended = true;
                    return None;
                };
                self.next_file += 1;
                match self.open(&path.clone()) {
                    Ok(source) => self.current = Some(source),
                    Err(e) => {
                        self.ended = true;
                        return Some(Err(e));
                    }
                }
                continue;
            };
            match current.next_message() {
                Some(Ok(message)) => {
                    self.read += 1;
                    return Some(Ok(message));
                }
                Some(Err(e)) => {
                    // A damaged file: the files after it are not read either.
                    self.ended = true;
                    let file = self.files[self.next_file - 1].display();
                    return Some(Err(Damaged(format!("{file}: {}", e.0))));
                }
                None => self.current = None,
            }
        }
        None
    }
}

/// How messages of each topic are used.
#[derive(Debug, Clone)]
struct Plan {
    scan_topic: String,
    odometry: Option<OdometryStream>,
    base_frame: String,
    odom_frame: String,
    mount: Pose2,
}

/// What one message is to the replay.
enum Decoded {
    Scan(messages::LaserScan),
    Odometry(OdometryRecord),
    /// Odometry transforms of a `/tf` message (none when it has none of the base frame).
    Tf(Vec<OdometryRecord>),
    /// A message of a topic the replay does not publish.
    PassedOver,
}

impl Plan {
    /// Decodes `message`, the `index`-th of the bag. `Err` for a message the replay would
    /// use but cannot: of another type or encoding, or not decodable.
    fn decode(&self, index: u64, message: &RawMessage) -> Result<Decoded, LineError> {
        let topic = message.channel.topic.as_str();
        let expected = if topic == self.scan_topic {
            LASER_SCAN
        } else if matches!(&self.odometry, Some(OdometryStream::Topic(t)) if t == topic) {
            ODOMETRY
        } else if topic == TF_TOPIC && self.odometry == Some(OdometryStream::Tf) {
            TF_MESSAGE
        } else {
            return Ok(Decoded::PassedOver);
        };
        let channel = &message.channel;
        let error = |kind, reason: String| LineError::new(index, kind, reason).in_record(topic);
        if (!channel.type_name.is_empty() && channel.type_name != expected)
            || channel.encoding != "cdr"
        {
            return Err(error(
                Malformation::WrongType,
                format!(
                    "message {index} on {topic} is {} in '{}', not {expected} in cdr",
                    if channel.type_name.is_empty() {
                        "of no named type"
                    } else {
                        &channel.type_name
                    },
                    channel.encoding
                ),
            ));
        }
        let undecodable = |e: CdrError| {
            error(
                Malformation::Undecodable,
                format!("message {index} on {topic} is no {expected}: {e}"),
            )
        };
        match expected {
            LASER_SCAN => {
                let mut scan = messages::LaserScan::decode(&message.data).map_err(undecodable)?;
                // A driver that never set its stamps: the recorder's time is the nearest.
                if scan.header.stamp_ns == 0 {
                    scan.header.stamp_ns = message.log_time_ns;
                }
                Ok(Decoded::Scan(scan))
            }
            ODOMETRY => {
                let odometry = messages::Odometry::decode(&message.data).map_err(undecodable)?;
                if odometry.child_frame_id != self.base_frame {
                    return Err(error(
                        Malformation::OtherFrame,
                        format!(
                            "message {index} on {topic} is the odometry of {}, not of {} \
                             (--base-frame)",
                            odometry.child_frame_id, self.base_frame
                        ),
                    ));
                }
                let stamp_ns = match odometry.header.stamp_ns {
                    0 => message.log_time_ns,
                    stamp => stamp,
                };
                Ok(Decoded::Odometry(OdometryRecord {
                    line: index,
                    stamp_ns,
                    x: odometry.pose.x,
                    y: odometry.pose.y,
                    yaw: odometry.pose.yaw,
                    linear_velocity: odometry.linear_velocity,
                    angular_velocity: odometry.angular_velocity,
                    log_covariance: odometry.covariance,
                }))
            }
            _ => {
                let tf = messages::TfMessage::decode(&message.data).map_err(undecodable)?;
                let mut poses = Vec::new();
                for transform in &tf.transforms {
                    if transform.header.frame_id != self.odom_frame
                        || transform.child_frame_id != self.base_frame
                    {
                        continue;
                    }
                    let pose = transform.planar().map_err(undecodable)?;
                    poses.push(OdometryRecord {
                        line: index,
                        stamp_ns: transform.header.stamp_ns,
                        x: pose.x,
                        y: pose.y,
                        yaw: pose.yaw,
                        linear_velocity: 0.0,
                        angular_velocity: 0.0,
                        log_covariance: [0.0; 9],
                    });
                }
                Ok(Decoded::Tf(poses))
            }
        }
    }
}

/// The scans and odometry of a bag, in publishing order: a [`crate::LogReader`] of
/// [`crate::LogFormat::Rosbag`].
#[derive(Debug)]
pub struct BagReader {
    messages: Messages,
    plan: Plan,
    window: ReorderWindow,
    /// Pairs each scan with its odometry; `None` without odometry.
    pairing: Option<Pairing>,
    ready: VecDeque<LogRecord>,
    /// Messages of topics not replayed, by topic.
    passed_over: BTreeMap<String, u64>,
    last_scan: Option<u64>,
    stop: StopFlag,
    ended: bool,
    pairing_ended: bool,
    stopped: bool,
}

impl BagReader {
    fn new(info: &BagInfo, reorder: ReorderConfig, stop: StopFlag) -> Self {
        let plan = Plan {
            scan_topic: info.scan_topic.clone(),
            odometry: info.odometry.clone(),
            base_frame: info.base_frame.clone(),
            odom_frame: info.odom_frame.clone(),
            mount: info.mount.pose(),
        };
        Self {
            messages: Messages::new(info.storage, info.files.clone()),
            pairing: plan.odometry.is_some().then(Pairing::default),
            plan,
            window: ReorderWindow::new(reorder),
            ready: VecDeque::new(),
            passed_over: BTreeMap::new(),
            last_scan: None,
            stop,
            ended: false,
            pairing_ended: false,
            stopped: false,
        }
    }

    /// Messages read so far, of every topic.
    pub fn messages_read(&self) -> u64 {
        self.messages.read
    }

    /// Topics read but not replayed, with their message counts.
    pub fn passed_over(&self) -> &BTreeMap<String, u64> {
        &self.passed_over
    }

    /// The reordering window and what it did so far.
    pub fn reordering(&self) -> (ReorderConfig, ReorderCounts) {
        (self.window.config(), *self.window.counts())
    }

    /// Odometry readings refused as not later than the one before (stamped alike).
    pub fn odometry_refused(&self) -> u64 {
        self.pairing.as_ref().map_or(0, |pairing| pairing.refused)
    }

    /// Sets the time since the previous scan where the message gave none.
    fn out(&mut self, record: LogRecord) -> LogRecord {
        match record {
            LogRecord::Scan(mut scan) => {
                if scan.geometry.scan_time == 0.0
                    && let Some(previous) = self.last_scan
                {
                    scan.geometry.scan_time = scan.stamp_ns.saturating_sub(previous) as f64 * 1e-9;
                }
                self.last_scan = Some(scan.stamp_ns);
                LogRecord::Scan(scan)
            }
            odometry => odometry,
        }
    }

    /// Takes what the window let out: to the pairing, or straight out.
    fn released(&mut self, entry: Entry) {
        let records = match entry {
            Entry::Odometry(odometry) => vec![LogRecord::Odometry(odometry)],
            Entry::Scan(scan) => vec![LogRecord::Scan(scan)],
            Entry::OdometryAndScan(odometry, scan) => {
                vec![LogRecord::Odometry(odometry), LogRecord::Scan(scan)]
            }
        };
        for record in records {
            match (&mut self.pairing, record) {
                (Some(pairing), LogRecord::Odometry(odometry)) => pairing.odometry(odometry),
                (Some(pairing), LogRecord::Scan(scan)) => {
                    pairing.scan(scan);
                    pairing.limit_waiting(MAX_SCANS_WAITING);
                }
                (None, record) => self.ready.push_back(record),
            }
        }
    }

    /// Puts a message's records into the window.
    fn take(&mut self, index: u64, message: &RawMessage) -> Result<(), LineError> {
        match self.plan.decode(index, message)? {
            Decoded::Scan(scan) => self.window.push(Entry::Scan(ScanRecord {
                line: index,
                stamp_ns: scan.header.stamp_ns,
                log_stamp_ns: scan.header.stamp_ns,
                geometry: scan.geometry,
                ranges: scan.ranges,
                intensities: scan.intensities,
                robot_from_sensor: self.plan.mount,
            })),
            Decoded::Odometry(odometry) => self.window.push(Entry::Odometry(odometry)),
            Decoded::Tf(poses) => {
                for pose in poses {
                    self.window.push(Entry::Odometry(pose));
                }
            }
            Decoded::PassedOver => {
                *self
                    .passed_over
                    .entry(message.channel.topic.clone())
                    .or_default() += 1;
            }
        }
        Ok(())
    }
}

impl Iterator for BagReader {
    type Item = Result<LogRecord, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.stopped {
            return None;
        }
        loop {
            if let Some(record) = self.ready.pop_front() {
                return Some(Ok(self.out(record)));
            }
            if let Some(record) = self.pairing.as_mut().and_then(Pairing::next) {
                return Some(Ok(self.out(record)));
            }
            let released = if self.ended {
                self.window.pop_any()
            } else {
                self.window.pop_ready()
            };
            if let Some(entry) = released {
                self.released(entry);
                continue;
            }
            if self.ended {
                if let Some(pairing) = &mut self.pairing
                    && !self.pairing_ended
                {
                    self.pairing_ended = true;
                    pairing.end();
                    continue;
                }
                return None;
            }
            if (self.stop)() {
                self.stopped = true;
                return Some(Err(ReadError::Stopped));
            }
            match self.messages.next() {
                None => self.ended = true,
                Some(Err(Damaged(cause))) => {
                    // What the window holds still comes out after the error.
                    self.ended = true;
                    return Some(Err(ReadError::Cut {
                        messages: self.messages.read,
                        cause,
                    }));
                }
                Some(Ok(message)) => {
                    let index = self.messages.read;
                    if let Err(e) = self.take(index, &message) {
                        return Some(Err(e.into()));
                    }
                }
            }
        }
    }
}

/// Surveys the bag at `path` (see the module's documentation) and opens it for replay.
pub fn open_bag_until(
    path: &Path,
    options: &BagOptions,
    stop: StopFlag,
) -> Result<(BagReader, BagInfo), BagError> {
    let info = survey(path, options, stop)?;
    Ok((BagReader::new(&info, options.reorder, stop), info))
}

/// [`open_bag_until`] without a stop: the survey alone, as slam-launch checks a bag before
/// it starts anything.
pub fn check_bag(path: &Path, options: &BagOptions) -> Result<BagInfo, BagError> {
    survey(path, options, crate::lines::never)
}

fn survey(path: &Path, options: &BagOptions, stop: StopFlag) -> Result<BagInfo, BagError> {
    let Located {
        storage,
        files,
        topics: declared,
    } = locate(path)?;
    let topics_error = |reason| BagError::Topics {
        path: path.to_path_buf(),
        reason,
    };
    // With the topics known, choose now; else from the channels the survey meets.
    let mut chosen = match &declared {
        Some(topics) => Some(choose(topics, options).map_err(topics_error)?),
        None => None,
    };
    let mut seen: Vec<Channel> = Vec::new();
    let mut statics = StaticTransforms::default();
    let mut first_scan: Option<(messages::LaserScan, u64)> = None;
    let mut first_problem: Option<String> = None;
    let mut messages = Messages::new(storage, files.clone());
    while let Some(next) = messages.next() {
        if stop() {
            return Err(BagError::Stopped {
                path: path.to_path_buf(),
            });
        }
        let message = match next {
            Ok(message) => message,
            Err(Damaged(cause)) if first_scan.is_none() => {
                return Err(BagError::Damaged {
                    path: path.to_path_buf(),
                    messages: messages.read,
                    cause,
                });
            }
            // Cut later on: the replay reads up to there and reports it.
            Err(_) => break,
        };
        let channel = &message.channel;
        if declared.is_none() && !seen.iter().any(|c| c.topic == channel.topic) {
            seen.push((**channel).clone());
            if first_scan.is_none() {
                chosen = choose(&topics_of(&seen), options).ok();
            }
        }
        if channel.topic == TF_STATIC_TOPIC {
            match messages::TfMessage::decode(&message.data) {
                Ok(tf) => tf.transforms.into_iter().for_each(|t| statics.add(t)),
                Err(e) => {
                    first_problem.get_or_insert(format!("{TF_STATIC_TOPIC}: {e}"));
                }
            }
        }
        match &first_scan {
            None => {
                if let Some((scan_topic, _)) = &chosen
                    && channel.topic == *scan_topic
                {
                    let plan = Plan {
                        scan_topic: scan_topic.clone(),
                        odometry: None,
                        base_frame: options.base_frame.clone(),
                        odom_frame: options.odom_frame.clone(),
                        mount: Pose2::IDENTITY,
                    };
                    match plan.decode(messages.read, &message) {
                        Ok(Decoded::Scan(scan)) => {
                            first_scan = Some((scan, message.log_time_ns));
                        }
                        Ok(_) => {}
                        Err(e) => {
                            first_problem.get_or_insert(e.to_string());
                        }
                    }
                }
                if first_scan.is_none() && messages.read >= SNIFF_MESSAGES {
                    break;
                }
            }
            Some((_, at)) => {
                if message.log_time_ns > at.saturating_add(STATIC_LOOKAHEAD_NS) {
                    break;
                }
            }
        }
    }
    let undeclared = declared.is_none();
    let topics = declared.unwrap_or_else(|| topics_of(&seen));
    // Topics only the survey saw: refuse now, naming them, if none could be chosen.
    let (scan_topic, mut odometry) = match chosen {
        Some(chosen) => chosen,
        None => choose(&topics, options).map_err(topics_error)?,
    };
    // ... and the odometry from every channel it met, some after the first scan.
    if undeclared && let Ok((_, later)) = choose(&topics, options) {
        odometry = later;
    }
    let Some((scan, _)) = first_scan else {
        let within = if messages.read >= SNIFF_MESSAGES {
            format!("in its first {SNIFF_MESSAGES} messages")
        } else {
            format!("in its {} messages", messages.read)
        };
        return Err(BagError::NoScan {
            path: path.to_path_buf(),
            topic: scan_topic,
            within,
            problem: first_problem
                .map(|p| format!(" (first problem: {p})"))
                .unwrap_or_default(),
        });
    };
    let scan_frame = scan.header.frame_id;
    let mount = statics
        .mount(&options.base_frame, &scan_frame)
        .map_err(|cause| BagError::Mount {
            path: path.to_path_buf(),
            cause,
        })?;
    Ok(BagInfo {
        path: path.to_path_buf(),
        storage,
        files,
        topics,
        scan_topic,
        scan_frame,
        odometry,
        mount,
        base_frame: options.base_frame.clone(),
        odom_frame: options.odom_frame.clone(),
    })
}

/// Whether the MCAP file at `path` holds ROS 2 messages (a channel in `cdr`, or a schema
/// of ROS 2 message definitions) rather than a run of slam-record; `None` when it cannot
/// be read far enough to tell.
pub fn is_ros2_mcap(path: &Path) -> Option<bool> {
    let open = || {
        BAG_FILE_INPUT
            .open(path, stage_kit::input::Links::Follow)
            .ok()
    };
    let is_ros2 = |channel: &Channel| channel.encoding == "cdr";
    if let Some(channels) = mcap_storage::summary_channels(BufReader::new(open()?))
        && !channels.is_empty()
    {
        return Some(channels.iter().any(is_ros2));
    }
    // No summary (a file cut short): its first message tells.
    let mut source = mcap_storage::McapSource::new(BufReader::new(open()?));
    let message = source.next_message()?.ok()?;
    Some(is_ros2(&message.channel))
}
