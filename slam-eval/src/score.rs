//! The relative-pose metric of Kuemmerle et al. 2009, "On measuring the accuracy of SLAM
//! algorithms": for each ground-truth relation `delta_gt` between the poses at `t1` and
//! `t2`, the estimate's own relation `delta_est = inv(P1) * P2` is compared through
//! `e = inv(delta_gt) * delta_est`; `|e.t|` is the translational error and the angle of
//! `e`'s rotation (for planar poses `|yaw|`, wrapped) the rotational one. Only relative
//! motions are compared, so no alignment of the trajectory is needed and an error early on
//! does not count again at every later pose.

use serde::Serialize;

use crate::pose::magnitude;
use crate::relations::Relation;
use crate::stats::ErrorStats;
use crate::trajectory::Trajectory;

/// How far a pose's stamp may be from a relation's by default: 1 ms. The relations files
/// of Kuemmerle et al. round the log's stamps to 5 decimals (10 us), and scans come at
/// most at 75 Hz (13 ms apart), so 1 ms finds the scan meant and never its neighbour.
pub const DEFAULT_TOLERANCE_NS: u64 = 1_000_000;

/// A relation whose poses the trajectory lacks.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Unmatched {
    /// Line of the relations file.
    pub line: usize,
    pub t1_ns: u64,
    pub t2_ns: u64,
    /// Which ends have no pose within the tolerance: "t1", "t2" or "t1 and t2".
    pub missing: &'static str,
}

/// The score of a trajectory against a set of relations.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Score {
    /// Relations in the file.
    pub relations: usize,
    /// Relations whose both poses were found, and which the errors are over.
    pub used: usize,
    /// Relations left out because a pose was missing.
    pub unmatched: Vec<Unmatched>,
    /// How far a pose's stamp may be from a relation's, nanoseconds.
    pub tolerance_ns: u64,
    /// Translational error, metres (squared: m^2).
    pub translation_m: ErrorStats,
    /// Rotational error, degrees (squared: deg^2).
    pub rotation_deg: ErrorStats,
    /// The lengths of the estimate's relations summed, over the true ones' (translations):
    /// under 1 the estimate's path is shorter than the truth's. A front end's scale error
    /// hides in the per-relation errors, where a few per cent of a short step is below the
    /// ground truth's noise, and no loop closure undoes it: it bends nothing. `None` when
    /// the relations used move nowhere.
    pub length_ratio: Option<f64>,
}

/// Scores `trajectory` against `relations`, taking for each stamp the nearest pose within
/// `tolerance_ns`.
pub fn score(trajectory: &Trajectory, relations: &[Relation], tolerance_ns: u64) -> Score {
    let mut translation = Vec::with_capacity(relations.len());
    let mut rotation = Vec::with_capacity(relations.len());
    let mut unmatched = Vec::new();
    let (mut estimated_length, mut true_length) = (0.0, 0.0);
    for relation in relations {
        let first = trajectory.pose_at(relation.t1_ns, tolerance_ns);
        let second = trajectory.pose_at(relation.t2_ns, tolerance_ns);
        let (first, second) = match (first, second) {
            (Some(first), Some(second)) => (first, second),
            (first, second) => {
                unmatched.push(Unmatched {
                    line: relation.line,
                    t1_ns: relation.t1_ns,
                    t2_ns: relation.t2_ns,
                    missing: match (first.is_none(), second.is_none()) {
                        (true, true) => "t1 and t2",
                        (true, false) => "t1",
                        _ => "t2",
                    },
                });
                continue;
            }
        };
        let estimated = first.inverse() * second;
        estimated_length += estimated.translation.vector.norm();
        true_length += relation.delta.translation.vector.norm();
        let error = relation.delta.inverse() * estimated;
        let (t, r) = magnitude(&error);
        translation.push(t);
        rotation.push(r);
    }
    Score {
        relations: relations.len(),
        used: translation.len(),
        unmatched,
        tolerance_ns,
        translation_m: ErrorStats::of(&translation),
        rotation_deg: ErrorStats::of(&rotation).scaled(180.0 / std::f64::consts::PI),
        length_ratio: (true_length > 0.0).then(|| estimated_length / true_length),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::{Pose, from_xyz_rpy};

    const SECOND: u64 = 1_000_000_000;

    fn planar(x: f64, y: f64, yaw: f64) -> Pose {
        from_xyz_rpy([x, y, 0.0], 0.0, 0.0, yaw)
    }

    fn relation(line: usize, t1: u64, t2: u64, delta: Pose) -> Relation {
        Relation {
            line,
            t1_ns: t1 * SECOND,
            t2_ns: t2 * SECOND,
            delta,
        }
    }

    /// Poses `start * step^k` at `k` seconds, `k = 0..n`.
    fn chain(start: Pose, step: Pose, n: u64) -> Trajectory {
        let mut pose = start;
        let mut stamped = Vec::new();
        for k in 0..n {
            stamped.push((k * SECOND, pose));
            pose *= step;
        }
        Trajectory::new(stamped).unwrap()
    }

    #[test]
    fn a_perfect_trajectory_scores_zero_wherever_it_starts() {
        let step = planar(1.0, 0.2, 0.1);
        // The estimate lives in its own frame: a rigid offset must not matter.
        let trajectory = chain(planar(-7.0, 3.0, 2.5), step, 10);
        let relations = vec![
            relation(1, 0, 1, step),
            relation(2, 3, 4, step),
            relation(3, 2, 5, step * step * step),
        ];
        let score = score(&trajectory, &relations, 0);
        assert_eq!((score.relations, score.used), (3, 3));
        assert!(score.translation_m.max < 1e-12, "{score:?}");
        assert!(score.rotation_deg.max < 1e-9, "{score:?}");
    }

    #[test]
    fn a_path_shrunk_by_a_per_cent_shows_in_the_length_ratio_alone() {
        // Truth: 1 m straight ahead and a tenth of a radian per second; the estimate
        // turns the same and goes 0.99 m.
        let trajectory = chain(planar(2.0, 1.0, 0.3), planar(0.99, 0.0, 0.1), 12);
        let truth = planar(1.0, 0.0, 0.1);
        let relations: Vec<Relation> = (0..11)
            .map(|k| relation(k as usize + 1, k, k + 1, truth))
            .collect();
        let score = score(&trajectory, &relations, 0);
        assert_eq!(score.used, 11);
        let ratio = score.length_ratio.expect("the relations move");
        assert!((ratio - 0.99).abs() < 1e-12, "{ratio}");
        // Each relation is off by 1 cm: a shrink the per-relation errors barely show.
        assert!((score.translation_m.mean - 0.01).abs() < 1e-12, "{score:?}");
        let standing = vec![relation(1, 0, 1, planar(0.0, 0.0, 0.0))];
        let still = chain(planar(0.0, 0.0, 0.0), planar(0.0, 0.0, 0.0), 2);
        assert_eq!(super::score(&still, &standing, 0).length_ratio, None);
    }

    #[test]
    fn a_constant_drift_gives_the_hand_computed_error() {
        // Truth: 1 m straight ahead per second. Estimate: 1.1 m and a 0.01 rad turn.
        let truth = planar(1.0, 0.0, 0.0);
        let trajectory = chain(planar(0.0, 0.0, 0.0), planar(1.1, 0.0, 0.01), 5);
        let one_step = [relation(1, 0, 1, truth), relation(2, 3, 4, truth)];
        let score1 = score(&trajectory, &one_step, 0);
        // e = (-1, 0, 0) * (1.1, 0, 0.01) = (0.1, 0, 0.01).
        assert!((score1.translation_m.mean - 0.1).abs() < 1e-12);
        assert!(score1.translation_m.std < 1e-12);
        assert!((score1.translation_m.squared_mean - 0.01).abs() < 1e-12);
        let degrees = 0.01_f64.to_degrees(); // 0.572958 deg
        assert!((score1.rotation_deg.mean - degrees).abs() < 1e-9);
        assert!((score1.rotation_deg.squared_mean - degrees * degrees).abs() < 1e-9);

        // Over two steps: the estimate ends at (1.1 + 1.1 cos 0.01, 1.1 sin 0.01) heading
        // 0.02 = (2.199945, 0.0109998) -> e.t = (0.199945, 0.0109998), |e.t| = 0.2002474.
        let two_steps = [relation(3, 1, 3, planar(2.0, 0.0, 0.0))];
        let score2 = score(&trajectory, &two_steps, 0);
        assert!(
            (score2.translation_m.mean - 0.200_247_4).abs() < 1e-7,
            "{score2:?}"
        );
        assert!((score2.rotation_deg.mean - 0.02_f64.to_degrees()).abs() < 1e-9);

        // Both kinds together: errors 0.1, 0.1, 0.2002474.
        let all: Vec<Relation> = one_step.iter().chain(&two_steps).cloned().collect();
        let score3 = score(&trajectory, &all, 0);
        let mean = (0.1 + 0.1 + 0.200_247_4) / 3.0;
        assert!((score3.translation_m.mean - mean).abs() < 1e-7);
        let std = ((2.0 * (0.1 - mean).powi(2) + (0.200_247_4 - mean).powi(2)) / 3.0).sqrt();
        assert!((score3.translation_m.std - std).abs() < 1e-7);
    }

    #[test]
    fn relations_without_poses_are_counted_not_scored() {
        let trajectory = chain(planar(0.0, 0.0, 0.0), planar(1.0, 0.0, 0.0), 3);
        let relations = vec![
            relation(1, 0, 1, planar(1.0, 0.0, 0.0)),
            relation(2, 1, 9, planar(1.0, 0.0, 0.0)),
            relation(5, 8, 9, planar(1.0, 0.0, 0.0)),
        ];
        let mut off_by_a_bit = relations.clone();
        off_by_a_bit[0].t2_ns += 999_999;
        let score = score(&trajectory, &off_by_a_bit, 1_000_000);
        assert_eq!((score.relations, score.used), (3, 1));
        assert_eq!(score.translation_m.mean, 0.0, "matched within 1 ms");
        let missing: Vec<(usize, &str)> = score
            .unmatched
            .iter()
            .map(|u| (u.line, u.missing))
            .collect();
        assert_eq!(missing, vec![(2, "t2"), (5, "t1 and t2")]);
    }
}
