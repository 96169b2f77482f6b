//! The observation model: a corner seen in the sensor frame, taken to the world by a pose.
//!
//! `w = (R z_xy + t, heading + yaw, angle)`: the opening angle does not depend on the pose.
//! Its covariance is `G_z S G_z^T` with `G_z = diag(R, 1, 1)`; the pose's own uncertainty
//! enters through `G_x`, the Jacobian with respect to `(x, y, yaw)`.

#[cfg(test)]
use nalgebra::Matrix4x3;
use nalgebra::{Matrix4, Vector2, Vector4};

use crate::filter::observation::Prepared;
use slam_geom::Pose2;
use slam_geom::wrap_angle;

/// An observation in the world frame of one particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WorldObservation {
    /// `(x, y, heading, angle)`, heading wrapped.
    pub z: Vector4<f64>,
    /// Covariance from the sensor noise alone, `G_z S G_z^T`.
    pub covariance: Matrix4<f64>,
    /// `d (x, y) / d yaw`: how turning the pose moves the corner. The rest of the pose
    /// Jacobian is constant (see [`WorldObservation::pose_jacobian`]).
    pub lever: Vector2<f64>,
}

#[cfg(test)]
impl WorldObservation {
    /// `d w / d (x, y, yaw)` of the pose: `[[1, 0, lx], [0, 1, ly], [0, 0, 1], [0, 0, 0]]`
    /// (position and heading move with the pose, the opening angle does not).
    pub fn pose_jacobian(&self) -> Matrix4x3<f64> {
        let mut g = Matrix4x3::zeros();
        g[(0, 0)] = 1.0;
        g[(1, 1)] = 1.0;
        g[(0, 2)] = self.lever.x;
        g[(1, 2)] = self.lever.y;
        g[(2, 2)] = 1.0;
        g
    }
}

/// Takes `observation` from the sensor frame of `pose` to the world.
#[cfg(test)]
pub(crate) fn to_world(pose: &Pose2, observation: &Prepared) -> WorldObservation {
    PoseTransform::new(pose).to_world(observation)
}

/// A particle's pose with its rotation evaluated once, for all of a scan's observations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PoseTransform {
    pose: Pose2,
    sin: f64,
    cos: f64,
}

impl PoseTransform {
    pub fn new(pose: &Pose2) -> Self {
        let (sin, cos) = pose.yaw.sin_cos();
        Self {
            pose: *pose,
            sin,
            cos,
        }
    }

    /// A world point in this frame.
    pub fn to_local(self, x: f64, y: f64) -> (f64, f64) {
        let (dx, dy) = (x - self.pose.x, y - self.pose.y);
        (
            self.cos * dx + self.sin * dy,
            -self.sin * dx + self.cos * dy,
        )
    }

    /// Takes `observation` from this frame to the world.
    pub fn to_world(self, observation: &Prepared) -> WorldObservation {
        let (pose, s, c) = (&self.pose, self.sin, self.cos);
        let (x, y) = (observation.z.x, observation.z.y);
        let z = Vector4::new(
            pose.x + c * x - s * y,
            pose.y + s * x + c * y,
            wrap_angle(observation.z.z + pose.yaw),
            observation.z.w,
        );
        // G_z S G_z^T with G_z = diag(R, 1, 1): rotate the first two rows, then the first two
        // columns.
        let mut covariance = observation.covariance;
        for j in 0..4 {
            let (a, b) = (covariance[(0, j)], covariance[(1, j)]);
            covariance[(0, j)] = c * a - s * b;
            covariance[(1, j)] = s * a + c * b;
        }
        for i in 0..4 {
            let (a, b) = (covariance[(i, 0)], covariance[(i, 1)]);
            covariance[(i, 0)] = c * a - s * b;
            covariance[(i, 1)] = s * a + c * b;
        }
        WorldObservation {
            z,
            covariance,
            lever: Vector2::new(-s * x - c * y, c * x - s * y),
        }
    }
}

/// `observed - corner`, heading and angle wrapped.
pub(crate) fn innovation(observed: &Vector4<f64>, corner: &Vector4<f64>) -> Vector4<f64> {
    Vector4::new(
        observed.x - corner.x,
        observed.y - corner.y,
        wrap_angle(observed.z - corner.z),
        wrap_angle(observed.w - corner.w),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::finite_difference::nudged;

    #[test]
    fn jacobians_match_finite_differences() {
        let observation = Prepared {
            z: Vector4::new(3.0, -1.0, 2.9, 1.2),
            covariance: Matrix4::from_diagonal(&Vector4::new(4e-4, 1e-4, 1e-4, 2e-4)),
        };
        let pose = Pose2::new(1.0, 2.0, 0.7);
        let w = to_world(&pose, &observation);
        let h = 1e-7;
        for k in 0..3 {
            let moved = nudged(&pose, k, h);
            let numeric = innovation(&to_world(&moved, &observation).z, &w.z) / h;
            for row in 0..4 {
                assert!((numeric[row] - w.pose_jacobian()[(row, k)]).abs() < 1e-5);
            }
        }
        // The covariance is G_z S G_z^T; heading gets the yaw.
        let mut g = Matrix4::identity();
        g.fixed_view_mut::<2, 2>(0, 0).copy_from(&pose.rotation());
        let mut correlated = observation;
        correlated.covariance[(0, 2)] = 5e-5;
        correlated.covariance[(2, 0)] = 5e-5;
        let expected = g * correlated.covariance * g.transpose();
        assert!(
            (to_world(&pose, &correlated).covariance - expected)
                .abs()
                .max()
                < 1e-18
        );
        assert!((w.z.z - wrap_angle(2.9 + 0.7)).abs() < 1e-15 && w.z.z < 0.0);
    }
}
