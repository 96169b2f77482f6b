//! # slam-geom
//!
//! Planar geometry every algorithm crate of the pipeline needs, in one place and free of
//! the shared-memory transport, so the libraries stay testable on their own.
//!
//! * [`wrap_angle`] wraps an angle once, where it is made;
//! * [`Pose2`] is the planar transform `world_from_robot` (docs/CONVENTIONS.md): composition,
//!   inverse, the increment between two poses, interpolation; its yaw is always wrapped;
//! * [`Point2`] is a point or vector in the plane;
//! * [`TrueCorner`], [`MeasuredCorner`] and [`MapCorner`] are a corner as it is, as one scan
//!   measured it and as a map estimates it; [`MeasuredLine`] is a wall line as a scan measured it;
//! * [`parse_stamp_ns`] and [`format_stamp`] convert decimal seconds and nanoseconds exactly;
//! * [`align_se2`] is the weighted least-squares rigid fit of paired points ([`Se2Alignment`]);
//! * [`ScanGeometry`] says where a scan's beams point and which ranges are valid;
//! * [`read_tum`], [`parse_tum`] and [`format_tum_line`] read and write TUM trajectories.

mod align;
mod angle;
mod corner;
mod line;
mod pose;
mod scan_geometry;
mod stamp;
mod stamped_pose;
mod tum;

pub use align::{Se2Alignment, WeightedPair, align_se2};
pub use angle::wrap_angle;
pub use corner::{MapCorner, MeasuredCorner, TrueCorner};
pub use line::MeasuredLine;
pub use pose::Pose2;
pub use scan_geometry::{ScanGeometry, ScanGeometryError};
pub use stamp::{StampError, StampProblem, format_stamp, parse_stamp_ns};
pub use stamped_pose::StampedPose;
pub use tum::{
    TumError, TumPose, TumProblem, TumReadError, format_tum_line, parse_tum, parse_tum_line,
    read_tum, yaw_quaternion,
};

/// A point or vector in the plane, metres.
pub type Point2 = nalgebra::Vector2<f64>;
