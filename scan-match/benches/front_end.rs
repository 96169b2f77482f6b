//! Time per scan of the front end on real recordings: mit-csail (361 beams, with its
//! odometry) and seed-hall (1081 beams, no odometry). The front end keeps state, so the
//! bench replays the log in order and times each `process` call; at the end of the log it
//! starts again with a fresh front end.
//!
//!     cargo bench -p scan-match --bench front_end
//!
//! The recordings come from `$SLAM_DATA_DIR` (default `../shared/data`); a missing one is
//! reported and its bench skipped.

#[path = "../tests/support/logs.rs"]
mod logs;

use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use lidar_replay::LogFormat;
use scan_match::{FrontEnd, FrontEndConfig};

fn bench_log(
    c: &mut Criterion,
    name: &str,
    path: &Path,
    format: LogFormat,
    limit: usize,
    odometry: bool,
) {
    if !path.exists() {
        eprintln!(
            "{name}: {} is missing (set SLAM_DATA_DIR); skipped",
            path.display()
        );
        return;
    }
    let scans = match logs::load(path, format, limit) {
        Ok(scans) if !scans.is_empty() => scans,
        Ok(_) => {
            eprintln!("{name}: no scans in {}; skipped", path.display());
            return;
        }
        Err(e) => {
            eprintln!("{name}: {e:#}; skipped");
            return;
        }
    };
    let mut front_end = match FrontEnd::new(FrontEndConfig::default()) {
        Ok(front_end) => front_end,
        Err(e) => {
            eprintln!("{name}: {e}; skipped");
            return;
        }
    };
    let fresh = front_end.clone();
    let mut next = 0;
    c.bench_function(name, |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                if next == scans.len() {
                    front_end = fresh.clone();
                    next = 0;
                }
                let input = scans[next].input(odometry);
                let start = Instant::now();
                let out = front_end.process(&input);
                total += start.elapsed();
                std::hint::black_box(out.ok());
                next += 1;
            }
            total
        })
    });
}

fn front_end(c: &mut Criterion) {
    let dir = test_data::data_dir();
    bench_log(
        c,
        "mit-csail 361 beams, odometry",
        &dir.join("carmen/mit-csail.clf"),
        LogFormat::Carmen,
        usize::MAX,
        true,
    );
    bench_log(
        c,
        "seed-hall 1081 beams, no odometry",
        &dir.join("seed-hall/scans.csv"),
        LogFormat::SeedCsv,
        usize::MAX,
        false,
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(Duration::from_secs(8));
    targets = front_end
}
criterion_main!(benches);
