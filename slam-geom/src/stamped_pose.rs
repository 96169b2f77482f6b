//! A pose with the stamp of the scan it belongs to: one entry of a trajectory.

use crate::Pose2;

/// The pose at a scan's stamp (nanoseconds, the scan's own clock), as a trajectory, the
/// filter's final path and a TUM file hold them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    pub stamp_ns: u64,
    pub pose: Pose2,
}
