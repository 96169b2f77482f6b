//! The walls of every scan that updated the particles, kept for checking loop closures.
//!
//! A closure ties the scan now seen to the scans that last saw the old corners it landed on;
//! their walls, placed by each particle's own poses, show whether the landing fits the place
//! (see [`crate::update::free_space`]). The walls are the particles' common input, so they
//! are kept once, by scan, not per particle.

use crate::update::free_space::WallSegment;

/// The walls of the scans that updated the particles, in scan order.
#[derive(Debug, Clone, Default)]
pub(crate) struct WallMemory {
    scans: Vec<usize>,
    walls: Vec<Vec<WallSegment>>,
}

impl WallMemory {
    /// Keeps `walls` as scan `scan`'s; scans come in increasing order.
    pub fn push(&mut self, scan: usize, walls: &[WallSegment]) {
        debug_assert!(self.scans.last().is_none_or(|&last| last < scan));
        self.scans.push(scan);
        self.walls.push(walls.to_vec());
    }

    /// The kept scans whose path length is within `reach` metres of one of `ties`' (scan
    /// numbers; `path_length` by scan, non-decreasing), each once, in increasing order,
    /// with their walls; at most `at_most` of them, evenly spread over those, where the
    /// robot turned on the spot or crept and updated many times within the reach.
    pub fn around<'a>(
        &'a self,
        ties: &[usize],
        path_length: &[f64],
        reach: f64,
        at_most: usize,
    ) -> Vec<(usize, &'a [WallSegment])> {
        let mut found: Vec<usize> = Vec::new();
        for &tie in ties {
            let Some(&at) = path_length.get(tie) else {
                continue;
            };
            let first = path_length.partition_point(|&l| l < at - reach);
            let end = path_length.partition_point(|&l| l <= at + reach);
            let from = self.scans.partition_point(|&s| s < first);
            let to = self.scans.partition_point(|&s| s < end);
            found.extend(from..to);
        }
        found.sort_unstable();
        found.dedup();
        let stride = found.len().div_ceil(at_most.max(1)).max(1);
        found
            .into_iter()
            .step_by(stride)
            .map(|k| (self.scans[k], self.walls[k].as_slice()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use slam_geom::Point2;

    fn wall(x: f64) -> Vec<WallSegment> {
        vec![WallSegment {
            start: Point2::new(x, 0.0),
            end: Point2::new(x, 1.0),
        }]
    }

    #[test]
    fn the_scans_around_a_tie_are_those_within_reach_along_the_path() {
        let mut memory = WallMemory::default();
        // Scans 0..10 a metre apart; every other one updated the particles.
        let path_length: Vec<f64> = (0..10).map(f64::from).collect();
        for scan in (0..10).step_by(2) {
            memory.push(scan, &wall(scan as f64));
        }
        let scans = |ties: &[usize], reach: f64| -> Vec<usize> {
            memory
                .around(ties, &path_length, reach, usize::MAX)
                .iter()
                .map(|(s, _)| *s)
                .collect()
        };
        assert_eq!(scans(&[4], 2.0), vec![2, 4, 6]);
        assert_eq!(scans(&[3], 1.0), vec![2, 4]);
        // Overlapping reaches give each scan once.
        assert_eq!(scans(&[3, 4, 9], 1.0), vec![2, 4, 8]);
        assert_eq!(scans(&[20], 1.0), Vec::<usize>::new());
        let found = memory.around(&[6], &path_length, 0.5, 10);
        assert_eq!(found, vec![(6, wall(6.0).as_slice())]);
        // At most so many, spread over the reach.
        let spread: Vec<usize> = memory
            .around(&[4], &path_length, 10.0, 2)
            .iter()
            .map(|(s, _)| *s)
            .collect();
        assert_eq!(spread, vec![0, 6]);
    }
}
