//! Corners: where two straight walls meet (docs/CONVENTIONS.md).

use nalgebra::Matrix4;

use crate::{Point2, wrap_angle};

/// A corner as it is: the walls' intersection point, the heading of the bisector towards the
/// tip and the opening angle. A world's corners, the truth a map is scored against.
///
/// With `d1`, `d2` the unit vectors from the tip along the two walls,
/// `angle = acos(d1 . d2)` and `heading = atan2(-(d1 + d2))`. Both depend on the arms alone,
/// not on the side the sensor is on, which is exactly what a feature extractor computes
/// from the two fitted lines: a room corner (seen from inside) has its heading pointing
/// into the wall, a pillar corner (seen from outside) pointing away from the pillar.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueCorner {
    pub x: f64,
    pub y: f64,
    /// Bisector towards the tip, in `[-pi, pi)`.
    pub heading: f64,
    /// Opening angle, in `(0, pi)`.
    pub angle: f64,
}

impl TrueCorner {
    /// The corner of the arms `d1`, `d2` (unit vectors from `tip`).
    pub fn from_arms(tip: Point2, d1: Point2, d2: Point2) -> TrueCorner {
        let s = -(d1 + d2);
        TrueCorner {
            x: tip.x,
            y: tip.y,
            heading: wrap_angle(s.y.atan2(s.x)),
            angle: d1.dot(&d2).clamp(-1.0, 1.0).acos(),
        }
    }

    /// The unit arms back from `heading` and `angle`: the bisector opposite the heading,
    /// turned by half the angle either way.
    pub fn arms(&self) -> [Point2; 2] {
        let back = self.heading + std::f64::consts::PI;
        let h = 0.5 * self.angle;
        [back - h, back + h].map(|a| Point2::new(a.cos(), a.sin()))
    }
}

/// A corner as one scan measured it, in the sensor frame: the extractor's output and the
/// filter's input, with the covariance of `(x, y, heading, angle)` (symmetric positive
/// definite) propagated from the two fitted lines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredCorner {
    pub x: f64,
    pub y: f64,
    /// Bisector towards the tip, in `[-pi, pi)`.
    pub heading: f64,
    /// Opening angle between the walls, in `(0, pi)`.
    pub angle: f64,
    /// Covariance of `(x, y, heading, angle)`.
    pub covariance: Matrix4<f64>,
}

/// A corner of a SLAM map, in the map frame: the estimate of a [`TrueCorner`] with its
/// covariance and the number of scans that saw it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapCorner {
    pub x: f64,
    pub y: f64,
    /// Bisector towards the tip, in `[-pi, pi)`.
    pub heading: f64,
    /// Opening angle, in `(0, pi)`.
    pub angle: f64,
    /// Covariance of `(x, y, heading, angle)`.
    pub covariance: Matrix4<f64>,
    /// Scans in which the corner was observed.
    pub observations: u32,
}

impl MapCorner {
    /// `corner` as a map holds it: with the covariance of its estimate and the number of
    /// scans that saw it.
    pub fn observed(corner: TrueCorner, covariance: Matrix4<f64>, observations: u32) -> Self {
        Self {
            x: corner.x,
            y: corner.y,
            heading: corner.heading,
            angle: corner.angle,
            covariance,
            observations,
        }
    }

    pub fn position(&self) -> Point2 {
        Point2::new(self.x, self.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn a_room_corner_points_into_the_walls_and_its_arms_come_back() {
        // Walls along +x and +y from the origin: seen from inside the room.
        let c = TrueCorner::from_arms(Point2::zeros(), Point2::x(), Point2::y());
        assert!((c.angle - FRAC_PI_2).abs() < 1e-12);
        assert!((c.heading + 0.75 * std::f64::consts::PI).abs() < 1e-12);
        let [a, b] = c.arms();
        let near = |p: Point2, q: Point2| (p - q).norm() < 1e-12;
        assert!(
            near(a, Point2::x()) && near(b, Point2::y())
                || near(a, Point2::y()) && near(b, Point2::x())
        );
    }
}
