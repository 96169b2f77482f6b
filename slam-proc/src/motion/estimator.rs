//! The motion between consecutive scans from matched corners (or, short of them, lines).
//!
//! 1. A prior: the odometry increment when the robot has odometry, else the last motion
//!    at constant velocity (scaled to the scan interval), with a generous covariance. The
//!    last motion is the filter's posterior increment, which the map has corrected, not
//!    the last fit: a wrong fit must not repeat through a stretch without corners.
//! 2. Candidate matches: every pair of corners (current, previous) whose 4-D Mahalanobis
//!    distance under the prior passes a chi-square gate. The opening angle does not change
//!    with motion, so it gates sharply; position and heading gate through the prior.
//! 3. RANSAC over every pair of candidates: each minimal hypothesis is fitted, its inliers
//!    counted one-to-one, and the best is refitted on its inliers (weighted Kabsch, then
//!    Gauss-Newton with headings and the prior, so the prior is fused with the fit, and
//!    with the wall lines that match under the fit: corners close together fix the
//!    heading poorly, long walls well).
//! 4. Fewer than two consistent matches, or a fit beyond the per-step limits: the wall
//!    lines matched under the prior, fused with it ([`crate::motion::line_motion`]); without a
//!    line either, the prior.

use nalgebra::{Cholesky, Matrix3, Matrix4, Matrix4x3, Vector2, Vector3, Vector4};

use crate::filter::observation::{OdometryInput, Prepared};
use crate::math::chi2::quantile_even;
use crate::motion::line_motion;
use crate::rigid_fit::{Prior, normal_equations, refine};
use slam_geom::MeasuredLine;
use slam_geom::Pose2;
use slam_geom::align_se2;
use slam_geom::wrap_angle;

/// Largest believable translation between consecutive scans, metres: a ground robot or a
/// UAV steps up to about 0.2 m between scans at 10-40 Hz, so a corner fit beyond this is a
/// wrong match and the prior is used instead.
const MAX_TRANSLATION: f64 = 0.5;
/// Largest believable rotation between consecutive scans, radians (as above, for turns).
const MAX_ROTATION: f64 = 0.5;
/// Standard deviation of the constant-velocity prior's translation, metres. Generous: it
/// only has to keep the true matches inside the gate.
const PRIOR_SIGMA_XY: f64 = 0.25;
/// Standard deviation of the constant-velocity prior's rotation, radians (as generous).
const PRIOR_SIGMA_YAW: f64 = 0.25;
/// Standard deviation of the prior's translation when wall lines are matched between
/// consecutive scans, metres (at most the prior's own). Lines match on two numbers, not four
/// like corners, and parallel walls alias: they need a tighter prior.
const LINE_PRIOR_SIGMA_XY: f64 = 0.05;
/// Standard deviation of the prior's rotation for line matching, radians.
const LINE_PRIOR_SIGMA_YAW: f64 = 0.05;
/// Gate probability for candidate matches between consecutive scans under the prior: wide,
/// since a true match missed costs a fit and a false one is voted out by RANSAC.
const GATE_PROBABILITY: f64 = 0.999;
/// Gate probability for the inliers of a motion hypothesis (no prior uncertainty left).
const INLIER_PROBABILITY: f64 = 0.99;
/// Candidate matches kept per corner of the current scan, best first: bounds the robust
/// fit's hypotheses (every pair of candidates), which grow with its square.
const CANDIDATES_PER_CORNER: usize = 4;
/// Smallest standard deviation of an odometry increment's translation, metres: a reported
/// covariance that does not grow would otherwise make the prior absolute.
const ODOMETRY_MIN_SIGMA_XY: f64 = 0.005;
/// Smallest standard deviation of an odometry increment's rotation, radians.
const ODOMETRY_MIN_SIGMA_YAW: f64 = 0.002;

/// The motion from the previous scan to this one (`previous_from_current`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Motion {
    pub delta: Pose2,
    pub covariance: Matrix3<f64>,
    /// What fixed it.
    pub source: MotionSource,
    /// Matches the fit used.
    pub inliers: usize,
}

/// Where a motion estimate comes from, which decides how far the particles spread.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MotionSource {
    /// Matched corners (fused with the prior): the fit's residual error.
    Corners,
    /// Matched wall lines and the prior: heading and offsets from the walls, the
    /// translation along them from the prior, which is odometry or constant velocity.
    Lines { on_odometry: bool },
    /// Odometry alone, with the covariance it reports.
    Odometry,
    /// Constant velocity alone: a guess.
    ConstantVelocity,
    /// A front end's measurement (scan matching fused with odometry), with its covariance.
    Measured,
}

/// A candidate match: current corner `current` may be previous corner `previous`.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    current: usize,
    previous: usize,
    distance: f64,
    /// Information of the residual without the prior's uncertainty, for inlier tests.
    information: Matrix4<f64>,
}

/// Keeps what the next scan's estimate needs: the last corners, motion, stamp, odometry.
#[derive(Debug, Clone)]
pub(crate) struct MotionEstimator {
    previous: Option<Vec<Prepared>>,
    previous_lines: Vec<MeasuredLine>,
    last_delta: Pose2,
    last_stamp: Option<u64>,
    last_interval: Option<u64>,
    last_odometry: Option<OdometryInput>,
    gate: f64,
    inlier_gate: f64,
    /// Gate for line matches (2 dof) under the prior.
    line_gate: f64,
}

impl MotionEstimator {
    pub fn new() -> Self {
        Self {
            previous: None,
            previous_lines: Vec::new(),
            last_delta: Pose2::IDENTITY,
            last_stamp: None,
            last_interval: None,
            last_odometry: None,
            gate: quantile_even(GATE_PROBABILITY, 4),
            line_gate: quantile_even(GATE_PROBABILITY, 2),
            inlier_gate: quantile_even(INLIER_PROBABILITY, 4),
        }
    }

    /// The motion since the previous call. The first call returns the identity: the first
    /// pose is the map frame. Corners fix it when enough match; otherwise wall lines and
    /// the prior, or the prior alone.
    pub fn estimate(
        &mut self,
        stamp_ns: u64,
        observations: &[Prepared],
        lines: &[MeasuredLine],
        odometry: Option<&OdometryInput>,
    ) -> Motion {
        let interval = self
            .last_stamp
            .and_then(|last| stamp_ns.checked_sub(last))
            .filter(|&d| d > 0);
        let (prior, prior_source) = match (odometry, &self.last_odometry) {
            (Some(now), Some(before)) => (odometry_prior(before, now), MotionSource::Odometry),
            _ => (
                self.constant_velocity_prior(interval),
                MotionSource::ConstantVelocity,
            ),
        };
        let motion = match &self.previous {
            None => Motion {
                delta: Pose2::IDENTITY,
                covariance: Matrix3::zeros(),
                source: MotionSource::Corners,
                inliers: 0,
            },
            Some(previous) => self
                .fit(previous, observations, lines, &prior)
                .or_else(|| self.fit_lines(lines, &prior, prior_source))
                .unwrap_or(Motion {
                    delta: prior.delta,
                    covariance: prior.covariance,
                    source: prior_source,
                    inliers: 0,
                }),
        };
        self.previous = Some(observations.to_vec());
        self.previous_lines.clear();
        self.previous_lines.extend_from_slice(lines);
        self.last_delta = motion.delta;
        self.last_stamp = Some(stamp_ns);
        self.last_interval = interval;
        self.last_odometry = odometry.copied();
        motion
    }

    /// Replaces the last motion by a better estimate of it: the filter's posterior
    /// increment, which the map has corrected. Without this a wrong step would repeat at
    /// constant velocity for as long as the scans have too few corners to fit.
    pub fn set_last_motion(&mut self, delta: Pose2) {
        self.last_delta = delta;
    }

    /// The last motion, scaled to this scan's interval when both intervals are known.
    fn constant_velocity_prior(&self, interval: Option<u64>) -> Prior {
        let scale = match (interval, self.last_interval) {
            // Scans can be dropped or arrive late; a velocity, not a step, is constant.
            (Some(now), Some(before)) => (now as f64 / before as f64).clamp(0.0, 4.0),
            _ => 1.0,
        };
        let d = self.last_delta;
        let (xy, yaw) = (PRIOR_SIGMA_XY, PRIOR_SIGMA_YAW);
        Prior {
            delta: Pose2::new(d.x * scale, d.y * scale, wrap_angle(d.yaw * scale)),
            covariance: Matrix3::from_diagonal(&Vector3::new(xy * xy, xy * xy, yaw * yaw)),
        }
    }

    /// A corner fit refined with the wall lines that match under it: two corners close
    /// together (the sides of a niche) fix the heading poorly, and long walls well.
    fn with_lines(
        &self,
        estimate: Pose2,
        pairs: &[(&Prepared, &Prepared)],
        lines: &[MeasuredLine],
        prior: &Prior,
    ) -> Option<(Pose2, Matrix3<f64>)> {
        if lines.is_empty() || self.previous_lines.is_empty() {
            return None;
        }
        let prior_information = Cholesky::new(prior.covariance)?.inverse();
        let around = line_prior(estimate, &prior.covariance);
        let (refined, covariance, _) = line_motion::refine(
            &self.previous_lines,
            lines,
            &around,
            self.line_gate,
            self.gate,
            |t| Some(normal_equations(t, pairs, prior, &prior_information)),
        )?;
        Some((refined, covariance))
    }

    /// The motion from the wall lines of this scan and the previous one, with the prior.
    fn fit_lines(
        &self,
        lines: &[MeasuredLine],
        prior: &Prior,
        prior_source: MotionSource,
    ) -> Option<Motion> {
        let tight = line_prior(prior.delta, &prior.covariance);
        let (delta, covariance, matched) = line_motion::fit(
            &self.previous_lines,
            lines,
            &tight,
            self.line_gate,
            self.gate,
        )?;
        within_limits(&delta).then_some(Motion {
            delta,
            covariance,
            source: MotionSource::Lines {
                on_odometry: prior_source == MotionSource::Odometry,
            },
            inliers: matched,
        })
    }

    fn fit(
        &self,
        previous: &[Prepared],
        current: &[Prepared],
        lines: &[MeasuredLine],
        prior: &Prior,
    ) -> Option<Motion> {
        let candidates = self.candidates(previous, current, prior);
        let mut best: Option<(usize, f64, Pose2)> = None;
        let mut matched = Vec::new();
        for (i, a) in candidates.iter().enumerate() {
            for b in &candidates[i + 1..] {
                if a.current == b.current || a.previous == b.previous {
                    continue;
                }
                let points = [
                    (xy(&current[a.current]), xy(&previous[a.previous]), 1.0),
                    (xy(&current[b.current]), xy(&previous[b.previous]), 1.0),
                ];
                let Some(hypothesis) = align_se2(&points).map(|fit| fit.to_pose()) else {
                    continue;
                };
                if !within_limits(&hypothesis) {
                    continue;
                }
                let cost = self.inliers(&hypothesis, previous, current, &candidates, &mut matched);
                let better = best.is_none_or(|(count, best_cost, _)| {
                    matched.len() > count || (matched.len() == count && cost < best_cost)
                });
                if better {
                    best = Some((matched.len(), cost, hypothesis));
                }
            }
        }
        let (_, _, mut estimate) = best?;
        let mut covariance = Matrix3::zeros();
        // Refit on the inliers; the refined transform may gain or lose a match, so refit
        // once more on the inliers it has. The fit depends on nothing but the inliers:
        // when they stay the same, the second round would repeat the first.
        let mut fitted: Vec<(usize, usize)> = Vec::new();
        for _ in 0..2 {
            self.inliers(&estimate, previous, current, &candidates, &mut matched);
            if matched.len() < 2 {
                return None;
            }
            if matched
                .iter()
                .map(|c| (c.current, c.previous))
                .eq(fitted.iter().copied())
            {
                break;
            }
            fitted.clear();
            fitted.extend(matched.iter().map(|c| (c.current, c.previous)));
            let points: Vec<_> = matched
                .iter()
                .map(|c| {
                    let (s, t) = (&current[c.current], &previous[c.previous]);
                    let variance = s.covariance[(0, 0)]
                        + s.covariance[(1, 1)]
                        + t.covariance[(0, 0)]
                        + t.covariance[(1, 1)];
                    (xy(s), xy(t), 1.0 / variance)
                })
                .collect();
            let start = align_se2(&points)?.to_pose();
            let pairs: Vec<_> = matched
                .iter()
                .map(|c| (&previous[c.previous], &current[c.current]))
                .collect();
            (estimate, covariance) = refine(start, &pairs, prior)?;
            // In both rounds: the second round's inliers are then chosen under the
            // estimate the walls have steadied.
            if let Some((refined, refined_covariance)) =
                self.with_lines(estimate, &pairs, lines, prior)
            {
                (estimate, covariance) = (refined, refined_covariance);
            }
        }
        within_limits(&estimate).then_some(Motion {
            delta: estimate,
            covariance,
            source: MotionSource::Corners,
            inliers: matched.len(),
        })
    }

    /// Candidate matches under the prior, grouped by current corner, best first, at most
    /// [`CANDIDATES_PER_CORNER`] each.
    fn candidates(
        &self,
        previous: &[Prepared],
        current: &[Prepared],
        prior: &Prior,
    ) -> Vec<Candidate> {
        let u = prior.delta;
        let (s, c) = u.yaw.sin_cos();
        let mut rotation = Matrix4::identity();
        rotation
            .fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&u.rotation());
        let mut candidates = Vec::new();
        let mut group = Vec::new();
        for (ci, cur) in current.iter().enumerate() {
            let predicted = predict(&u, cur);
            let rotated = rotation * cur.covariance * rotation.transpose();
            // Jacobian of the prediction with respect to the motion (tx, ty, yaw).
            let mut jacobian = Matrix4x3::zeros();
            jacobian[(0, 0)] = 1.0;
            jacobian[(1, 1)] = 1.0;
            jacobian[(0, 2)] = -s * cur.z.x - c * cur.z.y;
            jacobian[(1, 2)] = c * cur.z.x - s * cur.z.y;
            jacobian[(2, 2)] = 1.0;
            let from_prior = jacobian * prior.covariance * jacobian.transpose();
            group.clear();
            for (pi, prev) in previous.iter().enumerate() {
                let nu = residual(&prev.z, &predicted);
                let without_prior = prev.covariance + rotated;
                // The angle alone bounds the 4-D distance from below: a cheap exact reject.
                if nu.w * nu.w > self.gate * without_prior[(3, 3)] {
                    continue;
                }
                let Some(distance) = mahalanobis(&nu, &(without_prior + from_prior)) else {
                    continue;
                };
                if distance > self.gate {
                    continue;
                }
                let Some(information) = Cholesky::new(without_prior).map(|ch| ch.inverse()) else {
                    continue;
                };
                group.push(Candidate {
                    current: ci,
                    previous: pi,
                    distance,
                    information,
                });
            }
            group.sort_by(|a, b| a.distance.total_cmp(&b.distance));
            candidates.extend(group.iter().take(CANDIDATES_PER_CORNER));
        }
        candidates
    }

    /// The one-to-one inliers of `hypothesis` among `candidates` into `matched` (greedy per
    /// current corner, best residual first); returns their summed squared distance.
    fn inliers(
        &self,
        hypothesis: &Pose2,
        previous: &[Prepared],
        current: &[Prepared],
        candidates: &[Candidate],
        matched: &mut Vec<Candidate>,
    ) -> f64 {
        matched.clear();
        let mut cost = 0.0;
        let mut start = 0;
        while start < candidates.len() {
            let ci = candidates[start].current;
            let end = candidates[start..]
                .iter()
                .position(|c| c.current != ci)
                .map_or(candidates.len(), |n| start + n);
            let predicted = predict(hypothesis, &current[ci]);
            let mut chosen: Option<(f64, Candidate)> = None;
            for candidate in &candidates[start..end] {
                if matched.iter().any(|m| m.previous == candidate.previous) {
                    continue;
                }
                let nu = residual(&previous[candidate.previous].z, &predicted);
                let d = nu.dot(&(candidate.information * nu));
                if d <= self.inlier_gate && chosen.is_none_or(|(best, _)| d < best) {
                    chosen = Some((d, *candidate));
                }
            }
            if let Some((d, candidate)) = chosen {
                cost += d;
                matched.push(candidate);
            }
            start = end;
        }
        cost
    }
}

fn xy(p: &Prepared) -> Vector2<f64> {
    Vector2::new(p.z.x, p.z.y)
}

/// A current corner moved into the previous frame by `u`.
fn predict(u: &Pose2, current: &Prepared) -> Vector4<f64> {
    let p = u.transform(xy(current));
    Vector4::new(p.x, p.y, wrap_angle(current.z.z + u.yaw), current.z.w)
}

/// `observed - predicted`, heading and angle wrapped.
fn residual(observed: &Vector4<f64>, predicted: &Vector4<f64>) -> Vector4<f64> {
    Vector4::new(
        observed.x - predicted.x,
        observed.y - predicted.y,
        wrap_angle(observed.z - predicted.z),
        wrap_angle(observed.w - predicted.w),
    )
}

fn mahalanobis(nu: &Vector4<f64>, covariance: &Matrix4<f64>) -> Option<f64> {
    Cholesky::new(*covariance).map(|ch| nu.dot(&ch.solve(nu)))
}

/// A belief centred on `delta` for matching lines: `covariance`, but no wider than the
/// line prior. Lines match on two numbers, not four like corners, and parallel walls alias:
/// they need a tighter prior than corners.
fn line_prior(delta: Pose2, covariance: &Matrix3<f64>) -> Prior {
    let (xy, yaw) = (LINE_PRIOR_SIGMA_XY, LINE_PRIOR_SIGMA_YAW);
    let widest = Vector3::new(xy * xy, xy * xy, yaw * yaw);
    Prior {
        delta,
        covariance: Matrix3::from_fn(|i, j| {
            let c = covariance[(i, j)];
            if i == j { c.min(widest[i]) } else { c }
        }),
    }
}

fn within_limits(delta: &Pose2) -> bool {
    delta.translation_norm() <= MAX_TRANSLATION && delta.yaw.abs() <= MAX_ROTATION
}

/// The odometry increment between two readings, in the earlier robot frame. Its covariance
/// is the growth of the reported covariance over the step, rotated into that frame, its
/// diagonal floored (a covariance that does not grow would claim a perfect increment).
fn odometry_prior(before: &OdometryInput, now: &OdometryInput) -> Prior {
    let delta = before.pose.between(&now.pose);
    let growth = now.covariance - before.covariance;
    let (s, c) = before.pose.yaw.sin_cos();
    let to_robot = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
    let local = to_robot * growth * to_robot.transpose();
    let (xy, yaw) = (ODOMETRY_MIN_SIGMA_XY, ODOMETRY_MIN_SIGMA_YAW);
    let floor = Vector3::new(xy * xy, xy * xy, yaw * yaw);
    let diagonal = Vector3::from_fn(|i, _| {
        let v = local[(i, i)].abs();
        if v.is_finite() {
            v.max(floor[i])
        } else {
            floor[i]
        }
    });
    Prior {
        delta,
        covariance: Matrix3::from_diagonal(&diagonal),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corner(x: f64, y: f64, heading: f64, angle: f64) -> Prepared {
        Prepared {
            z: Vector4::new(x, y, heading, angle),
            covariance: Matrix4::from_diagonal(&Vector4::new(1e-4, 1e-4, 3e-4, 3e-4)),
        }
    }

    /// `corners` (previous frame) as seen from `delta` (the current frame).
    fn seen_from(delta: &Pose2, corners: &[Prepared]) -> Vec<Prepared> {
        let inverse = delta.inverse();
        corners
            .iter()
            .map(|c| {
                let p = inverse.transform(xy(c));
                corner(p.x, p.y, wrap_angle(c.z.z - delta.yaw), c.z.w)
            })
            .collect()
    }

    /// An estimator that has seen [`scene`] as its first scan, and that scene.
    fn after_scene() -> (MotionEstimator, Vec<Prepared>) {
        let mut estimator = MotionEstimator::new();
        let previous = scene();
        estimator.estimate(0, &previous, &[], None);
        (estimator, previous)
    }

    fn scene() -> Vec<Prepared> {
        vec![
            corner(3.0, 1.0, 0.5, 1.2),
            corner(5.0, -2.0, 2.0, 1.6),
            corner(-1.0, 4.0, -1.0, 1.9),
            corner(7.0, 3.0, 3.0, 1.4),
            corner(2.0, -5.0, -2.5, 1.0),
        ]
    }

    /// `(rho, theta)` lines (previous frame) as seen from `delta`.
    fn lines_seen_from(delta: &Pose2, lines: &[(f64, f64)]) -> Vec<MeasuredLine> {
        lines
            .iter()
            .map(|&(rho, theta)| {
                let (s, c) = theta.sin_cos();
                MeasuredLine::centred(
                    rho - delta.x * c - delta.y * s,
                    wrap_angle(theta - delta.yaw),
                    1e-6,
                    2.0,
                )
            })
            .collect()
    }

    #[test]
    fn walls_carry_the_motion_where_corners_do_not() {
        let mut estimator = MotionEstimator::new();
        // A corridor: two walls 1.2 m either side, one corner in view.
        let walls = [
            (1.2, std::f64::consts::FRAC_PI_2),
            (1.2, -std::f64::consts::FRAC_PI_2),
        ];
        let previous_corner = [corner(4.0, 1.2, -2.4, 1.57)];
        let identity = Pose2::IDENTITY;
        estimator.estimate(
            0,
            &previous_corner,
            &lines_seen_from(&identity, &walls),
            None,
        );
        // A straight step at constant velocity, then one that drifts 2 cm across and turns
        // 0.02 rad, which constant velocity cannot know and the walls see.
        let step = Pose2::new(0.1, 0.0, 0.0);
        let current = seen_from(&step, &previous_corner);
        estimator.estimate(25, &current, &lines_seen_from(&step, &walls), None);
        // The filter tells the estimator the step it made (the walls alone cannot say how
        // far along them it went).
        estimator.set_last_motion(step);
        let drift = Pose2::new(0.1, 0.02, 0.02);
        let after = step.compose(&drift);
        let motion = estimator.estimate(
            50,
            &seen_from(&after, &previous_corner),
            &lines_seen_from(&after, &walls),
            None,
        );
        assert_eq!(motion.source, MotionSource::Lines { on_odometry: false });
        assert!(
            (motion.delta.yaw - drift.yaw).abs() < 1e-3,
            "{:?}",
            motion.delta
        );
        assert!(
            (motion.delta.y - drift.y).abs() < 5e-3,
            "{:?}",
            motion.delta
        );
        // Along the walls, constant velocity.
        assert!((motion.delta.x - 0.1).abs() < 5e-3, "{:?}", motion.delta);
    }

    #[test]
    fn recovers_a_step_from_corners_despite_a_wrong_match() {
        let (mut estimator, previous) = after_scene();
        let truth = Pose2::new(0.12, 0.03, 0.15);
        let mut current = seen_from(&truth, &previous);
        // An outlier: a corner whose descriptor matches corner 0 but sits 0.4 m off.
        current[1] = corner(
            current[0].z.x + 0.4,
            current[0].z.y,
            current[0].z.z,
            current[0].z.w,
        );
        let motion = estimator.estimate(25_000_000, &current, &[], None);
        assert_eq!(motion.source, MotionSource::Corners);
        assert_eq!(motion.inliers, 4);
        assert!(
            (motion.delta.x - truth.x).abs() < 1e-3,
            "{:?}",
            motion.delta
        );
        assert!((motion.delta.y - truth.y).abs() < 1e-3);
        assert!((motion.delta.yaw - truth.yaw).abs() < 1e-3);
    }

    #[test]
    fn falls_back_to_constant_velocity_without_matches() {
        let (mut estimator, previous) = after_scene();
        let step = Pose2::new(0.1, 0.0, 0.05);
        let current = seen_from(&step, &previous);
        estimator.estimate(10, &current, &[], None);
        // Same interval, a single corner: the last step again.
        let motion = estimator.estimate(20, &current[..1], &[], None);
        assert_eq!(motion.source, MotionSource::ConstantVelocity);
        assert!((motion.delta.x - 0.1).abs() < 1e-3 && (motion.delta.yaw - 0.05).abs() < 1e-3);
        // Twice the interval: twice the step.
        let motion = estimator.estimate(40, &[], &[], None);
        assert!((motion.delta.x - 0.2).abs() < 2e-3);
    }

    #[test]
    fn odometry_is_the_prior_and_corners_correct_it() {
        let mut estimator = MotionEstimator::new();
        let previous = scene();
        let odom = |x: f64, yaw: f64, var: f64| OdometryInput {
            pose: Pose2::new(x, 1.0, yaw),
            covariance: Matrix3::identity() * var,
        };
        estimator.estimate(0, &previous, &[], Some(&odom(5.0, 0.0, 0.0)));
        let truth = Pose2::new(0.1, 0.0, 0.02);
        // Odometry says 0.15 m +- 0.1 m; the corners say 0.1 m +- 1 cm and win.
        let current = seen_from(&truth, &previous);
        let motion = estimator.estimate(10, &current, &[], Some(&odom(5.15, 0.02, 1e-2)));
        assert_eq!(motion.source, MotionSource::Corners);
        assert!(
            (motion.delta.x - truth.x).abs() < 5e-3,
            "{:?}",
            motion.delta
        );
        // Without corners the odometry increment is the motion.
        let motion = estimator.estimate(20, &[], &[], Some(&odom(5.35, 0.02, 1e-2 + 1e-4)));
        assert_eq!(motion.source, MotionSource::Odometry);
        let expected = Pose2::new(5.15, 1.0, 0.02).between(&Pose2::new(5.35, 1.0, 0.02));
        assert!(
            (motion.delta.x - expected.x).abs() < 1e-9
                && (motion.delta.y - expected.y).abs() < 1e-9
        );
        assert!(motion.delta.yaw.abs() < 1e-9);
        assert!((motion.covariance[(0, 0)] - 1e-4).abs() < 1e-12);
    }
}
