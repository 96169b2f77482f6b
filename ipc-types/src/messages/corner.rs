//! A corner feature: where two straight walls meet.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};

/// A corner (see docs/CONVENTIONS.md): the walls' intersection point, the heading of the
/// bisector towards the tip and the opening angle, with a row-major 4x4 covariance over
/// `(x, y, heading, angle)`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("slam::Corner::v1")]
pub struct Corner {
    pub x: f64,
    pub y: f64,
    pub heading: f64,
    pub angle: f64,
    pub covariance: [f64; 16],
}

/// A corner of the simulated world, for scoring a map. No covariance: it is the truth.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("slam::TrueCorner::v1")]
pub struct TrueCorner {
    pub x: f64,
    pub y: f64,
    pub heading: f64,
    pub angle: f64,
}

/// A corner of a SLAM map with the number of scans that saw it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("slam::MapCorner::v1")]
pub struct MapCorner {
    pub corner: Corner,
    pub observations: u32,
    /// Keeps the layout free of implicit padding; always 0.
    pub reserved: u32,
}
