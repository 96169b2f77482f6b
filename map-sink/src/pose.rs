//! The planar pose the recorder works with, independent of the IPC message types.

/// A planar pose `world_from_robot` (docs/CONVENTIONS.md): metres and radians.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose2 {
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

impl Pose2 {
    pub const fn new(x: f64, y: f64, yaw: f64) -> Self {
        Self { x, y, yaw }
    }

    pub const fn position(&self) -> [f64; 2] {
        [self.x, self.y]
    }

    /// Moves a point from the robot frame into the world frame.
    pub fn transform_point(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.yaw.sin_cos();
        [c * p[0] - s * p[1] + self.x, s * p[0] + c * p[1] + self.y]
    }
}

pub use slam_geom::wrap_angle;
