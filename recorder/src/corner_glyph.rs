//! How a corner is drawn in a scene: its two walls as short arms from the tip, and the
//! covariance of its position as an ellipse.
//!
//! The ellipse is a sphere flattened to a disc and scaled along the eigenvectors of the 2x2
//! position covariance, 2 sigma each way: Foxglove draws a sphere with any orientation and
//! extent as one exact, filled, see-through ellipse, in a few numbers (a loop of lines
//! would be a polygon of many points, drawn as an outline that a dense map turns into a
//! tangle).

use ipc_types::Corner;

use crate::geometry::Vector3;
use crate::scene::{Color, SpherePrimitive, mm, planar_pose, point};

/// Length of a drawn arm, metres: long enough to show the walls' directions at a glance,
/// short enough that neighbouring corners' arms do not cross.
pub const ARM_LENGTH: f64 = 0.3;
/// Sigmas of the position covariance the ellipse reaches along each axis.
pub const ELLIPSE_SIGMAS: f64 = 2.0;
/// Height of the flattened ellipse, metres: a disc, not a ball, seen from above or aside.
const ELLIPSE_HEIGHT: f64 = 0.002;

/// Whether the corner's position, heading and angle are numbers a scene can hold (JSON has
/// no NaN or infinity).
pub fn drawable(c: &Corner) -> bool {
    [c.x, c.y, c.heading, c.angle].iter().all(|v| v.is_finite())
}

/// The end of the first arm, the tip and the end of the second arm. The arms run along the
/// walls, at half the opening angle either side of the bisector, which points away from the
/// tip (docs/CONVENTIONS.md, "Corner features": `heading` points towards it).
pub fn arms(c: &Corner) -> [Vector3; 3] {
    let away = c.heading + std::f64::consts::PI;
    let end = |direction: f64| {
        point(
            c.x + ARM_LENGTH * direction.cos(),
            c.y + ARM_LENGTH * direction.sin(),
        )
    };
    [
        end(away - 0.5 * c.angle),
        point(c.x, c.y),
        end(away + 0.5 * c.angle),
    ]
}

/// The 2-sigma ellipse of the corner's position covariance, or `None` when the covariance
/// is not a finite symmetric 2x2 block with non-negative eigenvalues.
pub fn ellipse(c: &Corner, color: Color) -> Option<SpherePrimitive> {
    // Row-major 4x4 over (x, y, heading, angle): the position block is (0, 1, 4, 5).
    let (a, b, d) = (c.covariance[0], c.covariance[1], c.covariance[5]);
    if ![a, b, d].iter().all(|v| v.is_finite()) {
        return None;
    }
    let mean = 0.5 * (a + d);
    let spread = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (major, minor) = (mean + spread, mean - spread);
    if minor < 0.0 {
        return None;
    }
    // The major axis's direction; any direction for a round covariance.
    let yaw = 0.5 * (2.0 * b).atan2(a - d);
    let diameter = |variance: f64| mm(2.0 * ELLIPSE_SIGMAS * variance.sqrt());
    Some(SpherePrimitive {
        pose: planar_pose(c.x, c.y, yaw),
        size: Vector3 {
            x: diameter(major),
            y: diameter(minor),
            z: ELLIPSE_HEIGHT,
        },
        color,
    })
}
