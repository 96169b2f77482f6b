//! The scans kept for the occupancy grid until the final path comes.

use std::collections::BTreeMap;

use crate::compact_scan::CompactScan;
use slam_geom::Pose2;

/// Scans kept while they wait for their pose. A scan whose pose never comes (the SLAM
/// process dropped it) would otherwise be kept for ever; the oldest are dropped first.
const MAX_PENDING: usize = 256;
/// A scan is kept when the robot turned this much since the last scan kept (or moved a
/// grid cell): turning by it moves a wall 2.5 m away by a cell of 5 cm.
const KEEP_TURN_RAD: f64 = 0.02;

/// Keeps each scan whose viewpoint differs from the last one kept: by the online estimate,
/// the robot moved at least a grid cell or turned at least [`KEEP_TURN_RAD`]. A scan from
/// (nearly) the same viewpoint sees the same cells again and only adds certainty that the
/// log-odds clamp would cap anyway, so a robot standing still costs no memory.
#[derive(Debug)]
pub struct ScanKeeper {
    min_move_m: f64,
    pending: BTreeMap<u64, CompactScan>,
    kept: Vec<(u64, CompactScan)>,
    last_kept: Option<Pose2>,
    bytes: usize,
    beams: usize,
}

impl ScanKeeper {
    /// `min_move_m`: the grid's resolution.
    pub fn new(min_move_m: f64) -> Self {
        Self {
            min_move_m,
            pending: BTreeMap::new(),
            kept: Vec::new(),
            last_kept: None,
            bytes: 0,
            beams: 0,
        }
    }

    /// Scan `seq`, with its stamp and online estimate if they came first.
    pub fn add_scan(&mut self, seq: u64, scan: CompactScan, estimate: Option<(u64, Pose2)>) {
        match estimate {
            Some((stamp_ns, pose)) => self.decide(stamp_ns, scan, pose),
            None => {
                self.pending.insert(seq, scan);
                while self.pending.len() > MAX_PENDING {
                    self.pending.pop_first();
                }
            }
        }
    }

    /// The stamp and online estimate of scan `seq`, which decide a scan waiting for them.
    pub fn add_pose(&mut self, seq: u64, stamp_ns: u64, pose: Pose2) {
        if let Some(scan) = self.pending.remove(&seq) {
            self.decide(stamp_ns, scan, pose);
        }
    }

    /// The scans kept, with their stamps, in the order their poses came.
    pub fn kept(&self) -> &[(u64, CompactScan)] {
        &self.kept
    }

    /// Beams in the scans kept.
    pub fn beams(&self) -> usize {
        self.beams
    }

    /// Bytes the scans kept hold.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// Scans waiting for their pose.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    fn decide(&mut self, stamp_ns: u64, scan: CompactScan, pose: Pose2) {
        if scan.is_empty() {
            return;
        }
        if let Some(last) = self.last_kept {
            let moved = (pose.x - last.x).hypot(pose.y - last.y);
            let turned = slam_geom::wrap_angle(pose.yaw - last.yaw).abs();
            if moved < self.min_move_m && turned < KEEP_TURN_RAD {
                return;
            }
        }
        self.last_kept = Some(pose);
        self.bytes += scan.bytes();
        self.beams += scan.len();
        self.kept.push((stamp_ns, scan));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan() -> CompactScan {
        CompactScan::new(0.0, 0.1, 0.1, 30.0, &[1.0, 2.0], 0.0, 5.0)
    }

    #[test]
    fn scans_meet_their_pose_in_either_order_and_a_standing_robot_adds_nothing() {
        let mut keeper = ScanKeeper::new(0.05);
        keeper.add_scan(0, scan(), None);
        assert!(keeper.kept().is_empty(), "no pose yet");
        keeper.add_pose(0, 10, Pose2::default());
        assert_eq!(keeper.kept().len(), 1);
        // Standing still, then a turn, then a step.
        keeper.add_scan(1, scan(), Some((11, Pose2::new(0.01, 0.0, 0.0))));
        keeper.add_scan(2, scan(), Some((12, Pose2::new(0.01, 0.0, 0.03))));
        keeper.add_scan(3, scan(), Some((13, Pose2::new(0.07, 0.0, 0.03))));
        keeper.add_scan(4, scan(), Some((14, Pose2::new(0.07, 0.0, 0.03))));
        keeper.add_scan(5, scan(), Some((15, Pose2::new(0.07, 0.06, 0.03))));
        let stamps: Vec<u64> = keeper.kept().iter().map(|(s, _)| *s).collect();
        assert_eq!(stamps, [10, 12, 13, 15]);
        assert_eq!(keeper.beams(), 8);
        // A scan whose pose never comes is eventually forgotten.
        for seq in 100..100 + MAX_PENDING as u64 + 10 {
            keeper.add_scan(seq, scan(), None);
        }
        assert_eq!(keeper.pending(), MAX_PENDING);
    }
}
