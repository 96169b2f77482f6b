//! What the front end reports per scan, and its counters over a run.

use std::time::Duration;

use nalgebra::{Matrix3, Vector3};
use slam_geom::Pose2;

use crate::prior::OdometryRejection;

/// How the scan was registered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MatchStatus {
    /// The first scan: it starts the map, the pose is the identity.
    First,
    /// Registered; every direction constrained by the scan.
    Matched,
    /// Registered, but the scan leaves `count` directions open (1 in a corridor);
    /// `direction` is the weakest, over `(x, y, yaw)` in the robot frame (yaw scaled by the
    /// scan's spread, so a unit vector weighs metres and radians alike). The prior decides
    /// the pose along it.
    Degenerate { direction: Vector3<f64>, count: u8 },
    /// Not registered: the pose is the prior's.
    Failed(MatchFailure),
}

/// Why a scan could not be registered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatchFailure {
    /// Fewer usable points than a scan needs to be matched (30).
    TooFewPoints,
    /// Too few points found the map within the gate (under 40 % of its points).
    TooFewInliers,
    /// The scan constrains no direction at all.
    Unconstrained,
    /// A weak fit (under 60 % of its points as inliers) far from a believable odometry step:
    /// the odometry is taken instead.
    Contradicted,
}

/// What became of the odometry at this scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdometryStatus {
    /// None given with this scan.
    Absent,
    /// The first reading (or the first after absent ones): nothing to take a step from.
    Started,
    /// The step was fused with the scan match (or, if the match failed, taken alone).
    Used,
    /// The step was not believed; the prior was constant velocity.
    Rejected(OdometryRejection),
}

/// The front end's result for one scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontEndOutput {
    pub stamp_ns: u64,
    /// The robot's pose in the front end's own frame (the identity at the first scan);
    /// like any odometry, only its increments are meaningful over long spans.
    pub odom_from_robot: Pose2,
    /// The motion since the previous scan, in the previous robot frame.
    pub increment: Pose2,
    /// Covariance of `increment` over `(x, y, yaw)`, symmetric positive definite.
    pub increment_covariance: Matrix3<f64>,
    pub status: MatchStatus,
    pub odometry: OdometryStatus,
    /// The wheels' step since the previous scan as the front end weighed it against the
    /// scan (scaled by the learnt distance ratio; after stale or frozen readings, from the
    /// last one believed), in the previous robot frame: present when the odometry was used,
    /// or overruled by a clear fit. A second odometer whose errors are not the fit's: where
    /// the two disagree, the motion is uncertain by as much.
    pub wheel_increment: Option<Pose2>,
    /// Valid beams of the scan.
    pub valid_beams: usize,
    /// Points used for matching (valid, on a surface, one per voxel).
    pub points: usize,
    /// Points matched to the map within the final gate.
    pub inliers: usize,
    /// Gauss-Newton iterations of the registration that counted (0 when none ran).
    pub iterations: usize,
    /// Whether the scan became a keyframe of the local map.
    pub keyframe: bool,
    /// Time spent in [`crate::FrontEnd::process`].
    pub elapsed: Duration,
}

/// Counts over a run, for a summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrontEndStats {
    pub scans: u64,
    pub matched: u64,
    pub degenerate: u64,
    pub failed_matches: u64,
    pub odometry_used: u64,
    pub odometry_rejected: OdometryRejections,
    pub keyframes: u64,
    /// Wide searches run (a recovery: after a gap, a fast turn, or scans that did not
    /// register), and those whose fit was taken.
    pub wide_searches: u64,
    pub recovered: u64,
    /// The longest stretch of consecutive scans that did not register.
    pub longest_unregistered: u64,
    /// Total time in `process`, nanoseconds.
    pub busy_ns: u64,
}

/// Odometry steps not believed over a run, by why ([`OdometryRejection`]): a source whose
/// readings come late shows as stale, one that disagrees with the scans as inconsistent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OdometryRejections {
    pub not_finite: u64,
    pub implausible: u64,
    pub inconsistent: u64,
    pub stale: u64,
}

impl OdometryRejections {
    /// Counts one rejection.
    pub fn add(&mut self, rejection: &OdometryRejection) {
        let count = match rejection {
            OdometryRejection::NotFinite => &mut self.not_finite,
            OdometryRejection::Implausible => &mut self.implausible,
            OdometryRejection::Inconsistent { .. } => &mut self.inconsistent,
            OdometryRejection::Stale { .. } => &mut self.stale,
        };
        *count += 1;
    }

    /// Every rejection, whatever the reason.
    pub fn total(&self) -> u64 {
        self.not_finite + self.implausible + self.inconsistent + self.stale
    }
}
