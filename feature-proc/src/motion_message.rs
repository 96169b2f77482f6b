//! The front end's result for a scan as the features message carries it downstream.

use ipc_types::{ScanMotion, covariance_to_row_major};
use scan_match::{FrontEndOutput, MatchStatus, OdometryStatus};

/// The motion `output` measured, with how the scan was registered and what became of its
/// odometry, as a [`ScanMotion`]; the reasons behind a failure or a rejection stay in the
/// front end's counts.
pub fn scan_motion(output: &FrontEndOutput) -> ScanMotion {
    let mut motion = ScanMotion {
        pose: output.odom_from_robot.into(),
        increment: output.increment.into(),
        increment_covariance: covariance_to_row_major(&output.increment_covariance),
        match_status: match output.status {
            MatchStatus::First => ScanMotion::MATCH_FIRST,
            MatchStatus::Matched => ScanMotion::MATCH_OK,
            MatchStatus::Degenerate { .. } => ScanMotion::MATCH_DEGENERATE,
            MatchStatus::Failed(_) => ScanMotion::MATCH_FAILED,
        },
        odometry_status: match output.odometry {
            OdometryStatus::Absent => ScanMotion::ODOMETRY_ABSENT,
            OdometryStatus::Started => ScanMotion::ODOMETRY_STARTED,
            OdometryStatus::Used => ScanMotion::ODOMETRY_USED,
            OdometryStatus::Rejected(_) => ScanMotion::ODOMETRY_REJECTED,
        },
        points: u32::try_from(output.points).unwrap_or(u32::MAX),
        inliers: u32::try_from(output.inliers).unwrap_or(u32::MAX),
        ..ScanMotion::default()
    };
    motion.set_wheel_increment(output.wheel_increment.map(Into::into));
    motion
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use nalgebra::{Matrix3, Vector3};
    use scan_match::{MatchFailure, OdometryRejection};
    use slam_geom::Pose2;

    use super::*;

    fn output(status: MatchStatus, odometry: OdometryStatus) -> FrontEndOutput {
        FrontEndOutput {
            stamp_ns: 7,
            odom_from_robot: Pose2::new(3.0, 4.0, 0.5),
            increment: Pose2::new(0.2, 0.0, 0.01),
            increment_covariance: Matrix3::new(1e-4, 2e-6, 0.0, 2e-6, 3e-4, 0.0, 0.0, 0.0, 5e-5),
            status,
            odometry,
            wheel_increment: None,
            valid_beams: 180,
            points: 120,
            inliers: 95,
            iterations: 4,
            keyframe: false,
            elapsed: Duration::ZERO,
        }
    }

    #[test]
    fn the_message_carries_the_step_its_covariance_row_by_row_and_the_counts() {
        let motion = scan_motion(&output(MatchStatus::Matched, OdometryStatus::Used));
        assert_eq!(Pose2::from(motion.pose), Pose2::new(3.0, 4.0, 0.5));
        assert_eq!(Pose2::from(motion.increment), Pose2::new(0.2, 0.0, 0.01));
        assert_eq!(
            motion.increment_covariance,
            [1e-4, 2e-6, 0.0, 2e-6, 3e-4, 0.0, 0.0, 0.0, 5e-5]
        );
        assert_eq!((motion.points, motion.inliers), (120, 95));
        assert_eq!(motion.wheel_increment(), None);
        let mut with_wheels = output(MatchStatus::Matched, OdometryStatus::Used);
        with_wheels.wheel_increment = Some(Pose2::new(0.18, 0.001, 0.012));
        let motion = scan_motion(&with_wheels);
        assert_eq!(
            motion.wheel_increment().map(Pose2::from),
            Some(Pose2::new(0.18, 0.001, 0.012))
        );
    }

    #[test]
    fn every_status_has_its_own_value() {
        let degenerate = MatchStatus::Degenerate {
            direction: Vector3::x(),
            count: 1,
        };
        let matches = [
            (MatchStatus::First, ScanMotion::MATCH_FIRST),
            (MatchStatus::Matched, ScanMotion::MATCH_OK),
            (degenerate, ScanMotion::MATCH_DEGENERATE),
            (
                MatchStatus::Failed(MatchFailure::TooFewPoints),
                ScanMotion::MATCH_FAILED,
            ),
        ];
        for (status, value) in matches {
            let motion = scan_motion(&output(status, OdometryStatus::Absent));
            assert_eq!(motion.match_status, value, "{status:?}");
            assert_eq!(motion.odometry_status, ScanMotion::ODOMETRY_ABSENT);
        }
        let odometry = [
            (OdometryStatus::Started, ScanMotion::ODOMETRY_STARTED),
            (OdometryStatus::Used, ScanMotion::ODOMETRY_USED),
            (
                OdometryStatus::Rejected(OdometryRejection::Implausible),
                ScanMotion::ODOMETRY_REJECTED,
            ),
        ];
        for (status, value) in odometry {
            let motion = scan_motion(&output(MatchStatus::Matched, status));
            assert_eq!(motion.odometry_status, value, "{status:?}");
        }
    }
}
