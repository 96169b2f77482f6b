//! The estimated trajectory: a TUM file (`stamp x y z qx qy qz qw`), as map-sink writes it.

use std::path::Path;

use crate::error::EvalError;
use slam_geom::parse_tum;

use crate::pose::{Pose, from_tum};

/// A TUM trajectory: about 100 bytes a pose.
pub const TRAJECTORY_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "trajectory",
    limit_name: "slam_eval::TRAJECTORY_INPUT",
    max_bytes: 1 << 30,
};

/// Poses sorted by stamp, each stamp once.
#[derive(Debug, Clone, Default)]
pub struct Trajectory {
    stamps_ns: Vec<u64>,
    poses: Vec<Pose>,
}

impl Trajectory {
    /// Builds a trajectory from stamped poses in any order; `Err` names the first stamp given
    /// twice (which pose would count is ambiguous).
    pub fn new(mut stamped: Vec<(u64, Pose)>) -> Result<Self, u64> {
        stamped.sort_by_key(|(stamp, _)| *stamp);
        if let Some(pair) = stamped.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(pair[0].0);
        }
        let (stamps_ns, poses) = stamped.into_iter().unzip();
        Ok(Self { stamps_ns, poses })
    }

    /// Reads a TUM file with [`slam_geom::read_tum`]'s rules (blank lines and `#` comments
    /// skipped, a last line cut short by a crash dropped).
    pub fn read_tum(path: &Path) -> Result<Self, EvalError> {
        let malformed = |line, reason| EvalError::Malformed {
            path: path.to_path_buf(),
            line,
            reason,
        };
        let text = TRAJECTORY_INPUT.read_to_string(path)?;
        let lines = parse_tum(&text).map_err(|e| malformed(e.line, e.problem.to_string()))?;
        if lines.is_empty() {
            return Err(EvalError::Empty {
                path: path.to_path_buf(),
                what: "poses",
            });
        }
        let mut stamped = Vec::with_capacity(lines.len());
        for (line, tum) in &lines {
            let pose = from_tum(tum.position, tum.orientation).ok_or_else(|| {
                malformed(
                    *line,
                    "the quaternion has no direction (zero length)".to_owned(),
                )
            })?;
            stamped.push((tum.stamp_ns, pose));
        }
        Self::new(stamped).map_err(|repeated| {
            let mut at = lines
                .iter()
                .filter(|(_, tum)| tum.stamp_ns == repeated)
                .map(|(line, _)| *line);
            let first = at.next().unwrap_or_default();
            malformed(
                at.next().unwrap_or_default(),
                format!("stamp repeats line {first}"),
            )
        })
    }

    pub fn len(&self) -> usize {
        self.poses.len()
    }

    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// Every pose with its stamp, in stamp order.
    pub fn iter(&self) -> impl Iterator<Item = (u64, &Pose)> {
        self.stamps_ns.iter().copied().zip(&self.poses)
    }

    /// The pose whose stamp is nearest to `stamp_ns`, if it is within `tolerance_ns`.
    pub fn pose_at(&self, stamp_ns: u64, tolerance_ns: u64) -> Option<&Pose> {
        let after = self.stamps_ns.partition_point(|&s| s < stamp_ns);
        let candidates = [after.checked_sub(1), Some(after)];
        candidates
            .into_iter()
            .flatten()
            .filter(|&i| i < self.stamps_ns.len())
            .map(|i| (self.stamps_ns[i].abs_diff(stamp_ns), i))
            .filter(|&(distance, _)| distance <= tolerance_ns)
            .min()
            .map(|(_, i)| &self.poses[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planar(x: f64) -> Pose {
        from_tum([x, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]).unwrap()
    }

    #[test]
    fn the_nearest_pose_within_tolerance_is_found() {
        let trajectory = Trajectory::new(vec![
            (3_000, planar(3.0)),
            (1_000, planar(1.0)),
            (2_000, planar(2.0)),
        ])
        .unwrap();
        let x = |stamp, tolerance| {
            trajectory
                .pose_at(stamp, tolerance)
                .map(|p| p.translation.vector.x)
        };
        assert_eq!(x(2_000, 0), Some(2.0), "exact");
        assert_eq!(x(2_400, 500), Some(2.0), "nearest below");
        assert_eq!(x(2_600, 500), Some(3.0), "nearest above");
        assert_eq!(x(2_500, 100), None, "none within tolerance");
        assert_eq!(x(0, 999), None, "before the start");
        assert_eq!(x(3_999, 999), Some(3.0), "after the end");
    }

    #[test]
    fn repeated_stamps_are_refused() {
        assert_eq!(
            Trajectory::new(vec![(5, planar(0.0)), (5, planar(1.0))]).err(),
            Some(5)
        );
    }
}
