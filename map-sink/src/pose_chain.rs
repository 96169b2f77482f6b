//! A path re-solved from its own steps and from priors on some of its poses: the least-squares
//! path whose steps stay closest to the given ones while its poses meet the priors.
//!
//! Each step ties two consecutive poses and each prior one pose, so the normal equations
//! are block-tridiagonal (3 x 3 blocks): Gauss-Newton solves them by block elimination in
//! time linear in the path's length, without a sparse solver.

use nalgebra::{Matrix3, Vector3};
use slam_geom::{Pose2, wrap_angle};

/// What one pose should be, and how sure of it: information (inverse covariance) in
/// `x, y, yaw`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PosePrior {
    /// The pose's index in the path.
    pub index: usize,
    pub pose: Pose2,
    pub information: Matrix3<f64>,
}

/// Gauss-Newton steps at most.
const ITERATIONS: usize = 10;
/// A step that moves no pose by more than this (metres, radians) ends the iteration.
const CONVERGED: f64 = 1e-7;

/// The path closest to `initial`'s shape, by `steps` (`steps[i]` is pose `i + 1` seen from
/// pose `i`, of information `step_information[i]`), that meets `priors`. `None` when the
/// priors leave the path free to move as a whole (none at all) or the solve fails; the
/// caller keeps the path it had.
pub fn solve_pose_chain(
    initial: &[Pose2],
    steps: &[Pose2],
    step_information: &[Matrix3<f64>],
    priors: &[PosePrior],
) -> Option<Vec<Pose2>> {
    let n = initial.len();
    if n == 0 || steps.len() + 1 != n || step_information.len() != steps.len() || priors.is_empty()
    {
        return None;
    }
    if priors.iter().any(|p| p.index >= n) {
        return None;
    }
    let mut poses = initial.to_vec();
    for _ in 0..ITERATIONS {
        let mut diagonal = vec![Matrix3::<f64>::zeros(); n];
        let mut upper = vec![Matrix3::<f64>::zeros(); n.saturating_sub(1)];
        let mut gradient = vec![Vector3::<f64>::zeros(); n];
        for (i, step) in steps.iter().enumerate() {
            let (a, b) = (poses[i], poses[i + 1]);
            let seen = a.between(&b);
            let error = Vector3::new(
                seen.x - step.x,
                seen.y - step.y,
                wrap_angle(seen.yaw - step.yaw),
            );
            let (s, c) = a.yaw.sin_cos();
            // d seen / d a and d seen / d b, `seen = R(a.yaw)^T (b - a)`.
            let ja = Matrix3::new(-c, -s, seen.y, s, -c, -seen.x, 0.0, 0.0, -1.0);
            let jb = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
            let wa = ja.transpose() * step_information[i];
            let wb = jb.transpose() * step_information[i];
            diagonal[i] += wa * ja;
            diagonal[i + 1] += wb * jb;
            upper[i] += wa * jb;
            gradient[i] += wa * error;
            gradient[i + 1] += wb * error;
        }
        for prior in priors {
            let pose = poses[prior.index];
            let error = Vector3::new(
                pose.x - prior.pose.x,
                pose.y - prior.pose.y,
                wrap_angle(pose.yaw - prior.pose.yaw),
            );
            diagonal[prior.index] += prior.information;
            gradient[prior.index] += prior.information * error;
        }
        let update = solve_block_tridiagonal(diagonal, &upper, gradient)?;
        let mut largest: f64 = 0.0;
        for (pose, delta) in poses.iter_mut().zip(&update) {
            // The normal equations give the step that cancels the gradient: subtract it.
            *pose = Pose2::new(pose.x - delta.x, pose.y - delta.y, pose.yaw - delta.z);
            largest = largest.max(delta.amax());
        }
        if !largest.is_finite() {
            return None;
        }
        if largest < CONVERGED {
            break;
        }
    }
    Some(poses)
}

/// Solves `A x = b` for a symmetric block-tridiagonal `A` given by its diagonal blocks and
/// the blocks above them (`upper[i]` couples `i` and `i + 1`). `None` if a pivot block is
/// not positive definite.
fn solve_block_tridiagonal(
    mut diagonal: Vec<Matrix3<f64>>,
    upper: &[Matrix3<f64>],
    mut rhs: Vec<Vector3<f64>>,
) -> Option<Vec<Vector3<f64>>> {
    let n = diagonal.len();
    let mut pivots = Vec::with_capacity(n);
    for i in 0..n {
        let pivot = diagonal[i].cholesky()?;
        if i + 1 < n {
            // Eliminate block i from row i + 1.
            let factor = pivot.solve(&upper[i]).transpose();
            diagonal[i + 1] -= factor * upper[i];
            let carried = factor * rhs[i];
            rhs[i + 1] -= carried;
        }
        pivots.push(pivot);
    }
    let mut x = vec![Vector3::zeros(); n];
    for i in (0..n).rev() {
        let mut r = rhs[i];
        if i + 1 < n {
            r -= upper[i] * x[i + 1];
        }
        x[i] = pivots[i].solve(&r);
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steps_of(path: &[Pose2]) -> Vec<Pose2> {
        path.windows(2).map(|w| w[0].between(&w[1])).collect()
    }

    fn firm(pose: Pose2, index: usize) -> PosePrior {
        PosePrior {
            index,
            pose,
            information: Matrix3::identity() * 1e6,
        }
    }

    #[test]
    fn a_path_that_meets_its_priors_is_left_as_it_is() {
        let path: Vec<Pose2> = (0..20)
            .map(|i| Pose2::new(i as f64 * 0.3, (i as f64 * 0.2).sin(), i as f64 * 0.1))
            .collect();
        let priors = [firm(path[0], 0), firm(path[19], 19)];
        let steps = steps_of(&path);
        let information = vec![Matrix3::identity(); steps.len()];
        let solved = solve_pose_chain(&path, &steps, &information, &priors).expect("solvable");
        for (a, b) in solved.iter().zip(&path) {
            assert!((a.position() - b.position()).norm() < 1e-9);
            assert!(wrap_angle(a.yaw - b.yaw).abs() < 1e-9);
        }
    }

    #[test]
    fn a_loop_that_came_back_off_is_closed_and_the_error_spread_over_its_steps() {
        // A straight run out and back whose odometry drifted: its steps say it ends 0.5 m
        // to the left of where it started, but a prior puts it back at the start.
        let truth: Vec<Pose2> = (0..=10)
            .map(|i| Pose2::new(i as f64, 0.0, 0.0))
            .chain((0..=10).map(|i| Pose2::new(10.0 - i as f64, 0.0, std::f64::consts::PI)))
            .collect();
        let drifted: Vec<Pose2> = truth
            .iter()
            .enumerate()
            .map(|(i, p)| Pose2::new(p.x, p.y + 0.5 * i as f64 / 21.0, p.yaw))
            .collect();
        let priors = [firm(truth[0], 0), firm(truth[21], 21)];
        let steps = steps_of(&drifted);
        let information = vec![Matrix3::from_diagonal(&Vector3::new(1e4, 1e4, 4e4)); steps.len()];
        let solved = solve_pose_chain(&drifted, &steps, &information, &priors).expect("solvable");
        assert!((solved[21].position() - truth[21].position()).norm() < 1e-3);
        // Half way round it is off by part of the drift, not all of it and not none.
        let middle = (solved[10].position() - truth[10].position()).norm();
        let middle_before = (drifted[10].position() - truth[10].position()).norm();
        assert!(middle < middle_before, "{middle} {middle_before}");
        // Each step changed by a small, even share of the correction.
        for (s, d) in steps_of(&solved).iter().zip(steps_of(&drifted)) {
            assert!((s.position() - d.position()).norm() < 0.1, "{s:?} {d:?}");
        }
    }

    #[test]
    fn no_priors_leave_the_path_free_and_nothing_is_solved() {
        let path = [Pose2::new(0.0, 0.0, 0.0), Pose2::new(1.0, 0.0, 0.0)];
        assert_eq!(
            solve_pose_chain(&path, &steps_of(&path), &[Matrix3::identity()], &[]),
            None
        );
    }

    #[test]
    fn the_block_solver_matches_a_dense_solve() {
        let n = 5;
        let block = |k: f64| Matrix3::new(4.0 + k, 0.3, 0.1, 0.3, 5.0 + k, 0.2, 0.1, 0.2, 3.0 + k);
        let coupling = |k: f64| Matrix3::new(0.5, 0.1 * k, 0.0, 0.2, -0.4, 0.1, 0.0, 0.3, 0.2);
        let diagonal: Vec<_> = (0..n).map(|i| block(i as f64)).collect();
        let upper: Vec<_> = (0..n - 1).map(|i| coupling(i as f64)).collect();
        let rhs: Vec<_> = (0..n)
            .map(|i| Vector3::new(i as f64, 1.0 - i as f64, 0.5))
            .collect();
        let mut dense = nalgebra::DMatrix::<f64>::zeros(3 * n, 3 * n);
        for i in 0..n {
            dense
                .fixed_view_mut::<3, 3>(3 * i, 3 * i)
                .copy_from(&diagonal[i]);
            if i + 1 < n {
                dense
                    .fixed_view_mut::<3, 3>(3 * i, 3 * i + 3)
                    .copy_from(&upper[i]);
                dense
                    .fixed_view_mut::<3, 3>(3 * i + 3, 3 * i)
                    .copy_from(&upper[i].transpose());
            }
        }
        let b = nalgebra::DVector::from_iterator(3 * n, rhs.iter().flat_map(|v| v.iter().copied()));
        let expected = dense.lu().solve(&b).expect("invertible");
        let x = solve_block_tridiagonal(diagonal, &upper, rhs).expect("positive definite");
        for i in 0..n {
            for k in 0..3 {
                assert!((x[i][k] - expected[3 * i + k]).abs() < 1e-9);
            }
        }
    }
}
