//! The front end on the first 300 scans of the real mit-csail log, scored with the
//! relative-pose metric against the relations that fall inside them.

#[path = "support/logs.rs"]
mod logs;

use lidar_replay::LogFormat;
use scan_match::{FrontEnd, FrontEndConfig};
use slam_eval::{Trajectory, from_xyz_rpy, read_relations, score};

const SCANS: usize = 300;

fn run(with_odometry: bool) -> (slam_eval::Score, scan_match::FrontEndStats) {
    let log = test_data::carmen_log("mit-csail");
    let scans = logs::load(&log, LogFormat::Carmen, SCANS).unwrap();
    assert_eq!(scans.len(), SCANS);
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let mut poses = Vec::new();
    for scan in &scans {
        let out = front_end.process(&scan.input(with_odometry)).unwrap();
        let p = out.odom_from_robot;
        poses.push((out.stamp_ns, from_xyz_rpy([p.x, p.y, 0.0], 0.0, 0.0, p.yaw)));
    }
    let trajectory = Trajectory::new(poses).unwrap();
    let relations = read_relations(&log.with_extension("relations")).unwrap();
    let last = scans[SCANS - 1].stamp_ns;
    let inside: Vec<_> = relations
        .into_iter()
        .filter(|r| r.t1_ns <= last && r.t2_ns <= last)
        .collect();
    let s = score(&trajectory, &inside, 1_000_000);
    assert!(s.used > 100 && s.unmatched.is_empty(), "{s:?}");
    (s, front_end.stats())
}

// This prefix is a minute of driving with 154 relations; the bounds leave about twice
// what the front end scores on it, with odometry or without.
#[test]
fn the_first_300_scans_of_mit_csail_stay_within_five_centimetres() {
    for with_odometry in [true, false] {
        let (s, stats) = run(with_odometry);
        eprintln!(
            "odometry {with_odometry}: {} relations, {:.4} m, {:.3} deg; {stats:?}",
            s.used, s.translation_m.mean, s.rotation_deg.mean
        );
        assert!(s.translation_m.mean < 0.05, "{s:?}");
        assert!(s.rotation_deg.mean < 0.8, "{s:?}");
        assert_eq!(stats.failed_matches, 0);
    }
}
