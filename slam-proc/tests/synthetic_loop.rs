//! End to end on a synthetic ~100 m loop among 60 corners: the filter must beat dead
//! reckoning clearly, close the loop and build a clean map; with odometry it must also get
//! through stretches with too few corners for the scan-to-scan fit.

mod common;

use common::{Run, SensorModel, TrueCorner, align, ate_rmse, square_loop};
use nalgebra::{Matrix3, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use slam_proc::{FastSlam, MapCorner, OdometryInput, Pose2, SlamConfig};

struct Outcome {
    best: Vec<Pose2>,
    mean: Vec<Pose2>,
    dead_reckoning: Vec<Pose2>,
    map: Vec<MapCorner>,
    seconds_per_scan: f64,
}

fn run_filter(run: &Run, odometry: Option<&[OdometryInput]>, seed: u64) -> Outcome {
    let config = SlamConfig {
        particles: 100,
        ..SlamConfig::default()
    };
    let mut slam = FastSlam::new(config, seed).unwrap();
    let (mut best, mut mean, mut dead_reckoning) = (Vec::new(), Vec::new(), Vec::new());
    let start = std::time::Instant::now();
    for (k, (stamp, scan)) in run.stamps.iter().zip(&run.scans).enumerate() {
        let estimate = slam.process(*stamp, scan, &[], odometry.map(|o| &o[k]));
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

struct Scores {
    ate_best: f64,
    ate_mean: f64,
    ate_dead_reckoning: f64,
    map_worst: f64,
}

fn score(label: &str, run: &Run, outcome: &Outcome) -> Scores {
    let ate_best = ate_rmse(&outcome.best, &run.truth);
    let ate_mean = ate_rmse(&outcome.mean, &run.truth);
    let ate_dead_reckoning = ate_rmse(&outcome.dead_reckoning, &run.truth);
    let alignment = align(&outcome.best, &run.truth);
    let errors = map_errors(&outcome.map, &run.corners, &alignment);
    let map_rmse = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len().max(1) as f64).sqrt();
    let map_worst = errors.iter().copied().fold(0.0, f64::max);
    let per_scan = run.scans.iter().map(Vec::len).sum::<usize>() as f64 / run.scans.len() as f64;
    eprintln!(
        "{label}: {} scans, {per_scan:.1} corners/scan; ATE best {ate_best:.3} m, mean {ate_mean:.3} m, \
         dead reckoning {ate_dead_reckoning:.3} m; map {} corners (of {}), rmse {map_rmse:.3} m, \
         worst {map_worst:.3} m; {:.2} ms/scan",
        run.scans.len(),
        outcome.map.len(),
        run.corners.len(),
        1e3 * outcome.seconds_per_scan
    );
    Scores {
        ate_best,
        ate_mean,
        ate_dead_reckoning,
        map_worst,
    }
}

#[test]
fn loop_accuracy_beats_dead_reckoning() {
    for world in 1..=3 {
        let run = square_loop(world, 60, &SensorModel::default());
        let outcome = run_filter(&run, None, 7);
        let s = score(&format!("world {world}"), &run, &outcome);
        // Typically 2 cm against 10-30 cm: the margins are wide on purpose.
        assert!(
            s.ate_best < 0.08 && s.ate_mean < 0.08,
            "ATE {} / {} m",
            s.ate_best,
            s.ate_mean
        );
        assert!(
            s.ate_best < 0.5 * s.ate_dead_reckoning,
            "ATE {} m, dead reckoning {} m",
            s.ate_best,
            s.ate_dead_reckoning
        );
        // Every true corner once, nothing else: no duplicates, no spurious corners kept.
        assert!(
            (54..=60).contains(&outcome.map.len()),
            "{} map corners",
            outcome.map.len()
        );
        assert!(
            s.map_worst < 0.2,
            "a map corner {} m from any true corner",
            s.map_worst
        );
    }
}

/// Wheel odometry along the true path: each increment with 2 % + 2 mm translation noise and
/// 0.002 rad + 2 % yaw noise, so it drifts; its covariance grows accordingly.
fn odometry(run: &Run, seed: u64) -> Vec<OdometryInput> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pose = Pose2::IDENTITY;
    let mut covariance = Matrix3::zeros();
    let mut out = vec![OdometryInput { pose, covariance }];
    for pair in run.truth.windows(2) {
        let step = pair[0].between(&pair[1]);
        let sxy = 0.002 + 0.02 * step.translation_norm();
        let syaw = 0.002 + 0.02 * step.yaw.abs();
        let n = |rng: &mut ChaCha8Rng| -> f64 { rng.sample(StandardNormal) };
        let noisy = Pose2::new(
            step.x + sxy * n(&mut rng),
            step.y + sxy * n(&mut rng),
            step.yaw + syaw * n(&mut rng),
        );
        pose = pose.compose(&noisy);
        covariance += Matrix3::from_diagonal(&Vector3::new(sxy * sxy, sxy * sxy, syaw * syaw));
        out.push(OdometryInput { pose, covariance });
    }
    out
}

#[test]
fn odometry_carries_the_filter_through_sparse_stretches() {
    // Corners seen only from inside their wedge: some turns go by with no corner in view,
    // where constant velocity cannot know the robot turns, but odometry does.
    let sensor = SensorModel {
        wedge_margin: 0.0,
        ..SensorModel::default()
    };
    for world in [3, 4] {
        let run = square_loop(world, 60, &sensor);
        let odometry = odometry(&run, world);
        let outcome = run_filter(&run, Some(&odometry), 7);
        let s = score(
            &format!("sparse world {world} with odometry"),
            &run,
            &outcome,
        );
        let odometry_alone: Vec<Pose2> = odometry.iter().map(|o| o.pose).collect();
        let ate_odometry = ate_rmse(&odometry_alone, &run.truth);
        eprintln!("  odometry alone: ATE {ate_odometry:.3} m");
        assert!(s.ate_best < 0.15, "ATE {} m", s.ate_best);
        assert!(
            s.ate_best < 0.5 * ate_odometry,
            "ATE {} m, odometry {ate_odometry} m",
            s.ate_best
        );
        // Closing this loop after the sparse stretches, a few corners are not recognised
        // and mapped again: the particle cloud is tighter than the drift it carries.
        assert!(outcome.map.len() <= 70, "{} map corners", outcome.map.len());
    }
}
