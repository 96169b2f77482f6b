//! Each particle's whole path, shared with its ancestors' copies.
//!
//! FastSLAM's answer is a particle's path together with its map: the map was built from
//! those poses. Particles keep a pose at each scan that updated them (the robot had moved,
//! see `SlamConfig::update_min_distance`); the scans between are placed from it by the
//! front end's motion, held once for all particles ([`ScanLog`]). A resampled copy shares
//! its parent's path up to the split, so the storage is the particles' family tree, whose
//! branches die out with the particles that are not resampled: a long run costs memory by
//! the distance it drove, not by its scans.

use std::sync::Arc;

use slam_geom::{Pose2, StampedPose};

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
    pub fn push(&mut self, pose: StampedPose) {
        let previous = self.last.take();
        self.last = Some(Arc::new(Node {
            scan: self.len,
            pose,
            previous,
        }));
        self.len += 1;
    }

    /// The next scan, placed by the [`ScanLog`] from the last pose kept.
    pub fn pass(&mut self) {
        self.len += 1;
    }

    /// The poses from the first scan to the last, as the particle moved, each scan
    /// without a kept pose placed from the last one kept before it.
    pub fn poses(&self, log: &ScanLog) -> Vec<StampedPose> {
        let mut kept: Vec<&Node> = Vec::new();
        let mut node = self.last.as_deref();
        while let Some(n) = node {
            kept.push(n);
            node = n.previous.as_deref();
        }
        kept.reverse();
        let mut poses = Vec::with_capacity(self.len);
        for (k, n) in kept.iter().enumerate() {
            let end = kept.get(k + 1).map_or(self.len, |next| next.scan);
            for scan in n.scan..end {
                let placed = if scan == n.scan {
                    Some(n.pose)
                } else {
                    log.place(n.scan, &n.pose.pose, scan)
                };
                poses.extend(placed);
            }
        }
        poses
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
            parent.push(pose(seq));
        }
        let mut child = parent.clone();
        child.push(pose(10));
        parent.push(pose(3));
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
    fn a_very_long_path_drops_without_recursion() {
        let mut path = Path::default();
        for seq in 0..1_000_000 {
            path.push(pose(seq));
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
        path.push(StampedPose {
            stamp_ns: 0,
            pose: Pose2::new(1.0, 1.0, std::f64::consts::FRAC_PI_2),
        });
        path.pass();
        path.pass();
        path.push(pose(3));
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
        // No node is kept for the scans passed.
        assert_eq!(path.last.as_ref().map(|n| n.scan), Some(3));
    }
}
