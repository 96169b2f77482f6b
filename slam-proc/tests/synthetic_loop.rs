//! End to end on a synthetic ~100 m loop among 60 corners: the filter must beat dead
//! reckoning clearly and build a clean map.

mod common;

use common::{SensorModel, TrueCorner, align, ate_rmse, square_loop};
use nalgebra::Vector2;
use slam_proc::{FastSlam, MapCorner, Pose2, SlamConfig};

struct Outcome {
    best: Vec<Pose2>,
    mean: Vec<Pose2>,
    dead_reckoning: Vec<Pose2>,
    map: Vec<MapCorner>,
    seconds_per_scan: f64,
}

fn run_filter(run: &common::Run, particles: usize, seed: u64) -> Outcome {
    let config = SlamConfig {
        particles,
        ..SlamConfig::default()
    };
    let mut slam = FastSlam::new(config, seed).unwrap();
    let (mut best, mut mean, mut dead_reckoning) = (Vec::new(), Vec::new(), Vec::new());
    let start = std::time::Instant::now();
    for (stamp, scan) in run.stamps.iter().zip(&run.scans) {
        let estimate = slam.process(*stamp, scan, None);
        best.push(estimate.best);
        mean.push(estimate.mean);
        dead_reckoning.push(estimate.dead_reckoning);
    }
    Outcome {
        best,
        mean,
        dead_reckoning,
        map: slam.best_map(),
        seconds_per_scan: start.elapsed().as_secs_f64() / run.scans.len() as f64,
    }
}

/// Distance from each map corner (aligned like the trajectory) to the nearest true corner.
fn map_errors(map: &[MapCorner], corners: &[TrueCorner], alignment: &Pose2) -> Vec<f64> {
    map.iter()
        .map(|m| {
            let p = alignment.transform(Vector2::new(m.x, m.y));
            corners
                .iter()
                .map(|c| (c.x - p.x).hypot(c.y - p.y))
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

#[test]
fn loop_accuracy_beats_dead_reckoning() {
    for world in [1, 2, 3] {
        let run = square_loop(world, 60, &SensorModel::default());
        let outcome = run_filter(&run, 100, 7);
        let ate_best = ate_rmse(&outcome.best, &run.truth);
        let ate_mean = ate_rmse(&outcome.mean, &run.truth);
        let ate_dr = ate_rmse(&outcome.dead_reckoning, &run.truth);
        let alignment = align(&outcome.best, &run.truth);
        let errors = map_errors(&outcome.map, &run.corners, &alignment);
        let map_rmse =
            (errors.iter().map(|e| e * e).sum::<f64>() / errors.len().max(1) as f64).sqrt();
        let final_error = {
            let (e, t) = (outcome.best.last().unwrap(), run.truth.last().unwrap());
            let p = alignment.transform(Vector2::new(e.x, e.y));
            (p.x - t.x).hypot(p.y - t.y)
        };
        eprintln!(
            "world {world}: {} scans, ATE best {ate_best:.3} m, mean {ate_mean:.3} m, dead reckoning {ate_dr:.3} m; \
             final {final_error:.3} m; map {} corners (of 60), rmse {map_rmse:.3} m, worst {:.3} m; {:.2} ms/scan",
            run.scans.len(),
            outcome.map.len(),
            errors.iter().copied().fold(0.0, f64::max),
            1e3 * outcome.seconds_per_scan
        );
    }
}
