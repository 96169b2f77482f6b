//! Wheel or visual-inertial odometry.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::pose::Pose2;
use crate::header::Header;

/// A stamped odometry pose in the odometry frame (`odom_from_robot`) with its covariance.
///
/// Only increments between two messages are meaningful; the odometry frame drifts.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::Odometry::v1")]
pub struct Odometry {
    pub header: Header,
    pub pose: Pose2,
    /// Row-major 3x3 covariance of (x, y, yaw).
    pub covariance: [f64; 9],
    /// Forward speed, m/s (0 when unknown).
    pub linear_velocity: f64,
    /// Yaw rate, rad/s (0 when unknown).
    pub angular_velocity: f64,
}
