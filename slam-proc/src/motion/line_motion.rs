//! The motion between consecutive scans from their wall lines: alone where too few
//! corners match for a rigid fit (a corridor between corners), and with the corners where
//! they do (two corners close together fix the heading poorly, long walls well).
//!
//! A line `x cos(theta) + y sin(theta) = rho` of the current scan, seen from the previous
//! scan's frame through `previous_from_current = (tx, ty, yaw)`, is
//! `theta' = theta + yaw`, `rho' = rho + tx cos(theta') + ty sin(theta')`. Matched to the
//! previous scan's lines, each gives two residuals: its angle fixes the rotation, its
//! offset the translation across it. Translation along every matched line stays with the
//! prior (constant velocity or odometry), which enters the least squares as one more
//! residual, so two parallel walls give the heading and the lateral offset and the prior
//! the rest.

use nalgebra::{Cholesky, Matrix2, Matrix2x3, Matrix3, Vector2, Vector3};

use crate::rigid_fit::{Prior, gauss_newton};
use slam_geom::wrap_angle;
use slam_geom::{MeasuredLine, Pose2};

/// A line of the current scan in the previous scan's frame.
struct Moved {
    /// `(rho', theta')`.
    line: Vector2<f64>,
    /// `d (rho', theta') / d (tx, ty, yaw)`.
    pose_jacobian: Matrix2x3<f64>,
    /// `d (rho', theta') / d (rho, theta)`, which carries the line's own covariance.
    line_jacobian: Matrix2<f64>,
}

fn moved(line: &MeasuredLine, t: &Pose2) -> Moved {
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
/// (both lines' noise). A line's normal points from the sensor to the wall, i.e. against
/// the face the sensor sees, and keeps its direction when moved (the robot does not cross
/// a wall between scans): the two faces of a thin wall, a few centimetres apart but with
/// opposite normals, never match each other.
fn residual(
    current: &MeasuredLine,
    target: &MeasuredLine,
    t: &Pose2,
) -> (Vector2<f64>, Matrix2x3<f64>, Matrix2<f64>) {
    let m = moved(current, t);
    let (r, covariance) = m.residual(current, target);
    (r, m.pose_jacobian, covariance)
}

impl Moved {
    /// `moved - target` and its covariance, for the line `current` this was moved from.
    fn residual(
        &self,
        current: &MeasuredLine,
        target: &MeasuredLine,
    ) -> (Vector2<f64>, Matrix2<f64>) {
        let r = Vector2::new(
            self.line.x - target.rho,
            wrap_angle(self.line.y - target.theta),
        );
        let covariance = self.line_jacobian * current.covariance * self.line_jacobian.transpose()
            + target.covariance;
        (r, covariance)
    }
}

/// Mahalanobis distance of a residual, `None` when its covariance is not positive definite.
fn distance(r: &Vector2<f64>, covariance: &Matrix2<f64>) -> Option<f64> {
    Some(r.dot(&Cholesky::new(*covariance)?.solve(r)))
}

/// Whether two lines of one scan are one wall (pieces of it split by a doorway or a
/// gap in the points): their normal forms agree within `gate`.
fn same_wall(a: &MeasuredLine, b: &MeasuredLine, gate: f64) -> bool {
    let r = Vector2::new(a.rho - b.rho, wrap_angle(a.theta - b.theta));
    distance(&r, &(a.covariance + b.covariance)).is_some_and(|d| d <= gate)
}

/// One-to-one matches `(current, previous)` whose residual under `prior`, its uncertainty
/// included, passes `gate` (chi-square, 2 dof); the closest first. A line whose candidates
/// are different walls is left out: parallel walls a step apart (the sides of niches and
/// doors along a corridor) alias, and one wrong match moves the robot. Candidates that are
/// pieces of one wall are one candidate.
fn associate(
    previous: &[MeasuredLine],
    current: &[MeasuredLine],
    prior: &Prior,
    gate: f64,
) -> Vec<(usize, usize)> {
    let mut candidates = Vec::new();
    let mut found = Vec::new();
    // Each residual component alone bounds the 2-dof distance from below (a marginal has
    // the smaller variance): a pair whose angles, or offsets, differ by more than the gate
    // allows on that component is rejected before any 2x2 algebra. The moved line's
    // variances, prior included, are the same for every previous line.
    for (i, c) in current.iter().enumerate() {
        found.clear();
        let m = moved(c, &prior.delta);
        let g = &m.pose_jacobian;
        let moved_covariance = m.line_jacobian * c.covariance * m.line_jacobian.transpose()
            + g * prior.covariance * g.transpose();
        for (j, p) in previous.iter().enumerate() {
            let angle = wrap_angle(m.line.y - p.theta);
            let offset = m.line.x - p.rho;
            if angle * angle > gate * (moved_covariance[(1, 1)] + p.covariance[(1, 1)])
                || offset * offset > gate * (moved_covariance[(0, 0)] + p.covariance[(0, 0)])
            {
                continue;
            }
            let (r, covariance) = m.residual(c, p);
            let with_prior = covariance + g * prior.covariance * g.transpose();
            if let Some(d) = distance(&r, &with_prior)
                && d <= gate
            {
                found.push((d, i, j));
            }
        }
        let Some(&best) = found
            .iter()
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)))
        else {
            continue;
        };
        if found
            .iter()
            .all(|&(_, _, j)| same_wall(&previous[j], &previous[best.2], gate))
        {
            candidates.push(best);
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

/// The normal equations `(J^T W J, J^T W r)` of a Gaussian prior on the transform at `t`.
fn prior_terms(
    prior: &Prior,
    information: &Matrix3<f64>,
    t: &Pose2,
) -> (Matrix3<f64>, Vector3<f64>) {
    let offset = Vector3::new(
        t.x - prior.delta.x,
        t.y - prior.delta.y,
        wrap_angle(t.yaw - prior.delta.yaw),
    );
    (*information, information * offset)
}

/// Adds the matched lines' residuals at `t` to normal equations; `None` when a pair's
/// covariance is not positive definite.
fn add_line_terms(
    previous: &[MeasuredLine],
    current: &[MeasuredLine],
    matches: &[(usize, usize)],
    t: &Pose2,
    information: &mut Matrix3<f64>,
    gradient: &mut Vector3<f64>,
) -> Option<()> {
    for &(i, j) in matches {
        let (r, g, covariance) = residual(&current[i], &previous[j], t);
        let weight = Cholesky::new(covariance)?.inverse();
        *information += g.transpose() * weight * g;
        *gradient += g.transpose() * weight * r;
    }
    Some(())
}

/// Matches the lines under `around` (a transform and how far it may be off), then finds by
/// Gauss-Newton the transform that best fits them together with the residuals whose normal
/// equations `others` gives (the prior; matched corners). A match that does not fit the
/// result on its own is dropped and the transform solved again. Returns the transform, its
/// covariance and the lines that fixed it; `None` without a matched line, or when the
/// result leaves `around` by more than `departure_gate` (a chi-square threshold on the
/// 3-dof departure under `around`'s covariance): nearly parallel lines that disagree pull
/// hard along directions they barely see.
pub(crate) fn refine(
    previous: &[MeasuredLine],
    current: &[MeasuredLine],
    around: &Prior,
    gate: f64,
    departure_gate: f64,
    others: impl Fn(&Pose2) -> Option<(Matrix3<f64>, Vector3<f64>)>,
) -> Option<(Pose2, Matrix3<f64>, usize)> {
    let (estimate, covariance, lines) = refine_unchecked(previous, current, around, gate, others)?;
    let departure = Vector3::new(
        estimate.x - around.delta.x,
        estimate.y - around.delta.y,
        wrap_angle(estimate.yaw - around.delta.yaw),
    );
    let d = departure.dot(&Cholesky::new(around.covariance)?.solve(&departure));
    (d <= departure_gate).then_some((estimate, covariance, lines))
}

/// [`refine`] without the departure check.
fn refine_unchecked(
    previous: &[MeasuredLine],
    current: &[MeasuredLine],
    around: &Prior,
    gate: f64,
    others: impl Fn(&Pose2) -> Option<(Matrix3<f64>, Vector3<f64>)>,
) -> Option<(Pose2, Matrix3<f64>, usize)> {
    let solve = |matches: &[(usize, usize)]| {
        gauss_newton(around.delta, |t| {
            let (mut information, mut gradient) = others(t)?;
            add_line_terms(
                previous,
                current,
                matches,
                t,
                &mut information,
                &mut gradient,
            )?;
            Some((information, gradient))
        })
    };
    let matches = associate(previous, current, around, gate);
    if matches.is_empty() {
        return None;
    }
    let (estimate, covariance) = solve(&matches)?;
    let kept: Vec<_> = matches
        .iter()
        .copied()
        .filter(|&(i, j)| {
            let (r, _, covariance) = residual(&current[i], &previous[j], &estimate);
            distance(&r, &covariance).is_some_and(|d| d <= gate)
        })
        .collect();
    if kept.len() == matches.len() {
        return Some((estimate, covariance, kept.len()));
    }
    if kept.is_empty() {
        return None;
    }
    let (estimate, covariance) = solve(&kept)?;
    Some((estimate, covariance, kept.len()))
}

/// The motion `previous_from_current` from the scans' lines and the prior alone.
pub(crate) fn fit(
    previous: &[MeasuredLine],
    current: &[MeasuredLine],
    prior: &Prior,
    gate: f64,
    departure_gate: f64,
) -> Option<(Pose2, Matrix3<f64>, usize)> {
    let information = Cholesky::new(prior.covariance)?.inverse();
    refine(previous, current, prior, gate, departure_gate, |t| {
        Some(prior_terms(prior, &information, t))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::finite_difference::nudged;
    use std::f64::consts::PI;

    /// `line` (in the previous frame) as seen from `previous_from_current`.
    fn seen_from(t: &Pose2, rho: f64, theta: f64) -> MeasuredLine {
        // The inverse of `moved`: theta = theta' - yaw, rho = rho' - tx cos(theta') - ty sin(theta').
        let (s, c) = theta.sin_cos();
        MeasuredLine::centred(
            rho - t.x * c - t.y * s,
            wrap_angle(theta - t.yaw),
            1e-6,
            2.0,
        )
    }

    fn corridor() -> Vec<MeasuredLine> {
        // Two walls 1 m either side of the sensor, along x, and the far end wall 20 m ahead.
        [(1.0, PI / 2.0), (1.0, -PI / 2.0), (20.0, 0.0)]
            .iter()
            .map(|&(rho, theta)| MeasuredLine::centred(rho, theta, 1e-6, 2.0))
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
            let shifted = nudged(&t, k, h);
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
        let (estimate, covariance, lines) = fit(&previous, &current, &belief, 13.8, 16.3).unwrap();
        assert_eq!(lines, 3);
        assert!((estimate.yaw - truth.yaw).abs() < 1e-4, "{estimate:?}");
        assert!((estimate.y - truth.y).abs() < 1e-3, "{estimate:?}");
        // The end wall sees the advance too.
        assert!((estimate.x - truth.x).abs() < 1e-3, "{estimate:?}");
        assert!(covariance[(2, 2)] < 1e-5);

        // Without the end wall, the advance along the corridor is the prior's.
        let (estimate, covariance, lines) =
            fit(&previous[..2], &current[..2], &belief, 13.8, 16.3).unwrap();
        assert_eq!(lines, 2);
        assert!((estimate.yaw - truth.yaw).abs() < 1e-4);
        assert!((estimate.y - truth.y).abs() < 5e-3, "{estimate:?}");
        assert!((estimate.x - 0.12).abs() < 5e-3, "{estimate:?}");
        assert!(covariance[(0, 0)] > 100.0 * covariance[(1, 1)]);
    }

    #[test]
    fn the_faces_of_a_thin_wall_do_not_match() {
        // The previous scan saw the near face of a 10 cm wall 2 m ahead; after a step
        // through a doorway beside it the current scan sees its far face: the same line
        // but for 10 cm and the normal, which now points the other way.
        let previous = vec![MeasuredLine::centred(2.0, 0.0, 1e-4, 2.0)];
        let far_face = seen_from(&Pose2::new(2.2, 0.0, 0.0), 2.1, 0.0);
        assert!(far_face.rho < 0.0);
        let current = vec![MeasuredLine {
            rho: -far_face.rho,
            theta: wrap_angle(far_face.theta + PI),
            ..far_face
        }];
        // A prior that would allow it, were faces not told apart.
        let belief = prior(Pose2::new(2.2, 0.0, 0.0), 0.2, 0.05);
        assert!(fit(&previous, &current, &belief, 13.8, 16.3).is_none());
        // The near face seen again does match.
        let near_face = seen_from(&Pose2::new(0.1, 0.0, 0.0), 2.0, 0.0);
        let belief = prior(Pose2::new(0.12, 0.0, 0.0), 0.05, 0.05);
        let (estimate, _, lines) = fit(&previous, &[near_face], &belief, 13.8, 16.3).unwrap();
        assert_eq!(lines, 1);
        assert!((estimate.x - 0.1).abs() < 5e-3, "{estimate:?}");
    }

    #[test]
    fn pieces_of_one_wall_match_and_parallel_walls_do_not() {
        let line = |rho: f64, theta: f64| MeasuredLine::centred(rho, theta, 1e-6, 2.0);
        let truth = Pose2::new(0.1, 0.01, 0.0);
        let current = vec![seen_from(&truth, 1.0, PI / 2.0)];
        let belief = prior(Pose2::new(0.1, 0.0, 0.0), 0.05, 0.05);
        // A wall split by a doorway into two collinear pieces: one wall.
        let pieces = vec![line(1.0, PI / 2.0), line(1.0005, PI / 2.0 + 2e-4)];
        let (estimate, _, lines) = fit(&pieces, &current, &belief, 13.8, 16.3).unwrap();
        assert_eq!(lines, 1);
        assert!((estimate.y - truth.y).abs() < 1e-3, "{estimate:?}");
        // Two parallel walls 12 cm apart, both within the prior's reach: ambiguous.
        let parallel = vec![line(1.0, PI / 2.0), line(1.12, PI / 2.0)];
        assert!(fit(&parallel, &current, &belief, 13.8, 16.3).is_none());
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
        assert!(fit(&previous, &current, &belief, 13.8, 16.3).is_none());
    }
}
