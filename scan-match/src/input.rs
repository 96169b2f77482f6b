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

impl OdometryInput {
    /// The odometry of the sensor mounted at `robot_from_sensor`, from the robot's: the
    /// front end tracks the sensor whose scans it registers, and a turn of the robot swings
    /// a mount off its origin.
    pub fn of_sensor(
        odom_from_robot: Pose2,
        covariance: Matrix3<f64>,
        robot_from_sensor: &Pose2,
    ) -> Self {
        let jacobian = odom_from_robot.mount_jacobian(robot_from_sensor);
        Self {
            odom_from_robot: odom_from_robot.compose(robot_from_sensor),
            covariance: jacobian * covariance * jacobian.transpose(),
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_turning_in_place_swings_its_sensor_round() {
        let mount = Pose2::new(0.25, 0.0, 0.0);
        let covariance = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-4, 1e-4, 1e-2));
        let start = OdometryInput::of_sensor(Pose2::IDENTITY, covariance, &mount);
        let turned = OdometryInput::of_sensor(Pose2::new(0.0, 0.0, 1.0), covariance, &mount);
        assert_eq!(start.odom_from_robot, mount);
        let step = start.odom_from_robot.between(&turned.odom_from_robot);
        // The sensor moved along a chord of the 0.25 m circle and turned with the robot.
        assert!((step.translation_norm() - 2.0 * 0.25 * 0.5_f64.sin()).abs() < 1e-12);
        assert!((step.yaw - 1.0).abs() < 1e-12);
        // The yaw's uncertainty reaches the sensor's position, sideways to the mount.
        assert!((start.covariance[(1, 1)] - (1e-4 + 0.25 * 0.25 * 1e-2)).abs() < 1e-15);
        assert!((start.covariance[(0, 0)] - 1e-4).abs() < 1e-15);
        assert!(start.covariance.cholesky().is_some());
    }
}
