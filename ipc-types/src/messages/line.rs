//! A straight line fitted to scan points.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

/// A line in normal form `x cos(theta) + y sin(theta) = rho` in the sensor frame, with the
/// row-major 2x2 covariance of `(rho, theta)` and the end points of the fitted points.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::Line::v1")]
pub struct Line {
    pub rho: f64,
    pub theta: f64,
    pub covariance: [f64; 4],
    pub start: [f64; 2],
    pub end: [f64; 2],
    pub point_count: u32,
    /// Keeps the layout free of implicit padding; always 0.
    #[serde(skip)]
    pub reserved: u32,
}
