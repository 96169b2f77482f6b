//! Angle wrapping, done once where an angle is made (docs/CONVENTIONS.md).

pub use slam_geom::wrap_angle;
