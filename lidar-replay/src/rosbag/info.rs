//! What the survey of a bag found and chose, and how the console says it.

use std::path::PathBuf;

use super::metadata::{Storage, Topic};
use super::mount::Mount;
use super::topics::{OdometryStream, TF_STATIC_TOPIC, TF_TOPIC};

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
        vec![
            format!(
                "rosbag2 ({}, {files}): scans from {} (frame {}), {}",
                self.storage.name(),
                self.scan_topic,
                self.scan_frame,
                self.describe_odometry()
            ),
            self.describe_mount(),
        ]
    }

    fn describe_odometry(&self) -> String {
        match &self.odometry {
            Some(OdometryStream::Topic(topic)) => {
                format!("odometry from {topic} ({} in its frame)", self.base_frame)
            }
            Some(OdometryStream::Tf) => format!(
                "odometry from {TF_TOPIC} ({} to {})",
                self.odom_frame, self.base_frame
            ),
            None => "no odometry in the bag".to_owned(),
        }
    }

    fn describe_mount(&self) -> String {
        let (base, laser) = (&self.base_frame, &self.scan_frame);
        match &self.mount {
            Mount::AtBase => format!("the scans are in {base} itself"),
            Mount::Found {
                robot_from_sensor: m,
                ..
            } => format!(
                "laser mount from {TF_STATIC_TOPIC}: {base} -> {laser} at x {:.3} m, y {:.3} m, \
                 yaw {:.1} deg; trajectories are {base}'s",
                m.x,
                m.y,
                m.yaw.to_degrees(),
            ),
            Mount::Missing => format!(
                "no {TF_STATIC_TOPIC} transform from {base} to {laser}: the laser is taken to \
                 sit at {base}'s origin"
            ),
        }
    }
}
