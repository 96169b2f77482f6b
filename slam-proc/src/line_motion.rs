//! The motion between consecutive scans from their wall lines, for scans where too few
//! corners match for a rigid fit (a corridor between corners).
//!
//! A line `x cos(theta) + y sin(theta) = rho` of the current scan, seen from the previous
//! scan's frame through `previous_from_current = (tx, ty, yaw)`, is
//! `theta' = theta + yaw`, `rho' = rho + tx cos(theta') + ty sin(theta')`. Matched to the
//! previous scan's lines, each gives two residuals: its angle fixes the rotation, its
//! offset the translation across it. Translation along every matched line stays with the
//! prior (constant velocity or odometry), which enters the least squares as one more
//! residual, so two parallel walls give the heading and the lateral offset and the prior
//! the rest.

use std::f64::consts::PI;

use nalgebra::{Cholesky, Matrix2, Matrix2x3, Matrix3, Vector2, Vector3};

use crate::angle::wrap_angle;
use crate::observation::LineObservation;
use crate::pose::Pose2;
use crate::rigid_fit::{Prior, gauss_newton};

/// A line of the current scan in the previous scan's frame.
struct Moved {
    /// `(rho', theta')`.
    line: Vector2<f64>,
    /// `d (rho', theta') / d (tx, ty, yaw)`.
    pose_jacobian: Matrix2x3<f64>,
    /// `d (rho', theta') / d (rho, theta)`, which carries the line's own covariance.
    line_jacobian: Matrix2<f64>,
}

fn moved(line: &LineObservation, t: &Pose2) -> Moved {
    let theta = line.theta + t.yaw;
    let (s, c) = theta.sin_cos();
    let turn = -t.x * s + t.y * c;
    Moved {
        line: Vector2::new(line.rho + t.x * c + t.y * s, theta),
        pose_jacobian: Matrix2x3::new(c, s, turn, 0.0, 0.0, 1.0),
        line_jacobian: Matrix2::new(1.0, turn, 0.0, 1.0),
    }
}

/// A matched pair's residual `moved - target`, its pose Jacobian and its covariance
/// (both lines' noise), in whichever normal form of the moved line, `(rho, theta)` or
/// `(-rho, theta + pi)`, faces the target: a line through the sensor flips between them.
fn residual(
    current: &LineObservation,
    target: &LineObservation,
    t: &Pose2,
) -> (Vector2<f64>, Matrix2x3<f64>, Matrix2<f64>) {
    let m = moved(current, t);
    let same = Vector2::new(m.line.x - target.rho, wrap_angle(m.line.y - target.theta));
    let flipped = Vector2::new(
        -m.line.x - target.rho,
        wrap_angle(m.line.y + PI - target.theta),
    );
    let (r, sign) = if flipped.y.abs() < same.y.abs() {
        (flipped, -1.0)
    } else {
        (same, 1.0)
    };
    let mut pose_jacobian = m.pose_jacobian;
    let mut line_jacobian = m.line_jacobian;
    pose_jacobian.row_mut(0).scale_mut(sign);
    line_jacobian.row_mut(0).scale_mut(sign);
    let covariance =
        line_jacobian * current.covariance * line_jacobian.transpose() + target.covariance;
    (r, pose_jacobian, covariance)
}

/// Mahalanobis distance of a residual, `None` when its covariance is not positive definite.
fn distance(r: &Vector2<f64>, covariance: &Matrix2<f64>) -> Option<f64> {
    Some(r.dot(&Cholesky::new(*covariance)?.solve(r)))
}

/// One-to-one matches `(current, previous)` whose residual under `prior`, its uncertainty
/// included, passes `gate` (chi-square, 2 dof); the closest first. A line with two
/// candidates is left out: parallel walls a step apart (the sides of niches and doors
/// along a corridor) alias, and one wrong match moves the robot along the corridor.
fn associate(
    previous: &[LineObservation],
    current: &[LineObservation],
    prior: &Prior,
    gate: f64,
) -> Vec<(usize, usize)> {
    let mut candidates = Vec::new();
    for (i, c) in current.iter().enumerate() {
        let mut found = None;
        let mut count = 0;
        for (j, p) in previous.iter().enumerate() {
            let (r, g, covariance) = residual(c, p, &prior.delta);
            let with_prior = covariance + g * prior.covariance * g.transpose();
            if let Some(d) = distance(&r, &with_prior)
                && d <= gate
            {
                found = Some((d, i, j));
                count += 1;
            }
        }
        if let (Some(candidate), 1) = (found, count) {
            candidates.push(candidate);
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut matches: Vec<(usize, usize)> = Vec::new();
    for (_, i, j) in candidates {
        if matches.iter().all(|&(a, b)| a != i && b != j) {
            matches.push((i, j));
        }
    }
    matches
}

/// The maximum a posteriori motion from matched lines and the prior, by Gauss-Newton from
/// the prior, with its covariance.
fn solve(
    previous: &[LineObservation],
    current: &[LineObservation],
    matches: &[(usize, usize)],
    prior: &Prior,
) -> Option<(Pose2, Matrix3<f64>)> {
    let prior_information = Cholesky::new(prior.covariance)?.inverse();
    let normal_equations = |t: &Pose2| -> Option<(Matrix3<f64>, Vector3<f64>)> {
        let offset = Vector3::new(
            t.x - prior.delta.x,
            t.y - prior.delta.y,
            wrap_angle(t.yaw - prior.delta.yaw),
        );
        let mut information = prior_information;
        let mut gradient = prior_information * offset;
        for &(i, j) in matches {
            let (r, g, covariance) = residual(&current[i], &previous[j], t);
            let weight = Cholesky::new(covariance)?.inverse();
            information += g.transpose() * weight * g;
            gradient += g.transpose() * weight * r;
        }
        Some((information, gradient))
    };
    gauss_newton(prior.delta, normal_equations)
}

/// The motion `previous_from_current` from the scans' lines and the prior, with its
/// covariance and the number of lines that fixed it; `None` without a matched line.
/// Matches are made under the prior, then made again under the first estimate (a wrong
/// match the prior let through no longer fits) and the motion solved once more.
pub(crate) fn fit(
    previous: &[LineObservation],
    current: &[LineObservation],
    prior: &Prior,
    gate: f64,
) -> Option<(Pose2, Matrix3<f64>, usize)> {
    let matches = associate(previous, current, prior, gate);
    if matches.is_empty() {
        return None;
    }
    let (first, _) = solve(previous, current, &matches, prior)?;
    let settled = Prior {
        delta: first,
        covariance: prior.covariance,
    };
    let matches: Vec<_> = associate(previous, current, &settled, gate)
        .into_iter()
        .filter(|&(i, j)| {
            let (r, _, covariance) = residual(&current[i], &previous[j], &first);
            distance(&r, &covariance).is_some_and(|d| d <= gate)
        })
        .collect();
    if matches.is_empty() {
        return None;
    }
    let (estimate, covariance) = solve(previous, current, &matches, prior)?;
    Some((estimate, covariance, matches.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `line` (in the previous frame) as seen from `previous_from_current`.
    fn seen_from(t: &Pose2, rho: f64, theta: f64) -> LineObservation {
        // The inverse of `moved`: theta = theta' - yaw, rho = rho' - tx cos(theta') - ty sin(theta').
        let (s, c) = theta.sin_cos();
        LineObservation {
            rho: rho - t.x * c - t.y * s,
            theta: wrap_angle(theta - t.yaw),
            covariance: Matrix2::new(1e-6, 0.0, 0.0, 1e-6),
        }
    }

    fn corridor() -> Vec<LineObservation> {
        // Two walls 1 m either side of the sensor, along x, and the far end wall 20 m ahead.
        [(1.0, PI / 2.0), (1.0, -PI / 2.0), (20.0, 0.0)]
            .iter()
            .map(|&(rho, theta)| LineObservation {
                rho,
                theta,
                covariance: Matrix2::new(1e-6, 0.0, 0.0, 1e-6),
            })
            .collect()
    }

    fn prior(delta: Pose2, sigma_xy: f64, sigma_yaw: f64) -> Prior {
        Prior {
            delta,
            covariance: Matrix3::from_diagonal(&Vector3::new(
                sigma_xy * sigma_xy,
                sigma_xy * sigma_xy,
                sigma_yaw * sigma_yaw,
            )),
        }
    }

    #[test]
    fn moved_lines_round_trip_and_jacobians_match_finite_differences() {
        let t = Pose2::new(0.3, -0.2, 0.4);
        let line = seen_from(&t, 2.0, 0.7);
        let m = moved(&line, &t);
        assert!((m.line.x - 2.0).abs() < 1e-12 && (wrap_angle(m.line.y - 0.7)).abs() < 1e-12);
        let h = 1e-7;
        for k in 0..3 {
            let mut shifted = t;
            match k {
                0 => shifted.x += h,
                1 => shifted.y += h,
                _ => shifted.yaw += h,
            }
            let numeric = (moved(&line, &shifted).line - m.line) / h;
            for row in 0..2 {
                assert!((numeric[row] - m.pose_jacobian[(row, k)]).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn walls_fix_heading_and_offset_and_the_prior_the_rest() {
        let previous = corridor();
        // The robot moved 0.1 m along the corridor, 2 cm across and turned 0.03 rad; the
        // prior (constant velocity) says 0.12 m straight on.
        let truth = Pose2::new(0.1, 0.02, 0.03);
        let current: Vec<_> = previous
            .iter()
            .map(|l| seen_from(&truth, l.rho, l.theta))
            .collect();
        let belief = prior(Pose2::new(0.12, 0.0, 0.0), 0.25, 0.25);
        let (estimate, covariance, lines) = fit(&previous, &current, &belief, 13.8).unwrap();
        assert_eq!(lines, 3);
        assert!((estimate.yaw - truth.yaw).abs() < 1e-4, "{estimate:?}");
        assert!((estimate.y - truth.y).abs() < 1e-3, "{estimate:?}");
        // The end wall sees the advance too.
        assert!((estimate.x - truth.x).abs() < 1e-3, "{estimate:?}");
        assert!(covariance[(2, 2)] < 1e-5);

        // Without the end wall, the advance along the corridor is the prior's.
        let (estimate, covariance, lines) =
            fit(&previous[..2], &current[..2], &belief, 13.8).unwrap();
        assert_eq!(lines, 2);
        assert!((estimate.yaw - truth.yaw).abs() < 1e-4);
        assert!((estimate.y - truth.y).abs() < 5e-3, "{estimate:?}");
        assert!((estimate.x - 0.12).abs() < 5e-3, "{estimate:?}");
        assert!(covariance[(0, 0)] > 100.0 * covariance[(1, 1)]);
    }

    #[test]
    fn a_line_through_the_sensor_matches_across_its_flip() {
        // A wall through the sensor's origin: a small motion flips the sign of rho.
        let previous = vec![LineObservation {
            rho: 0.005,
            theta: 0.3,
            covariance: Matrix2::new(1e-6, 0.0, 0.0, 1e-6),
        }];
        let truth = Pose2::new(0.02, 0.0, 0.01);
        let seen = seen_from(&truth, 0.005, 0.3);
        // The extractor reports rho >= 0.
        let current = vec![if seen.rho < 0.0 {
            LineObservation {
                rho: -seen.rho,
                theta: wrap_angle(seen.theta + PI),
                ..seen
            }
        } else {
            seen
        }];
        assert!(current[0].rho >= 0.0);
        let belief = prior(Pose2::IDENTITY, 0.05, 0.05);
        let (estimate, _, lines) = fit(&previous, &current, &belief, 13.8).unwrap();
        assert_eq!(lines, 1);
        assert!((estimate.yaw - truth.yaw).abs() < 1e-4, "{estimate:?}");
    }

    #[test]
    fn lines_the_prior_rules_out_are_not_matched() {
        let previous = corridor();
        // Seen after a quarter turn: no line is where the prior expects one.
        let truth = Pose2::new(0.0, 0.0, PI / 2.0);
        let current: Vec<_> = previous
            .iter()
            .map(|l| seen_from(&truth, l.rho, l.theta))
            .collect();
        let belief = prior(Pose2::IDENTITY, 0.05, 0.05);
        assert!(fit(&previous, &current, &belief, 13.8).is_none());
    }
}
