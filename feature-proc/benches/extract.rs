//! Extraction time of one real 1081-beam scan (seed-hall), with the default configuration.

use criterion::{Criterion, criterion_group, criterion_main};
use feature_proc::{Extractor, FeatureConfig, seed_hall};

fn extract(c: &mut Criterion) {
    let path = seed_hall::default_path();
    let scans = seed_hall::load(&path).unwrap_or_else(|e| panic!("seed-hall recording: {e}"));
    let mut extractor = Extractor::new(FeatureConfig::default());
    // A scan with a typical number of lines and corners.
    let ranges = &scans[200];
    let scan = seed_hall::scan_input(ranges);
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
            let scan = seed_hall::scan_input(&scans[next]);
            let found = extractor.extract(std::hint::black_box(&scan));
            std::hint::black_box(found.map(|f| f.corners.len()).unwrap_or(0))
        })
    });
}

criterion_group!(benches, extract);
criterion_main!(benches);
