//! ROS 2 bags (rosbag2) as a log: a bag directory (its `metadata.yaml` and its MCAP or
//! SQLite3 files), or a bare `.mcap` / `.db3` file of ROS 2 messages.
//!
//! * Scans come from `sensor_msgs/msg/LaserScan` on one topic (`--scan-topic`, or the
//!   bag's only LaserScan topic), each with its own geometry, ranges in REP 117 form and
//!   stamped by its `header.stamp`.
//! * Odometry comes from `nav_msgs/msg/Odometry` (of the base frame) or from `/tf` (the odom
//!   frame to the base frame), [`OdometryFrom`]; the pose at each scan's stamp is
//!   interpolated between the readings around it and published right before the scan
//!   (`pairing.rs`), with the message's covariance added to the replay's odometry model.
//! * The laser's mount is the chain of `/tf_static` transforms from the base frame to the
//!   scans' `frame_id` (`mount.rs`), so that a run's trajectories are the base frame's.
//! * Messages go out in stamp order within the reordering window of CARMEN logs; what is
//!   late, repeats a stamp, is of another type or cannot be decoded is counted and
//!   skipped; a bag cut short replays up to the damage and says where it was cut.
//!
//! Before anything is published the bag is surveyed ([`open_bag_until`]): its topics
//! chosen, its first scan read, its static transforms gathered (those recorded before
//! the first scan or within [`STATIC_LOOKAHEAD_NS`] after it, where a recorder puts the
//! latched `/tf_static`); a bag that cannot be replayed is refused then, saying why.

mod cdr;
mod decode;
mod error;
mod info;
mod locate;
mod mcap_storage;
mod messages;
mod metadata;
mod mount;
mod options;
mod pairing;
mod reader;
mod sqlite_storage;
mod storage;
mod stream;
mod survey;
#[cfg(test)]
mod tests;
mod topics;

pub use cdr::CdrError;
pub use error::BagError;
pub use info::BagInfo;
pub use locate::is_ros2_mcap;
pub use messages::{LASER_SCAN, ODOMETRY, TF_MESSAGE, rep117_range};
pub use metadata::{METADATA_FILE, METADATA_INPUT, Metadata, MetadataError, Storage, Topic};
pub use mount::{MAX_TILT_DEG, Mount, MountError};
pub use options::{BagOptions, OdometryFrom};
pub use reader::BagReader;
pub use stream::BAG_FILE_INPUT;
pub use survey::{SNIFF_MESSAGES, STATIC_LOOKAHEAD_NS, check_bag, open_bag_until};
pub use topics::{OdometryStream, TF_STATIC_TOPIC, TF_TOPIC};
