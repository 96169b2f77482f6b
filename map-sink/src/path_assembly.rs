//! Puts the filter's final path back together from the chunks it travels in.

use slam_geom::StampedPose;

/// Why a chunk did not fit the path being assembled.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ChunkError {
    #[error("a path chunk starts at pose {first}, but {held} poses are held")]
    Gap { first: u64, held: u64 },
    #[error("a path chunk says the path has {total} poses, the path so far {expected}")]
    TotalChanged { total: u64, expected: u64 },
    #[error("a path chunk brings pose {end} of a path of {total}")]
    TooLong { end: u64, total: u64 },
}

/// The chunks of one path, in order. A chunk that starts at pose 0 starts a new path (the
/// filter sends its whole path again when it stops early and then ends).
#[derive(Debug, Clone, Default)]
pub struct PathAssembly {
    poses: Vec<StampedPose>,
    total: u64,
}

impl PathAssembly {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the chunk holding poses `first ..` of a path of `total`.
    pub fn add(&mut self, first: u64, total: u64, poses: &[StampedPose]) -> Result<(), ChunkError> {
        if first == 0 {
            self.poses.clear();
            self.total = total;
        }
        let held = self.poses.len() as u64;
        if first != held {
            return Err(ChunkError::Gap { first, held });
        }
        if total != self.total {
            return Err(ChunkError::TotalChanged {
                total,
                expected: self.total,
            });
        }
        let end = held + poses.len() as u64;
        if end > total {
            return Err(ChunkError::TooLong { end, total });
        }
        self.poses.extend_from_slice(poses);
        Ok(())
    }

    /// The whole path, once every chunk has come: handed over, and the next path starts.
    pub fn take_complete(&mut self) -> Option<Vec<StampedPose>> {
        (self.poses.len() as u64 == self.total && self.total > 0).then(|| {
            self.total = 0;
            std::mem::take(&mut self.poses)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slam_geom::Pose2;

    fn poses(range: std::ops::Range<u64>) -> Vec<StampedPose> {
        range
            .map(|i| StampedPose {
                stamp_ns: i,
                pose: Pose2::new(i as f64, 0.0, 0.0),
            })
            .collect()
    }

    #[test]
    fn chunks_in_order_make_the_path_and_a_new_start_replaces_it() {
        let mut path = PathAssembly::new();
        assert!(path.take_complete().is_none());
        path.add(0, 5, &poses(0..3)).unwrap();
        assert!(path.take_complete().is_none());
        path.add(3, 5, &poses(3..5)).unwrap();
        assert_eq!(path.take_complete().map(|p| p.len()), Some(5));
        // Handed over once.
        assert!(path.take_complete().is_none());
        path.add(0, 2, &poses(10..12)).unwrap();
        assert_eq!(path.take_complete().unwrap()[1].stamp_ns, 11);
    }

    #[test]
    fn gaps_changed_totals_and_overlong_chunks_are_refused() {
        let mut path = PathAssembly::new();
        path.add(0, 5, &poses(0..2)).unwrap();
        assert_eq!(
            path.add(3, 5, &poses(3..5)),
            Err(ChunkError::Gap { first: 3, held: 2 })
        );
        assert_eq!(
            path.add(2, 6, &poses(2..4)),
            Err(ChunkError::TotalChanged {
                total: 6,
                expected: 5
            })
        );
        assert_eq!(
            path.add(2, 5, &poses(2..6)),
            Err(ChunkError::TooLong { end: 6, total: 5 })
        );
        assert!(path.take_complete().is_none());
    }
}
