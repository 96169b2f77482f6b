//! The scans kept for the occupancy grid until the final path comes.

use std::collections::{BTreeMap, HashSet};

use back_end::compact_scan::CompactScan;
use slam_geom::Pose2;

/// Scans kept while they wait for their pose. A scan whose pose never comes (the SLAM
/// process dropped it) would otherwise be kept for ever; the oldest are dropped first.
const MAX_PENDING: usize = 256;
/// A scan is kept when the robot turned this much since the last scan kept (or moved a
/// grid cell): the back end's rule for the scans its submaps trace.
const KEEP_TURN_RAD: f64 = back_end::global_slam::GRID_TURN_RAD;

/// Beams kept before a scan must also come from a viewpoint where no kept scan was taken:
/// about 16 MB of scans, and an end step (tracing the grid) that fits slam-launch's grace
/// period for stopped stages on a loaded machine. Well above a run of the benchmark logs (the office loop
/// keeps 0.66 M beams), so their maps do not change; a robot that goes round the same rooms
/// for an hour keeps a lap or two of scans and then only those of places new to it.
const REVISIT_BEAMS: usize = 4_000_000;
/// Past `REVISIT_BEAMS`, viewpoints fall in cells of this edge and ...
const VIEWPOINT_CELL_M: f64 = 0.25;
/// ... headings in sectors of this width; a scan is kept when no kept scan's viewpoint fell
/// in its cell and sector.
const VIEWPOINT_SECTOR_RAD: f64 = 0.1;

/// Keeps each scan whose viewpoint differs from the last one kept: by the online estimate,
/// the robot moved at least a grid cell or turned at least `KEEP_TURN_RAD`. A scan from
/// (nearly) the same viewpoint sees the same cells again and only adds certainty that the
/// log-odds clamp would cap anyway, so a robot standing still costs no memory. Past
/// `REVISIT_BEAMS` a scan is also left out when a kept scan was taken from about the same
/// place and heading, however long ago, so that a robot going round and round costs memory
/// and end-step time for the places it saw, not for its laps.
#[derive(Debug)]
pub struct ScanKeeper {
    min_move_m: f64,
    /// `REVISIT_BEAMS`, but for the tests.
    revisit_beams: usize,
    pending: BTreeMap<u64, CompactScan>,
    kept: Vec<(u64, CompactScan)>,
    last_kept: Option<Pose2>,
    /// The cell and sector of every kept scan's viewpoint.
    viewpoints: HashSet<(i64, i64, i64)>,
    bytes: usize,
    beams: usize,
    /// Scans left out past `REVISIT_BEAMS` for a viewpoint seen before.
    revisits: usize,
}

impl ScanKeeper {
    /// `min_move_m`: the grid's resolution.
    pub fn new(min_move_m: f64) -> Self {
        Self {
            min_move_m,
            revisit_beams: REVISIT_BEAMS,
            pending: BTreeMap::new(),
            kept: Vec::new(),
            last_kept: None,
            viewpoints: HashSet::new(),
            bytes: 0,
            beams: 0,
            revisits: 0,
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

    /// Scans left out because a kept scan had their viewpoint, once the beams kept passed
    /// the point where revisits stop adding scans.
    pub fn revisits(&self) -> usize {
        self.revisits
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
        let viewpoint = (
            (pose.x / VIEWPOINT_CELL_M).floor() as i64,
            (pose.y / VIEWPOINT_CELL_M).floor() as i64,
            (pose.yaw / VIEWPOINT_SECTOR_RAD).floor() as i64,
        );
        let seen = !self.viewpoints.insert(viewpoint);
        if seen && self.beams >= self.revisit_beams {
            self.revisits += 1;
            return;
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

    #[test]
    fn past_the_cap_a_lap_over_the_same_places_adds_no_scans() {
        let mut keeper = ScanKeeper::new(0.05);
        // Two beams a scan: the first lap reaches the cap.
        keeper.revisit_beams = 100;
        let lap = |keeper: &mut ScanKeeper, lap: u64| {
            for i in 0..50_u64 {
                let seq = lap * 50 + i;
                // Along a 5 m line, and again a little off it, as a second lap would be.
                let pose = Pose2::new(0.1 * i as f64 + 0.01 * lap as f64, 0.02 * lap as f64, 0.0);
                keeper.add_scan(seq, scan(), Some((seq, pose)));
            }
        };
        lap(&mut keeper, 0);
        assert_eq!(keeper.kept().len(), 50, "a first lap is all new");
        assert_eq!(keeper.revisits(), 0);
        lap(&mut keeper, 1);
        assert_eq!(keeper.kept().len(), 50, "the second lap saw nothing new");
        // Its last scan is taken where the last kept one was: left out as ever, not a
        // revisit.
        assert_eq!(keeper.revisits(), 49);
        let kept = keeper.kept().len();
        // A new place is kept however far past the cap.
        keeper.add_scan(1000, scan(), Some((1000, Pose2::new(20.0, 0.0, 0.0))));
        assert_eq!(keeper.kept().len(), kept + 1);
    }
}
