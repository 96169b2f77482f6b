//! What the front end is given per scan: the beams as the `LaserScan` message has them, and
//! optionally the odometry pose at the scan's stamp.

use nalgebra::Matrix3;
use slam_geom::Pose2;

use crate::error::InputError;

/// Where the beams of a scan point and which ranges are valid (docs/CONVENTIONS.md: beam `i`
/// has bearing `angle_min + i * angle_increment` in the robot frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamGeometry {
    pub angle_min: f64,
    pub angle_increment: f64,
    pub range_min: f64,
    pub range_max: f64,
}

impl BeamGeometry {
    /// `Err` when no range could ever be valid or the bearings are not defined.
    pub fn check(&self) -> Result<(), InputError> {
        if !self.angle_min.is_finite() {
            return Err(InputError::Geometry("angle_min is not finite"));
        }
        if !self.angle_increment.is_finite() || self.angle_increment == 0.0 {
            return Err(InputError::Geometry(
                "angle_increment is zero or not finite",
            ));
        }
        if self.range_min.is_nan() || self.range_max.is_nan() || self.range_max <= self.range_min {
            return Err(InputError::Geometry("range_max is not above range_min"));
        }
        Ok(())
    }
}

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
    pub geometry: BeamGeometry,
    pub ranges: &'a [f32],
    pub odometry: Option<OdometryInput>,
}
