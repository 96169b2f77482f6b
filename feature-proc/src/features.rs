//! What the extractor reports for one scan: lines and corners in the sensor frame.

use nalgebra::Matrix2;
use slam_geom::MeasuredCorner;

/// A line in normal form `x cos(theta) + y sin(theta) = rho`, fitted by total least squares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Distance from the sensor, metres, >= 0.
    pub rho: f64,
    /// Direction of the normal towards the line, in `[-pi, pi)`.
    pub theta: f64,
    /// Covariance of `(rho, theta)`.
    pub covariance: Matrix2<f64>,
    /// The first fitted point in scan order, projected onto the line.
    pub start: [f64; 2],
    /// The last fitted point in scan order, projected onto the line.
    pub end: [f64; 2],
    /// Points the line was fitted to.
    pub point_count: usize,
}

impl Line {
    /// Distance between the end points, metres.
    pub fn length(&self) -> f64 {
        (self.end[0] - self.start[0]).hypot(self.end[1] - self.start[1])
    }
}

/// The features of one scan, lines and corners each in scan order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FeatureSet {
    pub lines: Vec<Line>,
    pub corners: Vec<MeasuredCorner>,
}
