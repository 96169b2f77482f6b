#[path = "../tests/common/mod.rs"]
mod common;
use common::*;
use nalgebra::{Matrix4, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slam_proc::*;
use std::f64::consts::TAU;
fn main() {
    let corners: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let particles: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let sensor = SensorModel {
        wedge_visibility: false,
        ..SensorModel::default()
    };
    let visible_area = sensor.max_range * sensor.max_range * sensor.half_fov;
    let side = (corners as f64 * visible_area / 8.0).sqrt();
    let mut rng = ChaCha8Rng::seed_from_u64(corners as u64);
    let truth: Vec<TrueCorner> = (0..corners)
        .map(|_| TrueCorner {
            x: side * (rng.random::<f64>() - 0.5),
            y: side * (rng.random::<f64>() - 0.5),
            heading: wrap_angle(TAU * rng.random::<f64>()),
            angle: (50.0 + 80.0 * rng.random::<f64>()).to_radians(),
        })
        .collect();
    let map: Vec<MapCorner> = truth
        .iter()
        .map(|c| MapCorner {
            x: c.x,
            y: c.y,
            heading: c.heading,
            angle: c.angle,
            covariance: Matrix4::from_diagonal(&Vector4::new(1e-4, 1e-4, 1e-4, 1e-4)),
            observations: 10,
        })
        .collect();
    let radius = 20.0;
    let steps = (TAU * radius / 0.1) as usize;
    let scans: Vec<Vec<Observation>> = (0..steps)
        .map(|k| {
            let a = k as f64 * TAU / steps as f64;
            let pose = Pose2::new(radius * a.sin(), radius * (1.0 - a.cos()), wrap_angle(a));
            observe(&mut rng, &sensor, &pose, &truth)
        })
        .collect();
    let mut slam = FastSlam::with_prior_map(
        SlamConfig {
            particles,
            ..SlamConfig::default()
        },
        1,
        &map,
    )
    .unwrap();
    let mut sum = [0u64; 5];
    let n: usize = std::env::args()
        .nth(3)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2000);
    let mut resamples = 0;
    for k in 0..n {
        let e = slam.process(k as u64 * 25_000_000, &scans[k % steps], None);
        if k >= 50 {
            let t = e.timing;
            for (s, v) in sum.iter_mut().zip([
                t.motion_ns,
                t.predict_ns,
                t.update_ns,
                t.resample_ns,
                t.total_ns,
            ]) {
                *s += v;
            }
        }
        if e.effective_particles < 50.0 {
            resamples += 1;
        }
    }
    let m = (n - 50) as f64 * 1e3;
    println!(
        "motion {:.1} us, predict {:.1} us, update {:.1} us, resample {:.1} us, total {:.1} us; resampled {resamples}",
        sum[0] as f64 / m,
        sum[1] as f64 / m,
        sum[2] as f64 / m,
        sum[3] as f64 / m,
        sum[4] as f64 / m
    );
}
