//! The real recording (shared data, seed-hall): corners from the feature extractor, all
//! 400 scans through the filter. No ground truth, so: it completes, the map has no
//! duplicate corners, the trajectory is plausible, and the time per scan is reported.

use std::time::Instant;

mod common;

use common::recorded::{ScanFeatures, seed_hall_features};
use feature_proc::FeatureConfig;
use slam_geom::wrap_angle;
use slam_proc::{FastSlam, MapCorner, Pose2, SlamConfig};

fn features() -> Vec<ScanFeatures> {
    // The course code keeps 15 m for SLAM: far corners are sparse and noisy.
    let scans = seed_hall_features(FeatureConfig {
        max_range: 15.0,
        ..FeatureConfig::default()
    });
    assert_eq!(scans.len(), 400);
    scans
}

struct Outcome {
    trajectory: Vec<Pose2>,
    map: Vec<MapCorner>,
    seconds_per_scan: f64,
}

fn run(scans: &[ScanFeatures], particles: usize) -> Outcome {
    let config = SlamConfig {
        particles,
        ..SlamConfig::default()
    };
    let mut slam = FastSlam::new(config, 1).unwrap();
    let start = Instant::now();
    // No timestamps in the recording: a nominal 40 Hz, used only for constant velocity.
    let trajectory = scans
        .iter()
        .enumerate()
        .map(|(k, s)| {
            slam.process(k as u64 * 25_000_000, &s.corners, &s.lines, None)
                .mean
        })
        .collect();
    let seconds_per_scan = start.elapsed().as_secs_f64() / scans.len() as f64;
    Outcome {
        trajectory,
        map: slam.best_map(),
        seconds_per_scan,
    }
}

/// Pairs of confirmed corners closer than 0.5 m with headings within 30 degrees.
fn duplicates(map: &[MapCorner]) -> Vec<(usize, usize, f64)> {
    let mut found = Vec::new();
    for (i, a) in map.iter().enumerate() {
        for (j, b) in map.iter().enumerate().skip(i + 1) {
            let d = (a.x - b.x).hypot(a.y - b.y);
            if d < 0.5 && wrap_angle(a.heading - b.heading).abs() < 30f64.to_radians() {
                found.push((i, j, d));
            }
        }
    }
    found
}

#[test]
fn all_scans_run_without_duplicate_corners() {
    let scans = features();
    let per_scan = scans.iter().map(|s| s.corners.len()).sum::<usize>() as f64 / scans.len() as f64;
    for particles in [50, 100] {
        let outcome = run(&scans, particles);
        let steps: Vec<f64> = outcome
            .trajectory
            .windows(2)
            .map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y))
            .collect();
        let length: f64 = steps.iter().sum();
        let longest = steps.iter().copied().fold(0.0, f64::max);
        let end = outcome.trajectory.last().copied().unwrap_or_default();
        eprintln!(
            "seed-hall, {particles} particles: {:.3} ms/scan ({:.1e} s; course code 2.2 s with 50 in Octave), \
             {per_scan:.2} corners/scan, path {length:.1} m, longest step {longest:.3} m, end ({:.2}, {:.2}, {:.2}), \
             map {} confirmed corners",
            1e3 * outcome.seconds_per_scan,
            outcome.seconds_per_scan,
            end.x,
            end.y,
            end.yaw,
            outcome.map.len()
        );
        let duplicated = duplicates(&outcome.map);
        assert!(duplicated.is_empty(), "duplicate corners: {duplicated:?}");
        // About 0.11 m per scan over 399 steps: the estimate must neither stall nor jump.
        assert!((25.0..=70.0).contains(&length), "path length {length} m");
        assert!(longest < 0.5, "a step of {longest} m");
        assert!(
            outcome.map.len() >= 10,
            "only {} corners",
            outcome.map.len()
        );
    }
}
