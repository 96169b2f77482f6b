//! A wall line as one scan measured it.

use nalgebra::Matrix2;

use crate::Point2;

/// A line fitted to scan points, in the sensor frame, in normal form
/// `x cos(theta) + y sin(theta) = rho` (docs/CONVENTIONS.md), with the stretch of wall it was
/// fitted to: what feature-proc extracts, and what slam-proc steadies its motion estimate
/// with and checks loop closures against (the beams crossed free space up to it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredLine {
    /// Distance from the sensor, metres, >= 0.
    pub rho: f64,
    /// Direction of the normal towards the line, in `[-pi, pi)`.
    pub theta: f64,
    /// Covariance of `(rho, theta)`, symmetric positive definite.
    pub covariance: Matrix2<f64>,
    /// The first of the fitted points in scan order, projected onto the line.
    pub start: Point2,
    /// The last of the fitted points in scan order, projected onto the line.
    pub end: Point2,
    /// Points the line was fitted to.
    pub point_count: usize,
}

impl MeasuredLine {
    /// A line seen along `length` metres of it, centred on the foot of its normal, with
    /// variance `variance` in both `rho` and `theta`: for tests and tools that build lines
    /// from their normal form.
    pub fn centred(rho: f64, theta: f64, variance: f64, length: f64) -> Self {
        let normal = Point2::new(theta.cos(), theta.sin());
        let along = Point2::new(-normal.y, normal.x) * (0.5 * length);
        Self {
            rho,
            theta,
            covariance: Matrix2::new(variance, 0.0, 0.0, variance),
            start: normal * rho - along,
            end: normal * rho + along,
            point_count: 0,
        }
    }

    /// Distance between the end points, metres.
    pub fn length(&self) -> f64 {
        (self.end.x - self.start.x).hypot(self.end.y - self.start.y)
    }

    /// Whether an estimator can use it: every number finite, the covariance positive
    /// definite.
    pub fn is_well_formed(&self) -> bool {
        let c = &self.covariance;
        self.rho.is_finite()
            && self.theta.is_finite()
            && c.iter().all(|v| v.is_finite())
            && c[(0, 0)] > 0.0
            && c[(0, 0)] * c[(1, 1)] - c[(0, 1)] * c[(1, 0)] > 0.0
            && self
                .start
                .iter()
                .chain(self.end.iter())
                .all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_centred_line_lies_on_its_normal_form_and_is_well_formed() {
        let line = MeasuredLine::centred(2.0, 0.5, 1e-4, 3.0);
        for p in [line.start, line.end] {
            let on = p.x * line.theta.cos() + p.y * line.theta.sin();
            assert!((on - line.rho).abs() < 1e-12);
        }
        assert!((line.length() - 3.0).abs() < 1e-12);
        assert!(line.is_well_formed());
        let singular = MeasuredLine {
            covariance: Matrix2::new(1.0, 1.0, 1.0, 1.0),
            ..line
        };
        assert!(!singular.is_well_formed());
        let not_finite = MeasuredLine {
            end: Point2::new(f64::NAN, 0.0),
            ..line
        };
        assert!(!not_finite.is_well_formed());
    }
}
