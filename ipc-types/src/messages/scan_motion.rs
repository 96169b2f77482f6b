//! The front end's registration of a scan: how the robot moved since the previous one.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::pose::Pose2;

/// The front end's motion estimate for one scan: the scan registered against a local map of
/// the recent ones and fused with the odometry (docs/CONVENTIONS.md, "Front end").
#[repr(C)]
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, FromZeros, Serialize, Deserialize,
)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::ScanMotion::v2")]
pub struct ScanMotion {
    /// The robot's pose in the front end's own frame (the identity at its first scan).
    pub pose: Pose2,
    /// The motion since the previous scan, in the previous robot frame.
    pub increment: Pose2,
    /// Row-major covariance of `increment` over `(x, y, yaw)`.
    pub increment_covariance: [f64; 9],
    /// The wheels' step since the previous scan as the front end weighed it against the
    /// scan, in the previous robot frame; meaningful when `has_wheel_increment` is 1 (the
    /// odometry used, or overruled by the scan; not when absent, stale or implausible).
    pub wheel_increment: Pose2,
    /// How the scan was registered: one of the `MATCH_*` values.
    pub match_status: u32,
    /// What became of the odometry: one of the `ODOMETRY_*` values.
    pub odometry_status: u32,
    /// Points used for the registration, and those that found the map.
    pub points: u32,
    pub inliers: u32,
    /// 1 when `wheel_increment` holds the wheels' step, 0 otherwise.
    pub has_wheel_increment: u32,
    /// Keeps the layout free of implicit padding; always 0.
    #[serde(skip)]
    pub reserved: u32,
}

impl ScanMotion {
    /// The wheels' step the front end weighed against the scan, if it had one.
    pub fn wheel_increment(&self) -> Option<Pose2> {
        (self.has_wheel_increment == 1).then_some(self.wheel_increment)
    }

    /// Sets (or clears) the wheels' step.
    pub fn set_wheel_increment(&mut self, step: Option<Pose2>) {
        self.wheel_increment = step.unwrap_or_default();
        self.has_wheel_increment = u32::from(step.is_some());
    }

    /// The first scan: it starts the front end's map.
    pub const MATCH_FIRST: u32 = 1;
    /// Registered; the scan fixes every direction.
    pub const MATCH_OK: u32 = 2;
    /// Registered, but a direction is left to the prior (a corridor's length).
    pub const MATCH_DEGENERATE: u32 = 3;
    /// Not registered: the motion is the prior's (odometry or constant velocity).
    pub const MATCH_FAILED: u32 = 4;

    /// No odometry with this scan.
    pub const ODOMETRY_ABSENT: u32 = 0;
    /// The first reading: nothing to take a step from yet.
    pub const ODOMETRY_STARTED: u32 = 1;
    /// The odometry step was used.
    pub const ODOMETRY_USED: u32 = 2;
    /// The odometry step was not believed (not finite, implausible, or contradicted by the
    /// scan).
    pub const ODOMETRY_REJECTED: u32 = 3;
}
