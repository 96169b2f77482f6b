//! A path's loop closures solved jointly: the path is a chain of steps, each closure ties
//! its landed pose to every pose that last saw one of the old corners it landed on, and
//! the smoothed path is the least-squares fit of both (a pose graph). Solved as LAGO does
//! for planar graphs: the headings first, a linear problem once the ties' heading offsets
//! are unwrapped against the chain, then the positions, linear once the headings are fixed.
//!
//! A chain with ties needs no sparse solver: the unknowns are the steps, each tie
//! constrains the sum of the steps it spans, and the normal equations reduce to one small
//! system over the ties (`S^T W^-1 S + C`, k x k for k ties, `S` their spans, `W` the
//! steps' information, `C` the ties' variances), whose entry for two ties is the variance
//! of the steps they share. The solution moves each step by its variance times the
//! multipliers of the ties spanning it: a step that drifts more takes more of the
//! correction, and a stretch that two loops share is bent only as far as both allow.
//!
//! Spreading each jump back on its own (see [`crate::path::particle_path::spread`]) is this
//! solution for one closure with one tie; with several, a later loop spread over a stretch
//! an earlier one had pinned to the old map would undo it.

use nalgebra::{DMatrix, DVector};
use slam_geom::{Pose2, wrap_angle};

use slam_geom::StampedPose;

use crate::path::particle_path::{Closure, spread};

/// The variances of the chain's steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GraphNoise {
    /// Translation variance of a step per metre travelled, m^2/m.
    pub xy_per_metre: f64,
    /// Translation variance of a step per radian turned, m^2/rad.
    pub xy_per_radian: f64,
    /// Heading variance of a step per metre travelled, rad^2/m.
    pub yaw_per_metre: f64,
    /// Heading variance of a step per radian turned, rad^2/rad.
    pub yaw_per_radian: f64,
}

/// The variance of a closure, as a share of the drift of the loop it closes: a revisit
/// landed the particle on its old map, and the path it built its map from meets it there,
/// as a jump spread back on its own does exactly. Near zero, so the closures are met
/// (softer, a loop's jump leaks into the poses after it: both benchmark logs measured
/// worse with closures of 1 cm, worse still of 3 cm), but not zero: two closures over the
/// same span would make the system singular.
const CLOSURE_SHARE: f64 = 1e-4;

/// A closure that another one follows within this much path (metres) is its first landing,
/// which the second corrected: the map put the robot where the second landed. Both kept as
/// ties, the two landings would disagree by the correction, and the stretch between the two
/// closures' ties (hundreds of metres long, where a short stretch between the landings is
/// what moved) would bend to make them agree.
const RELANDING_M: f64 = 2.0;

/// A step of a stopped robot has no drift, but a variance of zero would make the solve
/// singular; this keeps it invertible and, next to any real step's, rigid.
const MIN_STEP_VARIANCE: f64 = 1e-12;

/// A tie in the graph: the poses it joins (`from < at`) and the motion between them as the
/// map placed them.
struct Constraint {
    from: usize,
    at: usize,
    between: Pose2,
}

/// Smooths `poses` (as the particle moved, each closure's landed pose in place) given the
/// `closures` with the index of the pose each landed at, in the order they closed.
pub(crate) fn smooth(poses: &mut [StampedPose], closures: &[(usize, Closure)], noise: &GraphNoise) {
    let n = poses.len();
    let closures: Vec<&(usize, Closure)> = closures
        .iter()
        .filter(|(at, c)| c.ties()[0] < *at && *at < n)
        .collect();
    if closures.is_empty() {
        return;
    }
    // What each closure measured: its landed pose relative to each pose that last saw one
    // of its old corners (its ties), as the map then placed that pose. The poses between
    // two ties of one closure keep the shape the map gave them, and a later closure's
    // correction goes to the stretch that drifted, not to a loop an earlier closure had
    // already pinned. A corner map is moved with each closure's spread
    // (`CornerMap::reanchor`), so a later closure found the corners of an earlier drift
    // where the earlier spread had put them.
    let mut reference = poses.to_vec();
    let mut constraints = Vec::new();
    for (i, &(at, closure)) in closures.iter().enumerate() {
        let at = *at;
        let relanded = closures
            .get(i + 1)
            .is_some_and(|&(next, _)| path_length(&poses[at..*next]) < RELANDING_M);
        if !relanded {
            for &from in closure.ties().iter().filter(|&&from| from < at) {
                constraints.push(Constraint {
                    from,
                    at,
                    between: reference[from].pose.between(&reference[at].pose),
                });
            }
        }
        spread(&mut reference, at, closure);
    }
    // The chain's steps as the particle moved, without the jumps.
    let mut steps: Vec<Pose2> = poses
        .windows(2)
        .map(|w| w[0].pose.between(&w[1].pose))
        .collect();
    for &(at, closure) in &closures {
        steps[at - 1] = poses[at - 1].pose.between(&closure.drifted);
    }
    let variance = |per_metre: f64, per_radian: f64| -> Vec<f64> {
        steps
            .iter()
            .map(|s| {
                (per_metre * s.translation_norm() + per_radian * s.yaw.abs()).max(MIN_STEP_VARIANCE)
            })
            .collect()
    };

    // Headings: unwrapped along the chain, each closure's offset wrapped against the
    // chain's turn between its ends.
    let yaw_variance = variance(noise.yaw_per_metre, noise.yaw_per_radian);
    let mut yaw = Vec::with_capacity(n);
    yaw.push(poses[0].pose.yaw);
    for step in &steps {
        let last = yaw[yaw.len() - 1];
        yaw.push(last + step.yaw);
    }
    let misfit: Vec<f64> = constraints
        .iter()
        .map(|c| wrap_angle(c.between.yaw - (yaw[c.at] - yaw[c.from])))
        .collect();
    let Some(turns) = corrections(&constraints, &yaw_variance, &[misfit]) else {
        return;
    };
    for i in 0..steps.len() {
        yaw[i + 1] = yaw[i] + steps[i].yaw + turns[0][i];
    }

    // Positions: each step's translation turned by its solved heading.
    let xy_variance = variance(noise.xy_per_metre, noise.xy_per_radian);
    let turned: Vec<(f64, f64)> = steps
        .iter()
        .enumerate()
        .map(|(i, s)| rotate(yaw[i], s.x, s.y))
        .collect();
    let mut x = Vec::with_capacity(n);
    let mut y = Vec::with_capacity(n);
    x.push(poses[0].pose.x);
    y.push(poses[0].pose.y);
    for &(dx, dy) in &turned {
        x.push(x[x.len() - 1] + dx);
        y.push(y[y.len() - 1] + dy);
    }
    let (misfit_x, misfit_y): (Vec<f64>, Vec<f64>) = constraints
        .iter()
        .map(|c| {
            let (mx, my) = rotate(yaw[c.from], c.between.x, c.between.y);
            (mx - (x[c.at] - x[c.from]), my - (y[c.at] - y[c.from]))
        })
        .unzip();
    let Some(shifts) = corrections(&constraints, &xy_variance, &[misfit_x, misfit_y]) else {
        return;
    };
    for (i, pose) in poses.iter_mut().enumerate().skip(1) {
        x[i] = x[i - 1] + turned[i - 1].0 + shifts[0][i - 1];
        y[i] = y[i - 1] + turned[i - 1].1 + shifts[1][i - 1];
        pose.pose = Pose2::new(x[i], y[i], wrap_angle(yaw[i]));
    }
}

/// The length of the path through `poses`, metres.
fn path_length(poses: &[StampedPose]) -> f64 {
    poses
        .windows(2)
        .map(|w| w[0].pose.between(&w[1].pose).translation_norm())
        .sum()
}

/// `(x, y)` turned by `yaw`.
fn rotate(yaw: f64, x: f64, y: f64) -> (f64, f64) {
    let (s, c) = yaw.sin_cos();
    (c * x - s * y, s * x + c * y)
}

/// The least-squares corrections of the steps, one vector per entry of `misfits` (each
/// closure's measured minus the chain's sum over its span): step `i` moves by
/// `variance[i]` times the sum of the multipliers of the closures spanning it, the
/// multipliers solving `(S^T W^-1 S + C) lambda = misfit`, `C` the closures' variances.
/// `None` if that system is not positive definite (it is, for positive variances).
fn corrections(
    constraints: &[Constraint],
    variance: &[f64],
    misfits: &[Vec<f64>],
) -> Option<Vec<Vec<f64>>> {
    // The variance of the steps before each pose, for the variance two spans share.
    let mut before = Vec::with_capacity(variance.len() + 1);
    before.push(0.0);
    for v in variance {
        before.push(before[before.len() - 1] + v);
    }
    let k = constraints.len();
    let system = DMatrix::from_fn(k, k, |a, b| {
        let (ca, cb) = (&constraints[a], &constraints[b]);
        let (start, end) = (ca.from.max(cb.from), ca.at.min(cb.at));
        let shared = if end > start {
            before[end] - before[start]
        } else {
            0.0
        };
        shared * if a == b { 1.0 + CLOSURE_SHARE } else { 1.0 }
    });
    let cholesky = system.cholesky()?;
    Some(
        misfits
            .iter()
            .map(|misfit| {
                let multipliers = cholesky.solve(&DVector::from_column_slice(misfit));
                // Each closure's multiplier over the steps it spans, summed by a
                // difference array.
                let mut spanning = vec![0.0; variance.len() + 1];
                for (c, m) in constraints.iter().zip(multipliers.iter()) {
                    spanning[c.from] += m;
                    spanning[c.at] -= m;
                }
                let mut sum = 0.0;
                variance
                    .iter()
                    .zip(&spanning)
                    .map(|(v, s)| {
                        sum += s;
                        v * sum
                    })
                    .collect()
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const NOISE: GraphNoise = GraphNoise {
        xy_per_metre: 1e-4,
        xy_per_radian: 1e-4,
        yaw_per_metre: 1e-5,
        yaw_per_radian: 1e-4,
    };

    fn path_pose(i: usize, pose: Pose2) -> StampedPose {
        StampedPose {
            stamp_ns: i as u64,
            pose,
        }
    }

    /// A straight line along x, one metre a step, whose steps carry `bias` of extra turn.
    fn drifted_line(steps: usize, bias: f64) -> Vec<Pose2> {
        line_drifting_after(0, steps, bias)
    }

    /// `steps` one-metre steps along x, those after pose `straight` turning by `bias`.
    fn line_drifting_after(straight: usize, steps: usize, bias: f64) -> Vec<Pose2> {
        let mut poses = vec![Pose2::IDENTITY];
        for i in 1..=steps {
            let last = poses[i - 1];
            let turn = if i > straight { bias } else { 0.0 };
            poses.push(last.compose(&Pose2::new(1.0, 0.0, turn)));
        }
        poses
    }

    fn path_poses(raw: &[Pose2]) -> Vec<StampedPose> {
        raw.iter()
            .enumerate()
            .map(|(i, &p)| path_pose(i, p))
            .collect()
    }

    #[test]
    fn one_closure_is_met_and_spread_by_the_steps_drift() {
        // Out and back along a line whose heading drifted: the closure at the end says the
        // robot is back at the start.
        let mut poses: Vec<StampedPose> = drifted_line(10, 0.0)
            .into_iter()
            .chain((1..=10).map(|i| Pose2::new(10.0 - i as f64, 0.0, std::f64::consts::PI)))
            .enumerate()
            .map(|(i, p)| path_pose(i, p))
            .collect();
        // Headings drifted by 0.01 rad a step on the way back.
        for i in 11..=20 {
            let step = poses[i - 1].pose.between(&poses[i].pose);
            let drifted = Pose2::new(step.x, step.y, step.yaw + 0.01);
            poses[i].pose = poses[i - 1].pose.compose(&drifted);
        }
        let drifted = poses[20].pose;
        let landed = Pose2::new(0.0, 0.0, std::f64::consts::PI);
        poses[20].pose = landed;
        let closure = Closure::new(vec![0], drifted).expect("a tie");
        let mut spread_alone = poses.clone();
        spread(&mut spread_alone, 20, &closure);
        smooth(&mut poses, &[(20, closure.clone())], &NOISE);
        assert_eq!(poses[0].pose, Pose2::IDENTITY);
        // The closure holds (its variance is tiny next to the chain's)...
        let end = poses[20].pose;
        assert!(end.x.hypot(end.y) < 1e-3 && wrap_angle(end.yaw - landed.yaw).abs() < 1e-4);
        // ...and, one closure alone, the solution is the spread's.
        for (solved, spread) in poses.iter().zip(&spread_alone) {
            let d = solved.pose.between(&spread.pose);
            assert!(d.translation_norm() < 0.05 && d.yaw.abs() < 0.005, "{d:?}");
        }
    }

    #[test]
    fn a_later_closure_does_not_undo_an_earlier_one() {
        // A line of 30 one-metre steps whose heading drifted by 0.005 rad a step. At pose 20
        // the robot recognises pose 2 and lands where the straight line from there puts it;
        // it drifts on, and at pose 30 recognises pose 10, whose place the first closure's
        // spread had settled.
        let raw = drifted_line(30, 0.005);
        let line = |from: Pose2, metres: f64| from.compose(&Pose2::new(metres, 0.0, 0.0));
        let mut poses = path_poses(&raw);
        let first = Closure::new(vec![2], raw[20]).expect("a tie");
        poses[20].pose = line(raw[2], 18.0);
        for i in 21..=30 {
            let step = raw[i - 1].between(&raw[i]);
            poses[i].pose = poses[i - 1].pose.compose(&step);
        }
        let mut settled = poses.clone();
        spread(&mut settled, 20, &first);
        let second = Closure::new(vec![10], poses[30].pose).expect("a tie");
        poses[30].pose = line(settled[10].pose, 20.0);
        let closures = [(20, first), (30, second)];

        let mut sequential = poses.clone();
        for (at, closure) in &closures {
            spread(&mut sequential, *at, closure);
        }
        let mut joint = poses.clone();
        smooth(&mut joint, &closures, &NOISE);

        // How far pose `at` is from where the closure from `from` put it, metres.
        let missed = |poses: &[StampedPose], from: usize, at: usize| {
            let p = poses[from].pose.between(&poses[at].pose);
            (p.x - (at - from) as f64).hypot(p.y) + p.yaw.abs()
        };
        // Both closures met at once...
        assert!(missed(&joint, 2, 20) < 0.005, "{}", missed(&joint, 2, 20));
        assert!(missed(&joint, 10, 30) < 0.005, "{}", missed(&joint, 10, 30));
        // ...where the second jump spread on its own bends the stretch the first had fixed.
        assert!(
            missed(&sequential, 2, 20) > 0.02,
            "{}",
            missed(&sequential, 2, 20)
        );
        // No step jumps: each stays within centimetres of a metre.
        assert!(crate::path::steps_are_a_metre(&joint, 0.02));
    }

    #[test]
    fn the_stretch_between_a_closures_ties_keeps_the_shape_the_map_gave_it() {
        // A line of 30 one-metre steps, straight up to pose 18 and drifting by 0.02 rad a
        // step after it. At pose 30 the robot lands on corners last seen from poses 5 and
        // 18: the drift grew after 18, and the poses before it stay where they were.
        let raw = line_drifting_after(18, 30, 0.02);
        let mut poses = path_poses(&raw);
        let landed = Pose2::new(30.0, 0.0, 0.0);
        poses[30].pose = landed;
        let closure = Closure::new(vec![18, 5, 18], raw[30]).expect("ties");
        assert_eq!((closure.ties(), closure.drift_start()), (&[5, 18][..], 18));

        // Tied to pose 5 alone, the closure would bend the straight stretch as well.
        let mut tied_to_the_first = poses.clone();
        let first = Closure::new(vec![5], raw[30]).expect("a tie");
        smooth(&mut tied_to_the_first, &[(30, first)], &NOISE);
        let bent = tied_to_the_first[18]
            .pose
            .between(&raw[18])
            .translation_norm();
        assert!(bent > 0.02, "{bent}");

        let mut spread_alone = poses.clone();
        spread(&mut spread_alone, 30, &closure);
        smooth(&mut poses, &[(30, closure)], &NOISE);
        for solved in [&poses, &spread_alone] {
            for (i, pose) in solved.iter().enumerate().take(19) {
                let moved = pose.pose.between(&raw[i]).translation_norm();
                assert!(moved < 1e-3, "{i} {moved}");
            }
            let end = solved[30].pose.between(&landed);
            assert!(
                end.translation_norm() < 1e-3 && end.yaw.abs() < 1e-4,
                "{end:?}"
            );
            assert!(crate::path::steps_are_a_metre(solved, 0.05));
        }
    }

    #[test]
    fn a_landing_corrected_a_metre_later_leaves_the_loop_to_the_second() {
        // A straight line of 40 one-metre steps whose heading drifted by 0.002 rad a step
        // after pose 20. At pose 30 a revisit lands the robot on corners last seen from
        // pose 10, half a metre to the side of where it is; a metre on, another lands it
        // on corners last seen from pose 5, on the line. The second corrected the first;
        // kept as a tie, the first would bend the five steps between poses 5 and 10 by
        // most of the half metre.
        let raw = line_drifting_after(20, 40, 0.002);
        let mut poses = path_poses(&raw);
        let first = Closure::new(vec![10], raw[30]).expect("a tie");
        poses[30].pose = Pose2::new(30.0, 0.5, 0.0);
        let drifted = poses[30].pose.compose(&raw[30].between(&raw[31]));
        let second = Closure::new(vec![5], drifted).expect("a tie");
        poses[31].pose = Pose2::new(31.0, 0.0, 0.0);
        for i in 32..=40 {
            poses[i].pose = poses[i - 1].pose.compose(&raw[i - 1].between(&raw[i]));
        }
        smooth(&mut poses, &[(30, first), (31, second)], &NOISE);
        // The straight stretch bends only by its share of the drift...
        for (i, pose) in poses.iter().enumerate().take(21) {
            let off = pose.pose.between(&raw[i]).translation_norm();
            assert!(off < 0.05, "{i} {off}");
        }
        // ...and the second landing holds.
        let end = poses[31].pose.between(&Pose2::new(31.0, 0.0, 0.0));
        assert!(end.translation_norm() < 1e-3, "{end:?}");
    }

    #[test]
    fn no_closures_leave_the_path_as_it_is() {
        let raw = path_poses(&drifted_line(5, 0.1));
        let mut poses = raw.clone();
        smooth(&mut poses, &[], &NOISE);
        assert_eq!(poses, raw);
        // A closure that points outside the path is ignored, not a panic.
        let stray = Closure::new(vec![3], Pose2::IDENTITY).expect("a tie");
        smooth(&mut poses, &[(2, stray.clone()), (9, stray)], &NOISE);
        assert_eq!(poses, raw);
    }
}
