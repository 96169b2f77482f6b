//! A planar pose, the building block of the pose-carrying messages.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

/// A planar pose `world_from_robot`: position in metres, yaw in radians in `[-pi, pi)`.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, FromZeros, Serialize, Deserialize,
)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::Pose2::v1")]
pub struct Pose2 {
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

impl Pose2 {
    pub const fn new(x: f64, y: f64, yaw: f64) -> Self {
        Self { x, y, yaw }
    }
}

impl From<slam_geom::Pose2> for Pose2 {
    fn from(pose: slam_geom::Pose2) -> Self {
        Self::new(pose.x, pose.y, pose.yaw)
    }
}

impl From<Pose2> for slam_geom::Pose2 {
    /// The message's yaw is wrapped by its publisher (docs/CONVENTIONS.md), so it is taken
    /// as it is.
    fn from(pose: Pose2) -> Self {
        Self::new(pose.x, pose.y, pose.yaw)
    }
}
