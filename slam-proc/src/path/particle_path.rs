//! Each particle's whole path, shared with its ancestors' copies.
//!
//! FastSLAM's answer is a particle's path together with its map: the map was built from
//! those poses, so a loop that closes corrects the whole path, which the per-scan mean of
//! the particles never sees again. Particles keep a pose at each scan that updated them
//! (the robot had moved, see `SlamConfig::update_min_distance`); the scans between are
//! placed from it by the front end's motion, held once for all particles ([`ScanLog`]). A
//! resampled copy shares its parent's path up to the split, so the storage is the
//! particles' family tree, whose branches die out with the particles that are not
//! resampled: a long run costs memory by the distance it drove, not by its scans.
//!
//! A particle that closes a loop by a revisit jumps back onto its old map; the poses since it
//! last saw that part of the map carry the drift the jump undoes. Each such jump is kept with
//! the path, and [`Path::smoothed`] spreads it back over those poses in proportion to the
//! path length, as the drift grew: the rotation first, then what is left of the
//! translation. The map stays as it was built; the smoothed path is the trajectory.

use std::sync::Arc;

use slam_geom::{Pose2, StampedPose, wrap_angle};

use crate::path::pose_graph::{self, GraphNoise};

/// A loop closed at a pose: the pose the particle had drifted to before the jump, and the
/// poses that last saw the old corners it landed on.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Closure {
    /// Indices in the path of the poses that last saw the old corners the revisit paired,
    /// in increasing order, each once; never empty. Each ties its pose to the landed one:
    /// both saw a corner where the map has it.
    ties: Vec<usize>,
    /// The pose before the jump.
    pub drifted: Pose2,
}

impl Closure {
    /// The closure of a jump from `drifted` onto old corners last seen at the path's
    /// indices `ties` (in any order, repeats allowed); `None` without a tie.
    pub fn new(mut ties: Vec<usize>, drifted: Pose2) -> Option<Self> {
        ties.sort_unstable();
        ties.dedup();
        (!ties.is_empty()).then_some(Self { ties, drifted })
    }

    /// The poses tied to the landed one, earliest first.
    pub fn ties(&self) -> &[usize] {
        &self.ties
    }

    /// The first pose of the drift the jump undoes: the last that saw one of the old
    /// corners. The poses before it saw corners that the landed pose finds where they
    /// left them, so whatever they drifted the map drifted with them; a loop that an
    /// earlier closure had pinned on its way is not bent again.
    pub fn drift_start(&self) -> usize {
        self.ties[self.ties.len() - 1]
    }
}

/// The front end's pose at every scan, one copy for all particles. A particle keeps a pose
/// of its own only at the scans that updated it (where the robot had moved); a scan between
/// two of those is placed from the last one kept by the front end's motion since, so a
/// robot standing still adds nothing to any particle's path.
#[derive(Debug, Clone, Default)]
pub(crate) struct ScanLog {
    poses: Vec<StampedPose>,
}

impl ScanLog {
    /// The next scan: its stamp and the front end's pose there.
    pub fn push(&mut self, stamp_ns: u64, front_end: Pose2) {
        self.poses.push(StampedPose {
            stamp_ns,
            pose: front_end,
        });
    }

    /// Scan `scan` placed as the front end moved from scan `kept`, which had `pose`.
    fn place(&self, kept: usize, pose: &Pose2, scan: usize) -> Option<StampedPose> {
        let (from, to) = (self.poses.get(kept)?, self.poses.get(scan)?);
        Some(StampedPose {
            stamp_ns: to.stamp_ns,
            pose: pose.compose(&from.pose.inverse().compose(&to.pose)),
        })
    }
}

#[derive(Debug)]
struct Node {
    /// The scan this pose is of.
    scan: usize,
    pose: StampedPose,
    closure: Option<Closure>,
    previous: Option<Arc<Node>>,
}

impl Drop for Node {
    /// Frees a chain that nothing else holds one node at a time: dropped recursively, a
    /// path of a long run (hundreds of thousands of scans) would overflow the stack.
    fn drop(&mut self) {
        let mut next = self.previous.take();
        while let Some(node) = next {
            match Arc::try_unwrap(node) {
                Ok(mut node) => next = node.previous.take(),
                Err(_shared) => break,
            }
        }
    }
}

/// A particle's path; cloning it shares every pose so far.
#[derive(Debug, Clone, Default)]
pub(crate) struct Path {
    last: Option<Arc<Node>>,
    /// Scans the path reaches, kept poses or not.
    len: usize,
}

impl Path {
    /// The particle's pose at the next scan, kept.
    pub fn push(&mut self, pose: StampedPose, closure: Option<Closure>) {
        let previous = self.last.take();
        self.last = Some(Arc::new(Node {
            scan: self.len,
            pose,
            closure,
            previous,
        }));
        self.len += 1;
    }

    /// The next scan, placed by the [`ScanLog`] from the last pose kept.
    pub fn pass(&mut self) {
        self.len += 1;
    }

    /// The poses from the first scan to the last, as the particle moved.
    #[cfg(test)]
    pub fn poses(&self, log: &ScanLog) -> Vec<StampedPose> {
        self.nodes(log).0
    }

    /// The poses from the first scan to the last, the loop closures' jumps spread back over
    /// the drift they undid, all closures at once (see [`crate::path::pose_graph`]).
    pub fn smoothed(&self, noise: &GraphNoise, log: &ScanLog) -> Vec<StampedPose> {
        let (mut poses, closures) = self.nodes(log);
        pose_graph::smooth(&mut poses, &closures, noise);
        poses
    }

    /// The poses from index `from` to the last, as the particle moved.
    pub fn since(&self, from: usize, log: &ScanLog) -> Vec<StampedPose> {
        self.expand(from, log).0
    }

    /// The poses at `scans` (ascending) in the frame of the particle's map: each moved as
    /// every later loop closure moved the corners mapped from it (see
    /// `Particle::reanchor_since`), so the walls a scan saw, placed by its pose, lie where
    /// the map's corners are. `None` for a scan the path does not reach.
    pub fn map_frame_poses(&self, scans: &[usize], log: &ScanLog) -> Vec<Option<Pose2>> {
        let (raw, closures) = self.nodes(log);
        let mut poses: Vec<Option<Pose2>> =
            scans.iter().map(|&s| raw.get(s).map(|p| p.pose)).collect();
        for (at, closure) in &closures {
            let from = closure.drift_start();
            let moved_scans = from..*at;
            if !scans.iter().any(|s| moved_scans.contains(s)) {
                continue;
            }
            let Some(jump) = Closure::new(vec![0], closure.drifted) else {
                continue;
            };
            let mut moved = raw[from..=*at].to_vec();
            spread(&mut moved, *at - from, &jump);
            for (pose, &s) in poses.iter_mut().zip(scans) {
                if let Some(pose) = pose
                    && moved_scans.contains(&s)
                {
                    let correction = moved[s - from].pose.compose(&raw[s].pose.inverse());
                    *pose = correction.compose(pose);
                }
            }
        }
        poses
    }

    /// The number of loop closures kept with the path.
    pub fn closures(&self) -> usize {
        let mut count = 0;
        let mut node = self.last.as_deref();
        while let Some(n) = node {
            count += usize::from(n.closure.is_some());
            node = n.previous.as_deref();
        }
        count
    }

    /// The poses in order, and the closures with the index of their pose, in order.
    fn nodes(&self, log: &ScanLog) -> (Vec<StampedPose>, Vec<(usize, Closure)>) {
        self.expand(0, log)
    }

    /// The poses from scan `from` on, each scan without a kept pose placed from the last
    /// one kept before it, and the closures at those scans with their scan, in order.
    fn expand(&self, from: usize, log: &ScanLog) -> (Vec<StampedPose>, Vec<(usize, Closure)>) {
        let mut kept: Vec<&Node> = Vec::new();
        let mut node = self.last.as_deref();
        while let Some(n) = node {
            kept.push(n);
            if n.scan <= from {
                break;
            }
            node = n.previous.as_deref();
        }
        kept.reverse();
        let mut poses = Vec::with_capacity(self.len.saturating_sub(from));
        let mut closures = Vec::new();
        for (k, n) in kept.iter().enumerate() {
            let end = kept.get(k + 1).map_or(self.len, |next| next.scan);
            if let Some(closure) = &n.closure
                && n.scan >= from
            {
                closures.push((n.scan, closure.clone()));
            }
            for scan in from.max(n.scan)..end {
                let placed = if scan == n.scan {
                    Some(n.pose)
                } else {
                    log.place(n.scan, &n.pose.pose, scan)
                };
                poses.extend(placed);
            }
        }
        (poses, closures)
    }
}

/// Spreads the jump at `poses[at]` (from `closure.drifted` to where it landed) over the poses
/// from the closure's drift start on: each step turns by its share of the rotation (its
/// share of the path length), then each pose moves by its share of the translation left at
/// the end.
pub(crate) fn spread(poses: &mut [StampedPose], at: usize, closure: &Closure) {
    let from = closure.drift_start();
    if from >= at || at >= poses.len() {
        return;
    }
    let target = poses[at].pose;
    // The chain from `from` to the drifted pose, and its cumulative length.
    let chain: Vec<Pose2> = poses[from..at]
        .iter()
        .map(|p| p.pose)
        .chain(std::iter::once(closure.drifted))
        .collect();
    let mut lengths = Vec::with_capacity(chain.len());
    let mut total = 0.0;
    lengths.push(0.0);
    for pair in chain.windows(2) {
        total += pair[0].between(&pair[1]).translation_norm();
        lengths.push(total);
    }
    let steps = chain.len() - 1;
    let share = |i: usize| {
        if total > 0.0 {
            lengths[i] / total
        } else {
            i as f64 / steps as f64
        }
    };
    let turn = wrap_angle(target.yaw - closure.drifted.yaw);
    let mut turned = Vec::with_capacity(chain.len());
    turned.push(chain[0]);
    for i in 0..steps {
        let step = chain[i].between(&chain[i + 1]);
        let step = Pose2::new(step.x, step.y, step.yaw + (share(i + 1) - share(i)) * turn);
        turned.push(turned[i].compose(&step));
    }
    let (dx, dy) = (target.x - turned[steps].x, target.y - turned[steps].y);
    for (i, pose) in turned.iter().enumerate().take(steps).skip(1) {
        let t = share(i);
        poses[from + i].pose = Pose2::new(pose.x + t * dx, pose.y + t * dy, pose.yaw);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(seq: u64) -> StampedPose {
        StampedPose {
            stamp_ns: seq * 25_000_000,
            pose: Pose2::new(seq as f64, 0.0, 0.0),
        }
    }

    #[test]
    fn copies_share_the_past_and_keep_their_own_future() {
        let mut parent = Path::default();
        for seq in 0..3 {
            parent.push(pose(seq), None);
        }
        let mut child = parent.clone();
        child.push(pose(10), None);
        parent.push(pose(3), None);
        let seqs = |p: &Path| {
            p.poses(&ScanLog::default())
                .iter()
                .map(|p| p.pose.x as u64)
                .collect::<Vec<_>>()
        };
        assert_eq!(seqs(&parent), [0, 1, 2, 3]);
        assert_eq!(seqs(&child), [0, 1, 2, 10]);
        assert_eq!((parent.len, child.len), (4, 4));
        // The shared part is one chain, not two.
        let (Some(a), Some(b)) = (&parent.last, &child.last) else {
            panic!("paths are not empty");
        };
        let (Some(a), Some(b)) = (&a.previous, &b.previous) else {
            panic!("paths are longer than one pose");
        };
        assert!(Arc::ptr_eq(a, b));
    }

    #[test]
    fn old_poses_are_moved_into_the_map_frame_as_the_closures_moved_their_corners() {
        // Along x a metre a step; from scan 2 the path drifted 0.15 m sideways a step, and
        // at scan 6 a revisit of what scan 2 saw put it back on the line.
        let drifted = |i: usize| Pose2::new(i as f64, 0.15 * (i.max(2) - 2) as f64, 0.0);
        let mut path = Path::default();
        for i in 0..6 {
            path.push(
                StampedPose {
                    stamp_ns: i as u64,
                    pose: drifted(i),
                },
                None,
            );
        }
        path.push(
            StampedPose {
                stamp_ns: 6,
                pose: Pose2::new(6.0, 0.0, 0.0),
            },
            Closure::new(vec![2], drifted(6)),
        );
        path.push(
            StampedPose {
                stamp_ns: 7,
                pose: Pose2::new(7.0, 0.0, 0.0),
            },
            None,
        );
        let poses = path.map_frame_poses(&[1, 2, 4, 5, 6, 7, 20], &ScanLog::default());
        let on_line = |pose: Option<Pose2>, x: f64| {
            let pose = pose.expect("on the path");
            (pose.x - x).abs() < 1e-9 && pose.y.abs() < 1e-9 && pose.yaw.abs() < 1e-9
        };
        // Before the drift, and from the landing on, as they were.
        assert!(
            on_line(poses[0], 1.0) && on_line(poses[1], 2.0),
            "{poses:?}"
        );
        assert!(
            on_line(poses[4], 6.0) && on_line(poses[5], 7.0),
            "{poses:?}"
        );
        // The drifted stretch moved back as the jump was spread over it.
        assert!(
            on_line(poses[2], 4.0) && on_line(poses[3], 5.0),
            "{poses:?}"
        );
        assert_eq!(poses[6], None);
        // The path itself keeps the poses the particle had.
        assert_eq!(path.poses(&ScanLog::default())[4].pose, drifted(4));
    }

    #[test]
    fn a_loop_closure_is_spread_back_over_the_drift() {
        // A square loop of 4 x 10 steps of 1 m whose heading drifted by 0.01 rad a step; at
        // step 40 a revisit put the particle back at the start, where the true loop ends.
        let truth = |i: usize| {
            let side = (i / 10).min(3);
            let along = (i - side * 10) as f64;
            let corners = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)];
            let (cx, cy) = corners[side];
            let yaw = side as f64 * std::f64::consts::FRAC_PI_2;
            Pose2::new(
                cx + along * yaw.cos(),
                cy + along * yaw.sin(),
                wrap_angle(yaw),
            )
        };
        let mut drifted = vec![truth(0)];
        for i in 1..=40 {
            let step = truth(i - 1).between(&truth(i));
            let bias = 0.01;
            let last = drifted[i - 1];
            drifted.push(last.compose(&Pose2::new(step.x, step.y, step.yaw + bias)));
        }
        let mut path = Path::default();
        for (i, pose) in drifted.iter().enumerate().take(40) {
            path.push(
                StampedPose {
                    stamp_ns: i as u64,
                    pose: *pose,
                },
                None,
            );
        }
        let end = truth(40);
        path.push(
            StampedPose {
                stamp_ns: 40,
                pose: end,
            },
            Closure::new(vec![0], drifted[40]),
        );
        let raw = path.poses(&ScanLog::default());
        // Drift that grows with the path alone, as this loop's did.
        let noise = GraphNoise {
            xy_per_metre: 1e-4,
            xy_per_radian: 0.0,
            yaw_per_metre: 1e-5,
            yaw_per_radian: 0.0,
        };
        let smoothed = path.smoothed(&noise, &ScanLog::default());
        assert_eq!(smoothed.len(), 41);
        assert_eq!(smoothed[0].pose, raw[0].pose);
        let landed = smoothed[40].pose.between(&end);
        assert!(
            landed.translation_norm() < 1e-3 && landed.yaw.abs() < 1e-4,
            "{landed:?}"
        );
        let error = |poses: &[StampedPose]| {
            poses
                .iter()
                .enumerate()
                .map(|(i, p)| (p.pose.x - truth(i).x).hypot(p.pose.y - truth(i).y))
                .fold(0.0, f64::max)
        };
        // The drift reached metres; spread back, centimetres.
        assert!(error(&raw) > 2.0, "{}", error(&raw));
        assert!(
            error(&smoothed) < 0.05,
            "{} {}",
            error(&smoothed),
            error(&raw)
        );
        // The consecutive poses stay a step apart: no jump left.
        assert!(crate::path::steps_are_a_metre(&smoothed, 0.05));
    }

    #[test]
    fn a_very_long_path_drops_without_recursion() {
        let mut path = Path::default();
        for seq in 0..1_000_000 {
            path.push(pose(seq), None);
        }
        let copy = path.clone();
        drop(path);
        assert_eq!(copy.poses(&ScanLog::default()).len(), 1_000_000);
        drop(copy);
    }

    #[test]
    fn scans_without_a_pose_of_their_own_follow_the_front_end_from_the_last_kept() {
        // The front end: 0.1 m a scan along x, then a quarter turn in place.
        let mut log = ScanLog::default();
        let front_end = [0.0, 0.1, 0.2, 0.3].map(|x| Pose2::new(x, 0.0, 0.0));
        for (scan, pose) in front_end.iter().enumerate() {
            log.push(scan as u64, *pose);
        }
        log.push(4, Pose2::new(0.3, 0.0, std::f64::consts::FRAC_PI_2));
        // The particle keeps scans 0 and 3, a little off the front end.
        let mut path = Path::default();
        path.push(
            StampedPose {
                stamp_ns: 0,
                pose: Pose2::new(1.0, 1.0, std::f64::consts::FRAC_PI_2),
            },
            None,
        );
        path.pass();
        path.pass();
        path.push(pose(3), None);
        path.pass();
        let poses = path.poses(&log);
        assert_eq!(poses.len(), 5);
        let near = |p: StampedPose, stamp: u64, x: f64, y: f64, yaw: f64| {
            p.stamp_ns == stamp
                && (p.pose.x - x).abs() < 1e-12
                && (p.pose.y - y).abs() < 1e-12
                && (p.pose.yaw - yaw).abs() < 1e-12
        };
        let up = std::f64::consts::FRAC_PI_2;
        assert!(near(poses[1], 1, 1.0, 1.1, up), "{poses:?}");
        assert!(near(poses[2], 2, 1.0, 1.2, up), "{poses:?}");
        assert!(near(poses[3], 75_000_000, 3.0, 0.0, 0.0), "{poses:?}");
        assert!(near(poses[4], 4, 3.0, 0.0, up), "{poses:?}");
        assert_eq!(path.since(2, &log)[..2], poses[2..4]);
        // No node is kept for the scans passed.
        assert_eq!(path.last.as_ref().map(|n| n.scan), Some(3));
    }
}
