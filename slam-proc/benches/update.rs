//! One `FastSlam::process` call against the particle count and the map size, localising
//! in a known map with ~8 corners per scan (synthetic). Run with `RAYON_NUM_THREADS=1` for
//! single-core figures.

#[path = "../tests/common/mod.rs"]
mod common;

use std::f64::consts::TAU;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix4, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slam_geom::wrap_angle;
use slam_proc::{FastSlam, MapCorner, MeasuredCorner, Pose2, SlamConfig};

use common::{SensorModel, TrueCorner, observe};

/// Visible corners per scan the world is sized for.
const VISIBLE: f64 = 8.0;

struct Scenario {
    map: Vec<MapCorner>,
    scans: Vec<Vec<MeasuredCorner>>,
}

/// `corners` corners spread uniformly so that about `VISIBLE` are in view, and the scans
/// of one lap of a 20 m circle around the centre at 0.1 m per scan.
fn scenario(corners: usize) -> Scenario {
    let sensor = SensorModel {
        wedge_visibility: false,
        ..SensorModel::default()
    };
    let visible_area = sensor.max_range * sensor.max_range * sensor.half_fov;
    let side = (corners as f64 * visible_area / VISIBLE).sqrt();
    let mut rng = ChaCha8Rng::seed_from_u64(corners as u64);
    let truth: Vec<TrueCorner> = (0..corners)
        .map(|_| TrueCorner {
            x: side * (rng.random::<f64>() - 0.5),
            y: side * (rng.random::<f64>() - 0.5),
            heading: wrap_angle(TAU * rng.random::<f64>()),
            angle: (50.0 + 80.0 * rng.random::<f64>()).to_radians(),
        })
        .collect();
    let covariance = Matrix4::from_diagonal(&Vector4::new(1e-4, 1e-4, 1e-4, 1e-4));
    let map = truth
        .iter()
        .map(|c| MapCorner::observed(*c, covariance, 10))
        .collect();
    // The filter starts at the origin of its map: the circle starts there, facing +x.
    let radius = 20.0;
    let steps = (TAU * radius / 0.1) as usize;
    let scans = (0..steps)
        .map(|k| {
            let a = k as f64 * TAU / steps as f64;
            let pose = Pose2::new(radius * a.sin(), radius * (1.0 - a.cos()), wrap_angle(a));
            observe(&mut rng, &sensor, &pose, &truth)
        })
        .collect();
    Scenario { map, scans }
}

fn process(c: &mut Criterion) {
    let mut group = c.benchmark_group("process");
    group.sample_size(10);
    for corners in [100, 1000] {
        let scenario = scenario(corners);
        let per_scan =
            scenario.scans.iter().map(Vec::len).sum::<usize>() as f64 / scenario.scans.len() as f64;
        eprintln!("map of {corners} corners: {per_scan:.1} observations per scan");
        for particles in [50, 100, 1000, 5000] {
            let config = SlamConfig {
                particles,
                ..SlamConfig::default()
            };
            let Ok(mut slam) = FastSlam::with_prior_map(config, 1, &scenario.map) else {
                continue;
            };
            let mut k = 0usize;
            let mut step = |slam: &mut FastSlam| {
                let scan = &scenario.scans[k % scenario.scans.len()];
                let estimate = slam.process(k as u64 * 25_000_000, scan, &[], None);
                k += 1;
                estimate
            };
            // Let the particles spread and the maps diverge as in a long run.
            for _ in 0..50 {
                step(&mut slam);
            }
            let id = BenchmarkId::new(format!("{corners}_corners"), particles);
            group.bench_function(id, |b| b.iter(|| step(&mut slam)));
        }
    }
    group.finish();
}

criterion_group!(benches, process);
criterion_main!(benches);
