//! A corner feature: where two straight walls meet.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

/// A corner (see docs/CONVENTIONS.md): the walls' intersection point, the heading of the
/// bisector towards the tip and the opening angle, with a row-major 4x4 covariance over
/// `(x, y, heading, angle)`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
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
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::TrueCorner::v1")]
pub struct TrueCorner {
    pub x: f64,
    pub y: f64,
    pub heading: f64,
    pub angle: f64,
}

/// A corner of a SLAM map with the number of scans that saw it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[type_name("slam::MapCorner::v1")]
pub struct MapCorner {
    pub corner: Corner,
    pub observations: u32,
    /// Keeps the layout free of implicit padding; always 0.
    #[serde(skip)]
    pub reserved: u32,
}

impl From<slam_geom::MeasuredCorner> for Corner {
    /// The covariance goes row by row into the message.
    fn from(c: slam_geom::MeasuredCorner) -> Self {
        Self {
            x: c.x,
            y: c.y,
            heading: c.heading,
            angle: c.angle,
            covariance: std::array::from_fn(|i| c.covariance[(i / 4, i % 4)]),
        }
    }
}

impl From<Corner> for slam_geom::MeasuredCorner {
    fn from(c: Corner) -> Self {
        Self {
            x: c.x,
            y: c.y,
            heading: c.heading,
            angle: c.angle,
            covariance: nalgebra::Matrix4::from_row_slice(&c.covariance),
        }
    }
}

impl From<slam_geom::TrueCorner> for TrueCorner {
    fn from(c: slam_geom::TrueCorner) -> Self {
        Self {
            x: c.x,
            y: c.y,
            heading: c.heading,
            angle: c.angle,
        }
    }
}

impl From<TrueCorner> for slam_geom::TrueCorner {
    fn from(c: TrueCorner) -> Self {
        Self {
            x: c.x,
            y: c.y,
            heading: c.heading,
            angle: c.angle,
        }
    }
}

impl From<slam_geom::MapCorner> for MapCorner {
    /// The covariance goes row by row into the message.
    fn from(c: slam_geom::MapCorner) -> Self {
        Self {
            corner: Corner {
                x: c.x,
                y: c.y,
                heading: c.heading,
                angle: c.angle,
                covariance: std::array::from_fn(|i| c.covariance[(i / 4, i % 4)]),
            },
            observations: c.observations,
            reserved: 0,
        }
    }
}

impl From<MapCorner> for slam_geom::MapCorner {
    fn from(c: MapCorner) -> Self {
        let corner = c.corner;
        Self {
            x: corner.x,
            y: corner.y,
            heading: corner.heading,
            angle: corner.angle,
            covariance: nalgebra::Matrix4::from_row_slice(&corner.covariance),
            observations: c.observations,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_corner_keeps_its_covariance_row_by_row() {
        let corner = slam_geom::MapCorner {
            x: 1.0,
            y: -2.0,
            heading: 0.5,
            angle: 1.2,
            covariance: nalgebra::Matrix4::from_fn(|r, k| (4 * r + k) as f64),
            observations: 9,
        };
        let message = MapCorner::from(corner);
        assert_eq!(message.corner.covariance[1], 1.0, "row-major: (0, 1)");
        assert_eq!(message.corner.covariance[4], 4.0, "row-major: (1, 0)");
        assert_eq!(slam_geom::MapCorner::from(message), corner);
        let truth = slam_geom::TrueCorner::from_arms(
            slam_geom::Point2::new(1.0, 2.0),
            slam_geom::Point2::x(),
            slam_geom::Point2::y(),
        );
        assert_eq!(slam_geom::TrueCorner::from(TrueCorner::from(truth)), truth);
    }

    #[test]
    fn a_measured_corner_goes_through_the_message_unchanged() {
        let measured = slam_geom::MeasuredCorner {
            x: 3.0,
            y: -1.5,
            heading: -2.0,
            angle: 1.6,
            covariance: nalgebra::Matrix4::from_fn(|r, k| (1 + 4 * r + k) as f64),
        };
        let message = Corner::from(measured);
        assert_eq!(message.covariance[1], 2.0, "row-major: (0, 1)");
        assert_eq!(message.covariance[4], 5.0, "row-major: (1, 0)");
        assert_eq!(slam_geom::MeasuredCorner::from(message), measured);
    }
}
