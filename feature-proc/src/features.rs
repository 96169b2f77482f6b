//! What the extractor reports for one scan: lines and corners in the sensor frame.

use slam_geom::{MeasuredCorner, MeasuredLine};

/// The features of one scan, lines (fitted by total least squares) and the corners where
/// neighbouring lines meet, each in scan order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FeatureSet {
    pub lines: Vec<MeasuredLine>,
    pub corners: Vec<MeasuredCorner>,
}
