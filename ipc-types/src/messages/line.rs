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

impl From<slam_geom::MeasuredLine> for Line {
    /// The covariance goes row by row into the message; a count beyond `u32` saturates.
    fn from(l: slam_geom::MeasuredLine) -> Self {
        Self {
            rho: l.rho,
            theta: l.theta,
            covariance: [
                l.covariance[(0, 0)],
                l.covariance[(0, 1)],
                l.covariance[(1, 0)],
                l.covariance[(1, 1)],
            ],
            start: [l.start.x, l.start.y],
            end: [l.end.x, l.end.y],
            point_count: u32::try_from(l.point_count).unwrap_or(u32::MAX),
            reserved: 0,
        }
    }
}

impl From<Line> for slam_geom::MeasuredLine {
    fn from(l: Line) -> Self {
        Self {
            rho: l.rho,
            theta: l.theta,
            covariance: nalgebra::Matrix2::from_row_slice(&l.covariance),
            start: l.start.into(),
            end: l.end.into(),
            point_count: l.point_count as usize,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_measured_line_goes_through_the_message_unchanged() {
        let measured = slam_geom::MeasuredLine {
            covariance: nalgebra::Matrix2::new(1e-4, 2e-5, 3e-5, 4e-4),
            point_count: 40,
            ..slam_geom::MeasuredLine::centred(2.0, -0.7, 1e-4, 1.5)
        };
        let message = Line::from(measured);
        assert_eq!(message.covariance[1], 2e-5, "row-major: (0, 1)");
        assert_eq!(message.covariance[2], 3e-5, "row-major: (1, 0)");
        assert_eq!(message.point_count, 40);
        assert_eq!(slam_geom::MeasuredLine::from(message), measured);
    }
}
