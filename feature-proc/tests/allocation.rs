//! Once its buffers have grown to the scans' size, extraction allocates nothing.

mod common;

use common::recorded::scan_input;
use feature_proc::{Extractor, FeatureConfig};
use test_data::seed_hall_scans;

#[test]
fn the_hot_path_does_not_allocate() {
    let scans = seed_hall_scans();
    let mut extractor = Extractor::new(FeatureConfig::default());
    let inputs: Vec<_> = scans.iter().map(scan_input).collect();
    let mut corners = 0;
    let mut extract_all = |extractor: &mut Extractor| {
        for input in &inputs {
            corners += extractor.extract(input).map_or(0, |f| f.corners.len());
        }
    };
    // The first pass grows the buffers to the largest scan.
    extract_all(&mut extractor);
    let second = allocation_counter::measure(|| extract_all(&mut extractor));
    assert!(corners > 0);
    assert_eq!(
        second.count_total,
        0,
        "{} allocations in {} scans",
        second.count_total,
        inputs.len()
    );
}
