//! What the filter reports after each scan.

use nalgebra::{Matrix3, Vector3};

use ipc_types::StageTiming;
use slam_geom::Pose2;
use slam_geom::wrap_angle;

/// The pose estimate after one scan, in the map frame (the first pose is the origin).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Pose of the particle with the highest weight.
    pub best: Pose2,
    /// Weighted mean of the particles (yaw by circular mean).
    pub mean: Pose2,
    /// Weighted spread of the particles over `(x, y, yaw)`, yaw differences wrapped
    /// around the mean.
    pub covariance: Matrix3<f64>,
    /// `1 / sum(w_i^2)` of the normalised weights, before any resampling of this scan.
    pub effective_particles: f64,
    pub particle_count: usize,
    /// The scan-to-scan motion estimate integrated alone, for comparison.
    pub dead_reckoning: Pose2,
    /// Confirmed corners in the best particle's map.
    pub map_size: usize,
    pub timing: StageTiming,
}

/// Weighted mean (circular for yaw) and covariance of `(pose, weight)` pairs whose weights
/// sum to one.
pub(crate) fn weighted_mean_and_covariance(
    samples: impl Iterator<Item = (Pose2, f64)> + Clone,
) -> (Pose2, Matrix3<f64>) {
    let (mut x, mut y, mut sin, mut cos) = (0.0, 0.0, 0.0, 0.0);
    for (pose, w) in samples.clone() {
        x += w * pose.x;
        y += w * pose.y;
        let (s, c) = pose.yaw.sin_cos();
        sin += w * s;
        cos += w * c;
    }
    let mean = Pose2::new(x, y, wrap_angle(sin.atan2(cos)));
    let mut covariance = Matrix3::zeros();
    for (pose, w) in samples {
        let d = Vector3::new(
            pose.x - mean.x,
            pose.y - mean.y,
            wrap_angle(pose.yaw - mean.yaw),
        );
        covariance += d * d.transpose() * w;
    }
    (mean, covariance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn yaw_mean_and_spread_wrap_around_pi() {
        let samples = [
            (Pose2::new(0.0, 0.0, PI - 0.1), 0.5),
            (Pose2::new(2.0, 0.0, -PI + 0.1), 0.5),
        ];
        let (mean, covariance) = weighted_mean_and_covariance(samples.iter().copied());
        assert!((mean.x - 1.0).abs() < 1e-12);
        assert!(wrap_angle(mean.yaw - PI).abs() < 1e-12);
        assert!((covariance[(2, 2)] - 0.01).abs() < 1e-12);
        assert!((covariance[(0, 0)] - 1.0).abs() < 1e-12);
    }
}
