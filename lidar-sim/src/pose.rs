//! Planar poses and angle wrapping (docs/CONVENTIONS.md: a pose is `world_from_robot`).

use serde::{Deserialize, Serialize};

/// A point or vector in the plane, metres.
pub type Point2 = nalgebra::Vector2<f64>;

pub use slam_geom::wrap_angle;

/// The transform `world_from_robot`: `p_world = R(yaw) * p_robot + (x, y)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

impl Pose2 {
    /// A pose with its yaw wrapped.
    pub fn new(x: f64, y: f64, yaw: f64) -> Self {
        Self {
            x,
            y,
            yaw: wrap_angle(yaw),
        }
    }

    /// `self * other`: `other` expressed in the frame of `self`, moved into the world.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        let (s, c) = self.yaw.sin_cos();
        Pose2::new(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            self.yaw + other.yaw,
        )
    }

    /// The inverse transform, `robot_from_world`.
    pub fn inverse(&self) -> Pose2 {
        let (s, c) = self.yaw.sin_cos();
        Pose2::new(
            -(c * self.x + s * self.y),
            s * self.x - c * self.y,
            -self.yaw,
        )
    }

    /// Maps a point from the robot frame into the world.
    pub fn transform_point(&self, p: Point2) -> Point2 {
        let (s, c) = self.yaw.sin_cos();
        Point2::new(self.x + c * p.x - s * p.y, self.y + s * p.x + c * p.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn wraps_into_half_open_interval() {
        assert_eq!(wrap_angle(PI), -PI);
        assert_eq!(wrap_angle(-PI), -PI);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((wrap_angle(-7.0 * PI) + PI).abs() < 1e-9);
        let w = wrap_angle(-1e-17);
        assert!((-PI..PI).contains(&w));
    }

    #[test]
    fn compose_with_inverse_is_identity() {
        let p = Pose2::new(1.0, -2.0, 0.7);
        let q = p.compose(&p.inverse());
        assert!(q.x.abs() < 1e-12 && q.y.abs() < 1e-12 && q.yaw.abs() < 1e-12);
        let w = p.transform_point(Point2::new(1.0, 0.0));
        assert!((w.x - (1.0 + 0.7f64.cos())).abs() < 1e-12);
    }
}
