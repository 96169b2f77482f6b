//! What to replay of a bag: the topics, where the odometry comes from and the frames,
//! as the command line or slam-launch's configuration gives them.

use crate::reorder::ReorderConfig;

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
