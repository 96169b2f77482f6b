//! The real recording: at least as many corners as the course implementation, and they are
//! real: most recur in the next scan after the motion between the two.

mod common;

use common::eval::{MatchParams, estimate_motion, redetected};
use common::recorded::scan_input;
use feature_proc::{Extractor, FeatureConfig};
use slam_geom::MeasuredCorner;
use test_data::{ScanRecord, seed_hall_scans};

struct Stats {
    corners_per_scan: f64,
    redetected: f64,
    mean_step: f64,
}

fn run(scans: &[ScanRecord], config: FeatureConfig) -> Stats {
    let mut extractor = Extractor::new(config);
    let corners: Vec<Vec<MeasuredCorner>> = scans
        .iter()
        .map(|scan| {
            let found = extractor.extract(&scan_input(scan));
            found.map(|f| f.corners.clone()).unwrap_or_default()
        })
        .collect();
    let params = MatchParams::default();
    let (mut seen, mut again, mut step, mut steps) = (0, 0, 0.0, 0.0);
    for pair in corners.windows(2) {
        seen += pair[0].len();
        if let Some(motion) = estimate_motion(&pair[0], &pair[1], &params) {
            again += redetected(&pair[0], &pair[1], &motion, &params);
            step += motion.x.hypot(motion.y);
            steps += 1.0;
        }
    }
    let all: usize = corners.iter().map(Vec::len).sum();
    Stats {
        corners_per_scan: all as f64 / scans.len() as f64,
        redetected: again as f64 / seen.max(1) as f64,
        mean_step: step / steps,
    }
}

#[test]
fn corners_are_as_many_as_the_courses_and_recur_in_the_next_scan() {
    // Without the recording this fails, naming where it was looked for.
    let scans = seed_hall_scans();
    assert_eq!(scans.len(), 400);
    let default_cap = FeatureConfig::default().max_range;
    // The course's counts with its 15 m (SLAM) and 35 m (motion estimate) caps.
    for (cap, course) in [(15.0, 4.9), (default_cap, 6.5), (35.0, 6.5)] {
        let config = FeatureConfig {
            max_range: cap,
            ..FeatureConfig::default()
        };
        let stats = run(&scans, config);
        eprintln!(
            "seed-hall, cap {cap} m: {:.2} corners/scan (course {course}), {:.1} % found again \
             in the next scan, mean motion {:.3} m",
            stats.corners_per_scan,
            100.0 * stats.redetected,
            stats.mean_step,
        );
        assert!(
            stats.corners_per_scan >= course,
            "cap {cap}: too few corners"
        );
        assert!(stats.redetected >= 0.8, "cap {cap}: corners do not recur");
        // The recording moves about 0.11 m a scan; a motion estimate far off that would
        // make the recurrence meaningless.
        assert!(
            (0.07..0.16).contains(&stats.mean_step),
            "motion {}",
            stats.mean_step
        );
    }
}
