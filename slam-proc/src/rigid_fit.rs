//! The refinement of a rigid fit of matched corners between two frames (the closed-form
//! weighted fit of the positions is `slam_geom::align_se2`): Gauss-Newton that also uses the
//! headings, each pair's full covariance and a prior on the transform.

use nalgebra::{Cholesky, Matrix3, Vector3};

use crate::observation::Prepared;
use slam_geom::Pose2;
use slam_geom::wrap_angle;

/// A Gaussian belief about a transform: the prior of a motion fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Prior {
    pub delta: Pose2,
    pub covariance: Matrix3<f64>,
}

/// Refines `start` (`target ≈ T source` for each `(target, source)` pair) by Gauss-Newton
/// on positions and headings with their covariances, plus `prior` as one more residual, so
/// the result is the maximum a posteriori transform. Returns it with its covariance.
pub(crate) fn refine(
    start: Pose2,
    pairs: &[(&Prepared, &Prepared)],
    prior: &Prior,
) -> Option<(Pose2, Matrix3<f64>)> {
    let prior_information = Cholesky::new(prior.covariance)?.inverse();
    gauss_newton(start, |estimate| {
        Some(normal_equations(estimate, pairs, prior, &prior_information))
    })
}

/// Gauss-Newton over a 2-D transform from `start`, given the normal equations `(J^T W J,
/// J^T W r)` at an estimate. Returns the estimate and its covariance `(J^T W J)^-1`.
/// It converges in two or three steps from a good start; six at most.
pub(crate) fn gauss_newton(
    start: Pose2,
    normal_equations: impl Fn(&Pose2) -> Option<(Matrix3<f64>, Vector3<f64>)>,
) -> Option<(Pose2, Matrix3<f64>)> {
    let mut estimate = start;
    for _ in 0..6 {
        let (information, gradient) = normal_equations(&estimate)?;
        let factor = Cholesky::new(information)?;
        let step = -factor.solve(&gradient);
        estimate = Pose2::new(
            estimate.x + step.x,
            estimate.y + step.y,
            wrap_angle(estimate.yaw + step.z),
        );
        if step.x.abs() < 1e-9 && step.y.abs() < 1e-9 && step.z.abs() < 1e-10 {
            // A step this small leaves the Jacobians as they were: the information just
            // used is the one at the estimate, to rounding.
            return Some((estimate, factor.inverse()));
        }
    }
    let (information, _) = normal_equations(&estimate)?;
    Some((estimate, Cholesky::new(information)?.inverse()))
}

/// `J^T W J` and `J^T W r` of every residual at `estimate`, parameters `(tx, ty, yaw)`.
pub(crate) fn normal_equations(
    estimate: &Pose2,
    pairs: &[(&Prepared, &Prepared)],
    prior: &Prior,
    prior_information: &Matrix3<f64>,
) -> (Matrix3<f64>, Vector3<f64>) {
    let (s, c) = estimate.yaw.sin_cos();
    let rotation = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    let mut information = *prior_information;
    let prior_residual = Vector3::new(
        prior.delta.x - estimate.x,
        prior.delta.y - estimate.y,
        wrap_angle(prior.delta.yaw - estimate.yaw),
    );
    // The prior residual's Jacobian is -I.
    let mut gradient = -(prior_information * prior_residual);
    for (target, source) in pairs {
        let (sx, sy) = (source.z.x, source.z.y);
        let residual = Vector3::new(
            target.z.x - (c * sx - s * sy + estimate.x),
            target.z.y - (s * sx + c * sy + estimate.y),
            wrap_angle(target.z.z - source.z.z - estimate.yaw),
        );
        let jacobian = Matrix3::new(
            -1.0,
            0.0,
            s * sx + c * sy,
            0.0,
            -1.0,
            -(c * sx - s * sy),
            0.0,
            0.0,
            -1.0,
        );
        let covariance = target.covariance.fixed_view::<3, 3>(0, 0)
            + rotation * source.covariance.fixed_view::<3, 3>(0, 0) * rotation.transpose();
        // A pair whose covariance is not positive definite carries no usable information.
        let Some(weight) = Cholesky::new(covariance).map(|ch| ch.inverse()) else {
            continue;
        };
        let jw = jacobian.transpose() * weight;
        information += jw * jacobian;
        gradient += jw * residual;
    }
    (information, gradient)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix4, Vector2, Vector4};

    fn prepared(x: f64, y: f64, heading: f64) -> Prepared {
        Prepared {
            z: Vector4::new(x, y, heading, 1.5),
            covariance: Matrix4::from_diagonal(&Vector4::new(1e-4, 1e-4, 1e-4, 1e-4)),
        }
    }

    #[test]
    fn refinement_uses_headings_and_shrinks_towards_the_prior() {
        let truth = Pose2::new(0.1, 0.05, 0.1);
        let sources = [prepared(2.0, 1.0, 0.4), prepared(-1.0, 3.0, -2.0)];
        let targets: Vec<Prepared> = sources
            .iter()
            .map(|s| {
                let p = truth.transform(Vector2::new(s.z.x, s.z.y));
                prepared(p.x, p.y, wrap_angle(s.z.z + truth.yaw))
            })
            .collect();
        let pairs: Vec<_> = targets.iter().zip(&sources).collect();
        let loose = Prior {
            delta: Pose2::IDENTITY,
            covariance: Matrix3::identity() * 1e6,
        };
        let (fit, covariance) = refine(Pose2::IDENTITY, &pairs, &loose).unwrap();
        assert!((fit.x - truth.x).abs() < 1e-6 && (fit.yaw - truth.yaw).abs() < 1e-6);
        assert!(covariance[(2, 2)] < 1e-4);
        // A tight prior at the identity pulls the estimate towards it.
        let tight = Prior {
            delta: Pose2::IDENTITY,
            covariance: Matrix3::identity() * 1e-6,
        };
        let (pulled, _) = refine(Pose2::IDENTITY, &pairs, &tight).unwrap();
        assert!(pulled.translation_norm() < 0.01 && pulled.yaw.abs() < 0.01);
    }
}
