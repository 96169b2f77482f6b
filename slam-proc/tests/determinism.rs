//! The same seed gives the same bits whatever the thread count, and angles stay wrapped.

mod common;

use std::f64::consts::PI;

use common::{SensorModel, square_loop};
use slam_proc::{Estimate, FastSlam, MapCorner, MeasuredCorner, Pose2, SlamConfig};

fn run(
    scans: &[Vec<MeasuredCorner>],
    stamps: &[u64],
    threads: usize,
) -> (Vec<Estimate>, Vec<MapCorner>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let config = SlamConfig {
            particles: 64,
            ..SlamConfig::default()
        };
        let mut slam = FastSlam::new(config, 42).unwrap();
        let estimates = stamps
            .iter()
            .zip(scans)
            .map(|(t, s)| slam.process(*t, s, &[], None))
            .collect();
        (estimates, slam.best_map())
    })
}

fn bits(p: &Pose2) -> [u64; 3] {
    [p.x.to_bits(), p.y.to_bits(), p.yaw.to_bits()]
}

#[test]
fn one_and_two_threads_give_identical_results() {
    let data = square_loop(5, 60, &SensorModel::default());
    let n = 400;
    let (one, map_one) = run(&data.scans[..n], &data.stamps[..n], 1);
    let (two, map_two) = run(&data.scans[..n], &data.stamps[..n], 2);
    assert_eq!(one.len(), two.len());
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(bits(&a.best), bits(&b.best));
        assert_eq!(bits(&a.mean), bits(&b.mean));
        assert_eq!(bits(&a.dead_reckoning), bits(&b.dead_reckoning));
        assert_eq!(
            a.effective_particles.to_bits(),
            b.effective_particles.to_bits()
        );
        assert_eq!(a.covariance, b.covariance);
        assert_eq!(a.map_size, b.map_size);
    }
    assert!(!map_one.is_empty());
    assert_eq!(map_one, map_two);
    // A different seed gives a different run: the seed is used at all.
    let config = SlamConfig {
        particles: 64,
        ..SlamConfig::default()
    };
    let mut other = FastSlam::new(config, 43).unwrap();
    let last = data.stamps[..n]
        .iter()
        .zip(&data.scans[..n])
        .map(|(t, s)| other.process(*t, s, &[], None))
        .last();
    assert_ne!(
        last.map(|e| bits(&e.mean)),
        one.last().map(|e| bits(&e.mean))
    );
}

#[test]
fn angles_stay_in_range_while_spinning() {
    // A robot turning on the spot then driving in circles: yaw crosses +-pi many times.
    let data = square_loop(9, 60, &SensorModel::default());
    let corners = &data.corners;
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(3);
    let sensor = SensorModel::default();
    let config = SlamConfig {
        particles: 30,
        ..SlamConfig::default()
    };
    let mut slam = FastSlam::new(config, 1).unwrap();
    let in_range = |a: f64| (-PI..PI).contains(&a);
    let mut pose = Pose2::IDENTITY;
    for k in 0..600u64 {
        let step = if k < 200 {
            Pose2::new(0.0, 0.0, 0.2)
        } else {
            Pose2::new(0.1, 0.0, 0.15)
        };
        pose = pose.compose(&step);
        let scan = common::observe(&mut rng, &sensor, &pose, corners);
        let estimate = slam.process(k * 25_000_000, &scan, &[], None);
        for p in [estimate.best, estimate.mean, estimate.dead_reckoning] {
            assert!(in_range(p.yaw), "yaw {} at scan {k}", p.yaw);
        }
        assert!(estimate.covariance[(2, 2)] >= 0.0 && estimate.covariance[(2, 2)] < PI * PI);
    }
    for c in slam.best_map() {
        assert!(in_range(c.heading), "heading {}", c.heading);
        assert!(c.angle > 0.0 && c.angle < PI, "angle {}", c.angle);
    }
    for p in slam.particle_poses() {
        assert!(in_range(p.yaw));
    }
}
