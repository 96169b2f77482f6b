//! Each particle's path and the loop closures on it, smoothed as a pose graph.

pub(crate) mod particle_path;
pub(crate) mod pose_graph;

/// Whether each step between consecutive poses is a metre long, within `tolerance` metres:
/// a smoothed path of one-metre steps with no jump left in it.
#[cfg(test)]
pub(crate) fn steps_are_a_metre(poses: &[slam_geom::StampedPose], tolerance: f64) -> bool {
    poses
        .windows(2)
        .all(|w| (w[0].pose.between(&w[1].pose).translation_norm() - 1.0).abs() < tolerance)
}
