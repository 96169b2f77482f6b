//! What the filter is given each scan: corner and line features in the sensor frame and
//! either the motion a front end measured or, when the robot has it, an odometry pose.

use std::f64::consts::PI;

use nalgebra::{Cholesky, Matrix3, Matrix4, Vector4};

use slam_geom::{MeasuredCorner, Pose2};

/// An odometry reading: `odom_from_robot` in the odometry's own (drifting) frame, with the
/// covariance of `(x, y, yaw)`. Only increments between consecutive readings are used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryInput {
    pub pose: Pose2,
    pub covariance: Matrix3<f64>,
}

/// The motion since the previous scan as a front end measured it (the scan registered
/// against its recent predecessors, fused with odometry): the increment in the previous
/// robot frame and its covariance over `(x, y, yaw)`, symmetric positive definite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredMotion {
    pub increment: Pose2,
    pub covariance: Matrix3<f64>,
    /// The wheels' step the front end weighed against the scan, when it had one it
    /// believed or was overruled on (not a stale or implausible one).
    pub wheel_increment: Option<Pose2>,
}

impl MeasuredMotion {
    /// No motion, known exactly: the step of a first scan, or of a source without a front
    /// end.
    pub fn standing_still() -> Self {
        Self {
            increment: Pose2::IDENTITY,
            covariance: Matrix3::zeros(),
            wheel_increment: None,
        }
    }

    /// Whether the filter can use it: finite, with a covariance that has no negative
    /// variance.
    pub(crate) fn is_usable(&self) -> bool {
        let p = &self.increment;
        [p.x, p.y, p.yaw]
            .iter()
            .chain(self.covariance.iter())
            .all(|v| v.is_finite())
            && (0..3).all(|i| self.covariance[(i, i)] >= 0.0)
    }
}

impl From<&ipc_types::ScanMotion> for MeasuredMotion {
    /// The steps a features message carries; its pose in the front end's frame, statuses
    /// and counts are not the filter's business.
    fn from(motion: &ipc_types::ScanMotion) -> Self {
        Self {
            increment: motion.increment.into(),
            covariance: ipc_types::covariance_from_row_major(&motion.increment_covariance),
            wheel_increment: motion.wheel_increment().map(Into::into),
        }
    }
}

impl From<ipc_types::OdometryAtScan> for OdometryInput {
    fn from(odometry: ipc_types::OdometryAtScan) -> Self {
        Self {
            pose: odometry.pose.into(),
            covariance: ipc_types::covariance_from_row_major(&odometry.covariance),
        }
    }
}

/// An observation checked and made ready for the filter: its vector and a covariance that
/// is symmetric, inflated by the configured floor, and known to be positive definite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Prepared {
    pub z: Vector4<f64>,
    pub covariance: Matrix4<f64>,
}

impl Prepared {
    /// `None` for an observation the filter cannot use (non-finite values, an opening
    /// angle outside `(0, pi)`, a covariance that is not positive definite): one bad
    /// feature must not poison every particle's map.
    pub fn new(
        observation: &MeasuredCorner,
        extra_sigma_xy: f64,
        extra_sigma_angle: f64,
    ) -> Option<Self> {
        let z = Vector4::new(
            observation.x,
            observation.y,
            observation.heading,
            observation.angle,
        );
        let angle_ok = observation.angle > 0.0 && observation.angle < PI;
        if !(angle_ok && z.iter().all(|v| v.is_finite())) {
            return None;
        }
        let c = observation.covariance;
        if !c.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (pos, ang) = (
            extra_sigma_xy * extra_sigma_xy,
            extra_sigma_angle * extra_sigma_angle,
        );
        let covariance =
            (c + c.transpose()) * 0.5 + Matrix4::from_diagonal(&Vector4::new(pos, pos, ang, ang));
        Cholesky::new(covariance)?;
        Some(Self { z, covariance })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn observation() -> MeasuredCorner {
        MeasuredCorner {
            x: 1.0,
            y: 2.0,
            heading: 0.3,
            angle: 1.5,
            covariance: Matrix4::identity() * 1e-4,
        }
    }

    #[test]
    fn the_messages_steps_and_odometry_reach_the_filter_unchanged() {
        let mut motion = <ipc_types::ScanMotion as ipc_types::Zeroable>::boxed_zeroed();
        motion.increment = Pose2::new(0.3, -0.01, 0.02).into();
        motion.increment_covariance = [4e-4, 1e-5, 0.0, 1e-5, 2e-4, 0.0, 0.0, 0.0, 1e-5];
        let measured = MeasuredMotion::from(&*motion);
        assert_eq!(measured.increment, Pose2::new(0.3, -0.01, 0.02));
        assert_eq!(measured.covariance[(1, 0)], 1e-5);
        assert_eq!(measured.covariance[(1, 1)], 2e-4);
        assert_eq!(measured.wheel_increment, None);
        motion.set_wheel_increment(Some(Pose2::new(0.28, 0.0, 0.015).into()));
        let measured = MeasuredMotion::from(&*motion);
        assert_eq!(measured.wheel_increment, Some(Pose2::new(0.28, 0.0, 0.015)));
        let odometry = OdometryInput::from(ipc_types::OdometryAtScan {
            pose: Pose2::new(5.0, 6.0, -1.0).into(),
            covariance: [1.0, 0.0, 0.5, 0.0, 2.0, 0.0, 0.5, 0.0, 3.0],
        });
        assert_eq!(odometry.pose, Pose2::new(5.0, 6.0, -1.0));
        assert_eq!(odometry.covariance[(2, 0)], 0.5);
        assert_eq!(odometry.covariance[(2, 2)], 3.0);
        assert!(MeasuredMotion::standing_still().is_usable());
    }

    #[test]
    fn bad_observations_are_refused() {
        assert!(Prepared::new(&observation(), 0.0, 0.0).is_some());
        let mut bad = observation();
        bad.angle = PI;
        assert!(Prepared::new(&bad, 0.0, 0.0).is_none());
        let mut bad = observation();
        bad.x = f64::NAN;
        assert!(Prepared::new(&bad, 0.0, 0.0).is_none());
        let mut bad = observation();
        bad.covariance[(3, 3)] = -1.0;
        assert!(Prepared::new(&bad, 0.0, 0.0).is_none());
    }

    #[test]
    fn the_floor_is_added_to_the_diagonal() {
        let p = Prepared::new(&observation(), 0.01, 0.02);
        let c = p.map(|p| p.covariance).unwrap_or_else(Matrix4::zeros);
        assert!((c[(0, 0)] - 2e-4).abs() < 1e-15);
        assert!((c[(3, 3)] - 5e-4).abs() < 1e-15);
    }
}
