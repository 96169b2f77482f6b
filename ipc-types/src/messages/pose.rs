//! A planar pose, the building block of the pose-carrying messages.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};

/// A planar pose `world_from_robot`: position in metres, yaw in radians in `[-pi, pi)`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, Serialize, Deserialize)]
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
