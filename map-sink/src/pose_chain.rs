//! A path re-solved from its own steps, from priors on some of its poses and from links
//! between poses farther apart: the least-squares path whose steps stay closest to the given
//! ones while its poses meet the priors and the links.
//!
//! Each step ties two consecutive poses and each prior one pose, so without links the normal
//! equations are block-tridiagonal (3 x 3 blocks): Gauss-Newton solves them by block
//! elimination in time linear in the path's length, without a sparse solver. A link between
//! poses farther apart couples blocks off that band; the equations are then solved by
//! conjugate gradients, preconditioned by the band (every link's own blocks kept, its
//! coupling left out), which the chain dominates.

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

/// Where one pose is seen from another: pose `to` in the frame of pose `from`, with its
/// information in `x, y, yaw` of that frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseLink {
    pub from: usize,
    pub to: usize,
    pub seen: Pose2,
    pub information: Matrix3<f64>,
}

/// Gauss-Newton steps at most.
const ITERATIONS: usize = 10;
/// A step that moves no pose by more than this (metres, radians) ends the iteration.
const CONVERGED: f64 = 1e-7;
/// Conjugate-gradient iterations at most for one Gauss-Newton step.
const CG_ITERATIONS: usize = 400;
/// The conjugate gradients stop once the residual is this share of the right-hand side.
const CG_TOLERANCE: f64 = 1e-10;

/// The path closest to `initial`'s shape, by `steps` (`steps[i]` is pose `i + 1` seen from
/// pose `i`, of information `step_information[i]`), that meets `priors` and `links`. `None`
/// when the priors leave the path free to move as a whole (none at all), a link or prior
/// names a pose the path does not have, or the solve fails; the caller keeps the path it
/// had.
pub fn solve_pose_chain(
    initial: &[Pose2],
    steps: &[Pose2],
    step_information: &[Matrix3<f64>],
    priors: &[PosePrior],
    links: &[PoseLink],
) -> Option<Vec<Pose2>> {
    let n = initial.len();
    if n == 0 || steps.len() + 1 != n || step_information.len() != steps.len() || priors.is_empty()
    {
        return None;
    }
    if priors.iter().any(|p| p.index >= n)
        || links
            .iter()
            .any(|l| l.from >= n || l.to >= n || l.from == l.to)
    {
        return None;
    }
    let chain = steps
        .iter()
        .zip(step_information)
        .enumerate()
        .map(|(i, (step, information))| PoseLink {
            from: i,
            to: i + 1,
            seen: *step,
            information: *information,
        });
    let every_link: Vec<PoseLink> = chain.chain(links.iter().copied()).collect();
    let mut poses = initial.to_vec();
    for _ in 0..ITERATIONS {
        let mut system = NormalEquations::new(n);
        for link in &every_link {
            system.add_link(&poses, link);
        }
        for prior in priors {
            let pose = poses[prior.index];
            let error = Vector3::new(
                pose.x - prior.pose.x,
                pose.y - prior.pose.y,
                wrap_angle(pose.yaw - prior.pose.yaw),
            );
            system.diagonal[prior.index] += prior.information;
            system.gradient[prior.index] += prior.information * error;
        }
        let update = system.solve()?;
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

/// The Gauss-Newton normal equations of a path: 3 x 3 blocks on the diagonal, above it
/// (`upper[i]` couples `i` and `i + 1`), and farther off it.
struct NormalEquations {
    diagonal: Vec<Matrix3<f64>>,
    upper: Vec<Matrix3<f64>>,
    /// `(i, j, block)`: the block in row `i`, column `j` (and its transpose in row `j`,
    /// column `i`), `|i - j| > 1`.
    far: Vec<(usize, usize, Matrix3<f64>)>,
    gradient: Vec<Vector3<f64>>,
}

impl NormalEquations {
    fn new(n: usize) -> Self {
        Self {
            diagonal: vec![Matrix3::zeros(); n],
            upper: vec![Matrix3::zeros(); n.saturating_sub(1)],
            far: Vec::new(),
            gradient: vec![Vector3::zeros(); n],
        }
    }

    /// Adds `link`'s error at `poses`, linearised.
    fn add_link(&mut self, poses: &[Pose2], link: &PoseLink) {
        let (i, j) = (link.from, link.to);
        let (a, b) = (poses[i], poses[j]);
        let seen = a.between(&b);
        let error = Vector3::new(
            seen.x - link.seen.x,
            seen.y - link.seen.y,
            wrap_angle(seen.yaw - link.seen.yaw),
        );
        let (s, c) = a.yaw.sin_cos();
        // d seen / d a and d seen / d b, `seen = R(a.yaw)^T (b - a)`.
        let ja = Matrix3::new(-c, -s, seen.y, s, -c, -seen.x, 0.0, 0.0, -1.0);
        let jb = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
        let wa = ja.transpose() * link.information;
        let wb = jb.transpose() * link.information;
        self.diagonal[i] += wa * ja;
        self.diagonal[j] += wb * jb;
        self.gradient[i] += wa * error;
        self.gradient[j] += wb * error;
        let coupling = wa * jb;
        if j == i + 1 {
            self.upper[i] += coupling;
        } else if i == j + 1 {
            self.upper[j] += coupling.transpose();
        } else {
            self.far.push((i, j, coupling));
        }
    }

    /// The update that cancels the gradient; `None` if the equations are not positive
    /// definite.
    fn solve(self) -> Option<Vec<Vector3<f64>>> {
        if self.far.is_empty() {
            let band = BlockTridiagonal::factor(self.diagonal, &self.upper)?;
            return Some(band.solve(self.gradient));
        }
        // The conjugate gradients multiply by the whole matrix: the band is factored from
        // a copy of its diagonal.
        let band = BlockTridiagonal::factor(self.diagonal.clone(), &self.upper)?;
        Some(self.conjugate_gradients(&band))
    }

    /// `A x`.
    fn times(&self, x: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut y = vec![Vector3::zeros(); x.len()];
        self.times_into(x, &mut y);
        y
    }

    /// Writes `A x` into `y`.
    fn times_into(&self, x: &[Vector3<f64>], y: &mut [Vector3<f64>]) {
        for ((y, d), x) in y.iter_mut().zip(&self.diagonal).zip(x) {
            *y = d * x;
        }
        for (i, u) in self.upper.iter().enumerate() {
            y[i] += u * x[i + 1];
            y[i + 1] += u.transpose() * x[i];
        }
        for (i, j, block) in &self.far {
            y[*i] += block * x[*j];
            y[*j] += block.transpose() * x[*i];
        }
    }

    /// `A x = gradient` by conjugate gradients preconditioned with `band` (the equations
    /// without their far blocks).
    fn conjugate_gradients(&self, band: &BlockTridiagonal) -> Vec<Vector3<f64>> {
        let dot = |a: &[Vector3<f64>], b: &[Vector3<f64>]| -> f64 {
            a.iter().zip(b).map(|(a, b)| a.dot(b)).sum()
        };
        let b = &self.gradient;
        let target = CG_TOLERANCE * CG_TOLERANCE * dot(b, b);
        let mut x = band.solve(b.clone());
        let ax = self.times(&x);
        let mut r: Vec<Vector3<f64>> = b.iter().zip(&ax).map(|(b, ax)| b - ax).collect();
        let mut z = r.clone();
        band.solve_in_place(&mut z);
        let mut p = z.clone();
        let mut ap = vec![Vector3::zeros(); p.len()];
        let mut rz = dot(&r, &z);
        for _ in 0..CG_ITERATIONS {
            if dot(&r, &r) <= target {
                break;
            }
            self.times_into(&p, &mut ap);
            let pap = dot(&p, &ap);
            if pap <= 0.0 || !pap.is_finite() {
                break;
            }
            let alpha = rz / pap;
            for ((x, r), (p, ap)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&ap)) {
                *x += alpha * p;
                *r -= alpha * ap;
            }
            z.copy_from_slice(&r);
            band.solve_in_place(&mut z);
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (p, z) in p.iter_mut().zip(&z) {
                *p = z + beta * *p;
            }
        }
        x
    }
}

/// A symmetric positive-definite block-tridiagonal matrix, factored by block elimination.
struct BlockTridiagonal {
    /// The inverses of the pivot blocks: a solve is then products only, which the
    /// conjugate gradients repeat a hundred times a step.
    inverse_pivots: Vec<Matrix3<f64>>,
    /// `factors[i]`: the multiple of row `i` taken from row `i + 1`.
    factors: Vec<Matrix3<f64>>,
    upper: Vec<Matrix3<f64>>,
}

impl BlockTridiagonal {
    /// Factors the matrix of `diagonal` blocks and the blocks above them (`upper[i]`
    /// couples `i` and `i + 1`). `None` if a pivot block is not positive definite.
    fn factor(mut diagonal: Vec<Matrix3<f64>>, upper: &[Matrix3<f64>]) -> Option<Self> {
        let n = diagonal.len();
        let mut inverse_pivots = Vec::with_capacity(n);
        let mut factors = Vec::with_capacity(n.saturating_sub(1));
        for i in 0..n {
            let pivot = diagonal[i].cholesky()?;
            if i + 1 < n {
                // Eliminate block i from row i + 1.
                let factor = pivot.solve(&upper[i]).transpose();
                diagonal[i + 1] -= factor * upper[i];
                factors.push(factor);
            }
            inverse_pivots.push(pivot.inverse());
        }
        Some(Self {
            inverse_pivots,
            factors,
            upper: upper.to_vec(),
        })
    }

    /// `x` with `A x = rhs`.
    fn solve(&self, mut rhs: Vec<Vector3<f64>>) -> Vec<Vector3<f64>> {
        self.solve_in_place(&mut rhs);
        rhs
    }

    /// Overwrites `b` with `x`, `A x = b`.
    fn solve_in_place(&self, b: &mut [Vector3<f64>]) {
        let n = self.inverse_pivots.len();
        for (i, factor) in self.factors.iter().enumerate() {
            let carried = factor * b[i];
            b[i + 1] -= carried;
        }
        for i in (0..n).rev() {
            if i + 1 < n {
                let carried = self.upper[i] * b[i + 1];
                b[i] -= carried;
            }
            b[i] = self.inverse_pivots[i] * b[i];
        }
    }
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
        let solved = solve_pose_chain(&path, &steps, &information, &priors, &[]).expect("solvable");
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
        let solved =
            solve_pose_chain(&drifted, &steps, &information, &priors, &[]).expect("solvable");
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
            solve_pose_chain(&path, &steps_of(&path), &[Matrix3::identity()], &[], &[]),
            None
        );
    }

    #[test]
    fn links_stretch_a_path_whose_steps_came_out_short() {
        // Down a corridor, steps 5 % short; links from poses well behind (as a scan sees
        // the walls its own pass drew from farther back) say how far each truly is from
        // them. Only the first pose has a prior: the links, not priors, must stretch it.
        let truth: Vec<Pose2> = (0..=40)
            .map(|i| Pose2::new(0.1 * i as f64, 0.0, 0.0))
            .collect();
        let short: Vec<Pose2> = truth
            .iter()
            .map(|p| Pose2::new(0.95 * p.x, p.y, p.yaw))
            .collect();
        let steps = steps_of(&short);
        let information = vec![Matrix3::from_diagonal(&Vector3::new(1e3, 1e3, 1e4)); 40];
        let links: Vec<PoseLink> = (10..=40)
            .map(|to| PoseLink {
                from: to - 10,
                to,
                seen: truth[to - 10].between(&truth[to]),
                information: Matrix3::identity() * 1e4,
            })
            .collect();
        let solved = solve_pose_chain(&short, &steps, &information, &[firm(short[0], 0)], &links)
            .expect("solvable");
        let length = solved[40].x - solved[0].x;
        assert!((length - 4.0).abs() < 0.02, "{length}");
        // Without the links it stays as short as its steps.
        let alone = solve_pose_chain(&short, &steps, &information, &[firm(short[0], 0)], &[])
            .expect("solvable");
        assert!((alone[40].x - 3.8).abs() < 1e-6, "{:?}", alone[40]);
    }

    #[test]
    fn a_link_that_agrees_with_where_its_poses_are_moves_nothing() {
        // A path held at both ends, with a link that says what the path already has: the
        // path must stay, however far apart the link's poses are.
        let path: Vec<Pose2> = (0..30)
            .map(|i| Pose2::new(i as f64 * 0.2, (i as f64 * 0.3).sin(), i as f64 * 0.05))
            .collect();
        let steps = steps_of(&path);
        let information = vec![Matrix3::identity() * 100.0; steps.len()];
        let links = [PoseLink {
            from: 3,
            to: 25,
            seen: path[3].between(&path[25]),
            information: Matrix3::identity() * 1e3,
        }];
        let solved = solve_pose_chain(&path, &steps, &information, &[firm(path[0], 0)], &links)
            .expect("solvable");
        for (a, b) in solved.iter().zip(&path) {
            assert!((a.position() - b.position()).norm() < 1e-6, "{a:?} {b:?}");
        }
    }

    #[test]
    fn links_to_poses_that_name_no_pose_are_refused() {
        let path = [Pose2::new(0.0, 0.0, 0.0), Pose2::new(1.0, 0.0, 0.0)];
        let link = PoseLink {
            from: 0,
            to: 2,
            seen: Pose2::new(2.0, 0.0, 0.0),
            information: Matrix3::identity(),
        };
        let steps = steps_of(&path);
        assert_eq!(
            solve_pose_chain(
                &path,
                &steps,
                &[Matrix3::identity()],
                &[firm(path[0], 0)],
                &[link]
            ),
            None
        );
    }

    #[test]
    fn the_conjugate_gradients_match_a_dense_solve() {
        let n = 8;
        let block = |k: f64| Matrix3::new(6.0 + k, 0.3, 0.1, 0.3, 7.0 + k, 0.2, 0.1, 0.2, 5.0 + k);
        let coupling = |k: f64| Matrix3::new(0.5, 0.1 * k, 0.0, 0.2, -0.4, 0.1, 0.0, 0.3, 0.2);
        let mut system = NormalEquations::new(n);
        for i in 0..n {
            system.diagonal[i] = block(i as f64);
            system.gradient[i] = Vector3::new(i as f64, 1.0 - i as f64, 0.5);
        }
        for i in 0..n - 1 {
            system.upper[i] = coupling(i as f64);
        }
        system.far = vec![(0, 5, coupling(1.0) * 0.8), (6, 2, coupling(2.0) * -0.7)];
        let mut dense = nalgebra::DMatrix::<f64>::zeros(3 * n, 3 * n);
        for i in 0..n {
            dense
                .fixed_view_mut::<3, 3>(3 * i, 3 * i)
                .copy_from(&system.diagonal[i]);
        }
        let mut place = |i: usize, j: usize, b: Matrix3<f64>| {
            let mut view = dense.fixed_view_mut::<3, 3>(3 * i, 3 * j);
            view += b;
            let mut mirror = dense.fixed_view_mut::<3, 3>(3 * j, 3 * i);
            mirror += b.transpose();
        };
        for i in 0..n - 1 {
            place(i, i + 1, system.upper[i]);
        }
        for &(i, j, b) in &system.far {
            place(i, j, b);
        }
        let rhs = nalgebra::DVector::from_iterator(
            3 * n,
            system.gradient.iter().flat_map(|v| v.iter().copied()),
        );
        let expected = dense.lu().solve(&rhs).expect("invertible");
        let x = system.solve().expect("positive definite");
        for i in 0..n {
            for k in 0..3 {
                assert!((x[i][k] - expected[3 * i + k]).abs() < 1e-8, "{i} {k}");
            }
        }
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
        let x = BlockTridiagonal::factor(diagonal, &upper)
            .expect("positive definite")
            .solve(rhs);
        for i in 0..n {
            for k in 0..3 {
                assert!((x[i][k] - expected[3 * i + k]).abs() < 1e-9);
            }
        }
    }
}
