//! What the front end is given per scan: the beams as the `LaserScan` message has them, and
//! optionally the odometry pose at the scan's stamp.

use nalgebra::Matrix3;
use slam_geom::{Pose2, ScanGeometry};

/// The odometry at a scan's stamp: `odom_from_robot` in the odometry's own drifting frame,
/// with the covariance of that integrated pose (row-major over x, y, yaw). Only the
/// difference between two readings means anything, the growth of covariance included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryInput {
    pub odom_from_robot: Pose2,
    pub covariance: Matrix3<f64>,
}

/// One scan: its acquisition stamp, geometry, ranges (REP 117: non-finite or outside
/// `[range_min, range_max]` is invalid) and, when there is odometry, the odometry at its stamp.
#[derive(Debug, Clone, Copy)]
pub struct ScanInput<'a> {
    pub stamp_ns: u64,
    pub geometry: ScanGeometry,
    pub ranges: &'a [f32],
    pub odometry: Option<OdometryInput>,
}
