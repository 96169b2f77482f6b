//! Poses nudged along one coordinate, for checking Jacobians against finite differences.

use slam_geom::Pose2;

/// `pose` with `h` added to its x (`axis` 0), y (1) or yaw (2): the yaw is not re-wrapped,
/// so the nudge is exactly `h`.
pub(crate) fn nudged(pose: &Pose2, axis: usize, h: f64) -> Pose2 {
    let mut nudged = *pose;
    match axis {
        0 => nudged.x += h,
        1 => nudged.y += h,
        _ => nudged.yaw += h,
    }
    nudged
}
