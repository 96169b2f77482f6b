//! One relative-pose measurement between two nodes, linearised; and the robust kernel of
//! the closures (dynamic covariance scaling).

use nalgebra::{Matrix3, Vector3};
use slam_geom::{Pose2, wrap_angle};

/// A measurement's error at the current poses and its derivatives with respect to them.
#[derive(Debug, Clone, Copy)]
pub(super) struct Linearized {
    /// `(x, y, yaw)` of the pose `to` in the frame of `from`, minus the measurement: the
    /// translation in the frame of `from` (the frame of its information), the yaw wrapped.
    pub error: Vector3<f64>,
    /// `d error / d from`, the poses' `(x, y, yaw)` in the world frame.
    pub jacobian_from: Matrix3<f64>,
    /// `d error / d to`.
    pub jacobian_to: Matrix3<f64>,
}

impl Linearized {
    /// The error of `seen` (pose `to` measured in the frame of `from`) at `from`, `to`.
    pub(super) fn new(from: &Frame, to: &Pose2, seen: &Pose2) -> Self {
        let (s, c) = (from.sin, from.cos);
        let now = relative(from, to);
        let error = Vector3::new(
            now.x - seen.x,
            now.y - seen.y,
            wrap_angle(now.yaw - seen.yaw),
        );
        // `now = R(from.yaw)^T (to - from)`: turning `from` swings the offset.
        let jacobian_from = Matrix3::new(-c, -s, now.y, s, -c, -now.x, 0.0, 0.0, -1.0);
        let jacobian_to = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
        Self {
            error,
            jacobian_from,
            jacobian_to,
        }
    }
}

/// A node's pose with its yaw's sine and cosine: taken once per pose for all the edges that
/// leave it, rather than once per edge, at every evaluation of the cost and the equations.
#[derive(Debug, Clone, Copy)]
pub(super) struct Frame {
    pose: Pose2,
    sin: f64,
    cos: f64,
}

impl Frame {
    pub(super) fn new(pose: &Pose2) -> Self {
        let (sin, cos) = pose.yaw.sin_cos();
        Self {
            pose: *pose,
            sin,
            cos,
        }
    }
}

/// Every pose as a frame.
pub(super) fn frames(poses: &[Pose2]) -> Vec<Frame> {
    poses.iter().map(Frame::new).collect()
}

/// `from.between(to)`.
fn relative(from: &Frame, to: &Pose2) -> Pose2 {
    let (s, c) = (from.sin, from.cos);
    let (dx, dy) = (to.x - from.pose.x, to.y - from.pose.y);
    Pose2 {
        x: c * dx + s * dy,
        y: -s * dx + c * dy,
        yaw: wrap_angle(to.yaw - from.pose.yaw),
    }
}

/// The error of `seen` at `from`, `to` only (no derivatives).
pub(super) fn error(from: &Frame, to: &Pose2, seen: &Pose2) -> Vector3<f64> {
    let now = relative(from, to);
    Vector3::new(
        now.x - seen.x,
        now.y - seen.y,
        wrap_angle(now.yaw - seen.yaw),
    )
}

/// The squared Mahalanobis norm `e^T W e`.
pub(super) fn chi2(error: &Vector3<f64>, information: &Matrix3<f64>) -> f64 {
    error.dot(&(information * error))
}

/// Dynamic covariance scaling (Agarwal et al. 2013), the closed form of a switchable
/// constraint's switch: a closure of squared error `chi2` counts with its information scaled
/// by `scale^2`, full up to `phi` and falling as `2 phi / (phi + chi2)` beyond.
pub(super) fn dcs_scale(chi2: f64, phi: f64) -> f64 {
    if chi2 <= phi {
        1.0
    } else {
        2.0 * phi / (phi + chi2)
    }
}

/// The curvature the kernel adds beyond the threshold: Newton's Hessian of a closure's
/// cost is `J^T (scale^2 W + c (W e)(W e)^T) J` with `c` this (twice the second derivative
/// of the cost in `chi2`); zero below the threshold, where the cost is `chi2` itself.
pub(super) fn dcs_curvature(chi2: f64, phi: f64) -> f64 {
    if chi2 <= phi {
        0.0
    } else {
        -4.0 * dcs_scale(chi2, phi).powi(2) / (phi + chi2)
    }
}

/// The cost that [`dcs_scale`] minimises by reweighting: `chi2` up to `phi`, then bounded
/// by `3 phi`, so a closure however wrong costs at most that.
pub(super) fn dcs_cost(chi2: f64, phi: f64) -> f64 {
    if chi2 <= phi {
        chi2
    } else {
        phi * (3.0 * chi2 - phi) / (phi + chi2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_jacobians_are_the_derivatives_of_the_error() {
        let from = Pose2::new(1.0, -2.0, 2.9);
        let to = Pose2::new(-0.5, 0.7, -2.8);
        let seen = Pose2::new(0.3, 0.2, 0.4);
        let linear = Linearized::new(&Frame::new(&from), &to, &seen);
        let h = 1e-6;
        for k in 0..3 {
            let nudge = |p: &Pose2| {
                let mut v = [p.x, p.y, p.yaw];
                v[k] += h;
                Pose2::new(v[0], v[1], v[2])
            };
            let d_from = (error(&Frame::new(&nudge(&from)), &to, &seen) - linear.error) / h;
            let d_to = (error(&Frame::new(&from), &nudge(&to), &seen) - linear.error) / h;
            for r in 0..3 {
                assert!((d_from[r] - linear.jacobian_from[(r, k)]).abs() < 1e-5);
                assert!((d_to[r] - linear.jacobian_to[(r, k)]).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn the_relative_pose_is_the_increment_between_the_poses() {
        let from = Pose2::new(1.0, -2.0, 2.9);
        let to = Pose2::new(-0.5, 0.7, -2.8);
        let fast = relative(&Frame::new(&from), &to);
        let slow = from.between(&to);
        assert!((fast.x - slow.x).abs() < 1e-12 && (fast.y - slow.y).abs() < 1e-12);
        assert!(wrap_angle(fast.yaw - slow.yaw).abs() < 1e-12);
    }

    #[test]
    fn the_scale_is_the_derivative_of_the_cost() {
        // The reweighting minimises the cost: its weight, scale^2, is d cost / d chi2.
        let phi = 5.0;
        for chi2 in [0.5, 4.9, 5.1, 12.0, 300.0, 1e5] {
            let h = 1e-6 * chi2;
            let slope = (dcs_cost(chi2 + h, phi) - dcs_cost(chi2 - h, phi)) / (2.0 * h);
            let weight = dcs_scale(chi2, phi).powi(2);
            assert!((slope - weight).abs() < 1e-6 * weight.max(1e-3), "{chi2}");
        }
        for chi2 in [5.1, 12.0, 300.0] {
            let h = 1e-5 * chi2;
            let bend = (dcs_scale(chi2 + h, phi).powi(2) - dcs_scale(chi2 - h, phi).powi(2)) / h;
            assert!((bend - dcs_curvature(chi2, phi)).abs() < 1e-6, "{chi2}");
        }
        assert!(dcs_cost(1e12, phi) < 3.0 * phi);
        assert_eq!(dcs_scale(3.0 * phi, phi), 0.5);
    }
}
