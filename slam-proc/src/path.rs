//! Each particle's whole path, shared with its ancestors' copies.
//!
//! FastSLAM's answer is a particle's path together with its map: the map was built from
//! those poses, so a loop that closes corrects the whole path, which the per-scan mean of
//! the particles never sees again. Particles append one pose per scan; a resampled copy
//! shares its parent's path up to the split, so the storage is the particles' family tree,
//! whose branches die out with the particles that are not resampled.

use std::sync::Arc;

use slam_geom::Pose2;

/// One pose of a path: the scan's stamp and the particle's pose after that scan's update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPose {
    pub stamp_ns: u64,
    pub pose: Pose2,
}

#[derive(Debug)]
struct Node {
    pose: PathPose,
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
    len: usize,
}

impl Path {
    pub fn push(&mut self, pose: PathPose) {
        let previous = self.last.take();
        self.last = Some(Arc::new(Node { pose, previous }));
        self.len += 1;
    }

    /// The poses from the first scan to the last.
    pub fn poses(&self) -> Vec<PathPose> {
        let mut poses = Vec::with_capacity(self.len);
        let mut node = self.last.as_deref();
        while let Some(n) = node {
            poses.push(n.pose);
            node = n.previous.as_deref();
        }
        poses.reverse();
        poses
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(seq: u64) -> PathPose {
        PathPose {
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
            p.poses()
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
        assert_eq!(copy.poses().len(), 1_000_000);
        drop(copy);
    }
}
