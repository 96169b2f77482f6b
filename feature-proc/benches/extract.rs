//! Extraction time of one real 1081-beam scan (seed-hall), with the default configuration.

#[path = "../tests/common/recorded.rs"]
mod recorded;

use criterion::{Criterion, criterion_group, criterion_main};
use feature_proc::{Extractor, FeatureConfig};
use recorded::scan_input;
use test_data::seed_hall_scans;

fn extract(c: &mut Criterion) {
    let scans = seed_hall_scans();
    let mut extractor = Extractor::new(FeatureConfig::default());
    // A scan with a typical number of lines and corners.
    let scan = scan_input(&scans[200]);
    c.bench_function("extract seed-hall scan 200", |b| {
        b.iter(|| {
            let found = extractor.extract(std::hint::black_box(&scan));
            std::hint::black_box(found.map(|f| f.corners.len()).unwrap_or(0))
        })
    });
    let mut next = 0;
    c.bench_function("extract seed-hall, all scans in turn", |b| {
        b.iter(|| {
            next = (next + 1) % scans.len();
            let scan = scan_input(&scans[next]);
            let found = extractor.extract(std::hint::black_box(&scan));
            std::hint::black_box(found.map(|f| f.corners.len()).unwrap_or(0))
        })
    });
}

criterion_group!(benches, extract);
criterion_main!(benches);
