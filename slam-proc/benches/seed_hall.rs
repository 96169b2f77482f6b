//! The speed target, measured where it is stated: the real seed-hall recording
//! (shared data), corners from the feature extractor at the pipeline's default settings,
//! all 400 scans through a fresh filter per iteration. Criterion reports the time of the
//! whole pass and its throughput in scans per second; the per-scan mean is printed too.
//! Run with `RAYON_NUM_THREADS=1` for single-core figures.

use std::time::{Duration, Instant};

#[path = "../tests/common/mod.rs"]
mod common;

use common::recorded::seed_hall_corners;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use feature_proc::FeatureConfig;
use slam_proc::{FastSlam, Observation, SlamConfig};

/// One pass over the recording with a fresh filter; the time spent in `process` only.
fn pass(scans: &[Vec<Observation>], particles: usize) -> Duration {
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
        std::hint::black_box(slam.process(k as u64 * 25_000_000, scan, &[], None));
    }
    start.elapsed()
}

fn seed_hall(c: &mut Criterion) {
    let scans = seed_hall_corners(FeatureConfig::default());
    let per_scan = scans.iter().map(Vec::len).sum::<usize>() as f64 / scans.len() as f64;
    eprintln!(
        "seed-hall: {} scans, {per_scan:.2} corners per scan",
        scans.len()
    );
    let mut group = c.benchmark_group("seed_hall");
    group.sample_size(10);
    group.throughput(Throughput::Elements(scans.len() as u64));
    for particles in [50, 100, 1000] {
        let probe = pass(&scans, particles);
        eprintln!(
            "seed-hall, {particles} particles: {:.3} ms per scan (one pass)",
            1e3 * probe.as_secs_f64() / scans.len() as f64
        );
        group.bench_function(BenchmarkId::new("pass", particles), |b| {
            b.iter_custom(|iterations| (0..iterations).map(|_| pass(&scans, particles)).sum());
        });
    }
    group.finish();
}

criterion_group!(benches, seed_hall);
criterion_main!(benches);
