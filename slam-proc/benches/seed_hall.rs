//! The speed target, measured where it is stated: the real seed-hall recording
//! (shared data), corners and lines from the feature extractor, all 400 scans through a
//! fresh filter per iteration; at the course code's 15 m range (5.6 corners a scan) and
//! at the pipeline's 25 m default (8.6). Criterion reports the time of the
//! whole pass and its throughput in scans per second; the per-scan mean is printed too.
//! Run with `RAYON_NUM_THREADS=1` for single-core figures.

use std::time::{Duration, Instant};

#[path = "../tests/common/mod.rs"]
mod common;

use common::recorded::{ScanFeatures, seed_hall_features};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use feature_proc::FeatureConfig;
use slam_proc::{FastSlam, SlamConfig};

/// One pass over the recording with a fresh filter; the time spent in `process` only.
fn pass(scans: &[ScanFeatures], particles: usize) -> Duration {
    let config = SlamConfig {
        particles,
        ..SlamConfig::default()
    };
    let Ok(mut slam) = FastSlam::new(config, 1) else {
        return Duration::ZERO;
    };
    let start = Instant::now();
    for (k, scan) in scans.iter().enumerate() {
        // No timestamps in the recording: a nominal 40 Hz.
        std::hint::black_box(slam.process(k as u64 * 25_000_000, &scan.corners, &scan.lines, None));
    }
    start.elapsed()
}

fn seed_hall(c: &mut Criterion) {
    let mut group = c.benchmark_group("seed_hall");
    group.sample_size(10);
    for max_range in [15.0, 25.0] {
        let scans = seed_hall_features(FeatureConfig {
            max_range,
            ..FeatureConfig::default()
        });
        let per_scan =
            scans.iter().map(|s| s.corners.len()).sum::<usize>() as f64 / scans.len() as f64;
        eprintln!(
            "seed-hall to {max_range} m: {} scans, {per_scan:.2} corners per scan",
            scans.len()
        );
        group.throughput(Throughput::Elements(scans.len() as u64));
        for particles in [50, 100, 1000] {
            let probe = pass(&scans, particles);
            eprintln!(
                "seed-hall to {max_range} m, {particles} particles: {:.3} ms per scan (one pass)",
                1e3 * probe.as_secs_f64() / scans.len() as f64
            );
            let id = BenchmarkId::new(format!("{max_range}m"), particles);
            group.bench_function(id, |b| {
                b.iter_custom(|iterations| (0..iterations).map(|_| pass(&scans, particles)).sum());
            });
        }
    }
    group.finish();
}

criterion_group!(benches, seed_hall);
criterion_main!(benches);
