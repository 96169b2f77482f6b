//! A corner at the intersection of two neighbouring fitted lines, with the covariance of
//! `(x, y, heading, angle)` propagated from the two lines' `(rho, theta)` covariances.

use nalgebra::{Matrix4, SMatrix};

use slam_geom::{MeasuredCorner, MeasuredLine, Point2, wrap_angle};

/// Shortest arm of a corner, metres: the distance from the intersection to the far end of
/// each line (and the shortest stub that stays a line of its own). A pillar's side is about
/// this long; shorter arms are too few beams to fix a direction.
pub const MIN_LINE_LENGTH: f64 = 0.3;
/// Smallest opening angle of a corner, radians. Wider than the course's 60..120 degrees, with
/// both limits clear of the common 45, 120 and 135 degree corners so that none of them
/// flickers at a limit.
pub const CORNER_MIN_ANGLE: f64 = 40f64.to_radians();
/// Largest opening angle of a corner, radians (see [`CORNER_MIN_ANGLE`]); flatter than this,
/// the two walls' intersection is too poorly fixed along them.
pub const CORNER_MAX_ANGLE: f64 = 130f64.to_radians();
/// Largest gap between the end of one line and the start of the next for them to form a
/// corner, metres: wider is an opening between two walls, not a corner.
const CORNER_MAX_GAP: f64 = 0.3;
/// Largest distance from either line's near end to the intersection, metres: a line that
/// stops short of the intersection ends at an occlusion or a doorway, not a corner.
const CORNER_MAX_EXTENSION: f64 = 0.25;

/// The corner where `first` meets `second` (next in scan order), if they are two walls that
/// truly meet: the near ends close to each other and to the intersection, both arms long
/// enough and the opening angle within limits.
pub(crate) fn corner_between(
    first: &MeasuredLine,
    second: &MeasuredLine,
) -> Option<MeasuredCorner> {
    if distance(first.end, second.start.into()) > CORNER_MAX_GAP {
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
    if distance(first.end, tip) > CORNER_MAX_EXTENSION
        || distance(second.start, tip) > CORNER_MAX_EXTENSION
    {
        return None;
    }
    if distance(first.start, tip) < MIN_LINE_LENGTH || distance(second.end, tip) < MIN_LINE_LENGTH {
        return None;
    }
    // Arms: unit directions from the tip along each line towards its points.
    let arm1 = arm([-s1, c1], first.start, tip);
    let arm2 = arm([-s2, c2], second.end, tip);
    let phi1 = arm1[1].atan2(arm1[0]);
    let turn = wrap_angle(arm2[1].atan2(arm2[0]) - phi1);
    let angle = turn.abs();
    if !(CORNER_MIN_ANGLE..=CORNER_MAX_ANGLE).contains(&angle) {
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
