//! A corner at the intersection of two neighbouring fitted lines, with the covariance of
//! `(x, y, heading, angle)` propagated from the two lines' `(rho, theta)` covariances.

use nalgebra::{Matrix4, SMatrix};

use crate::config::FeatureConfig;
use slam_geom::{MeasuredCorner, MeasuredLine, Point2, wrap_angle};

/// The corner where `first` meets `second` (next in scan order), if they are two walls that
/// truly meet: the near ends close to each other and to the intersection, both arms long
/// enough and the opening angle within limits.
pub(crate) fn corner_between(
    first: &MeasuredLine,
    second: &MeasuredLine,
    config: &FeatureConfig,
) -> Option<MeasuredCorner> {
    if distance(first.end, second.start.into()) > config.corner_max_gap {
        return None;
    }
    let (s1, c1) = first.theta.sin_cos();
    let (s2, c2) = second.theta.sin_cos();
    // Rows of A are the normals: A [x y]^T = [rho1 rho2]^T.
    let det = c1 * s2 - s1 * c2;
    if det.abs() < 1e-9 {
        return None;
    }
    let tip = [
        (first.rho * s2 - second.rho * s1) / det,
        (second.rho * c1 - first.rho * c2) / det,
    ];
    // A line that stops short of the intersection ends at an occlusion, not at a corner.
    if distance(first.end, tip) > config.corner_max_extension
        || distance(second.start, tip) > config.corner_max_extension
    {
        return None;
    }
    if distance(first.start, tip) < config.min_line_length
        || distance(second.end, tip) < config.min_line_length
    {
        return None;
    }
    // Arms: unit directions from the tip along each line towards its points.
    let arm1 = arm([-s1, c1], first.start, tip);
    let arm2 = arm([-s2, c2], second.end, tip);
    let phi1 = arm1[1].atan2(arm1[0]);
    let turn = wrap_angle(arm2[1].atan2(arm2[0]) - phi1);
    let angle = turn.abs();
    if angle < config.corner_min_angle || angle > config.corner_max_angle {
        return None;
    }
    let heading = wrap_angle((-(arm1[1] + arm2[1])).atan2(-(arm1[0] + arm2[0])));

    // Jacobian of (x, y, heading, angle) by (rho1, theta1, rho2, theta2). The tip moves with
    // rho_i along column i of A^-1 and with theta_i as a rho change of -(t_i . tip). Each arm
    // turns with its own theta, so the bisector turns by half of each and the angle by
    // +-1 each.
    let d_rho1 = [s2 / det, -c2 / det];
    let d_rho2 = [-s1 / det, c1 / det];
    let t1_tip = -s1 * tip[0] + c1 * tip[1];
    let t2_tip = -s2 * tip[0] + c2 * tip[1];
    let sign = turn.signum();
    #[rustfmt::skip]
    let jacobian = Matrix4::new(
        d_rho1[0], -t1_tip * d_rho1[0], d_rho2[0], -t2_tip * d_rho2[0],
        d_rho1[1], -t1_tip * d_rho1[1], d_rho2[1], -t2_tip * d_rho2[1],
        0.0, 0.5, 0.0, 0.5,
        0.0, -sign, 0.0, sign,
    );
    let mut lines = Matrix4::zeros();
    lines
        .fixed_view_mut::<2, 2>(0, 0)
        .copy_from(&first.covariance);
    lines
        .fixed_view_mut::<2, 2>(2, 2)
        .copy_from(&second.covariance);
    let covariance: SMatrix<f64, 4, 4> = jacobian * lines * jacobian.transpose();
    Some(MeasuredCorner {
        x: tip[0],
        y: tip[1],
        heading,
        angle,
        covariance: (covariance + covariance.transpose()) * 0.5,
    })
}

/// The line direction `t` or its opposite, whichever points from `tip` towards `far`.
fn arm(t: [f64; 2], far: Point2, tip: [f64; 2]) -> [f64; 2] {
    if t[0] * (far.x - tip[0]) + t[1] * (far.y - tip[1]) >= 0.0 {
        t
    } else {
        [-t[0], -t[1]]
    }
}

fn distance(a: Point2, b: [f64; 2]) -> f64 {
    // Plain square root: `hypot`'s overflow care is not needed for metres and is slow.
    let (dx, dy) = (a.x - b[0], a.y - b[1]);
    (dx * dx + dy * dy).sqrt()
}
