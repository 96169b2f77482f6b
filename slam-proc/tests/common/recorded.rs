//! The real recording (shared data, seed-hall) as the filter sees it: each scan's corners
//! from the feature extractor.

use feature_proc::{Extractor, FeatureConfig, seed_hall};
use slam_proc::Observation;

/// Every scan's corners, extracted with `config`. Panics without the recording: the tests
/// and the bench that call this are about it.
pub fn seed_hall_corners(config: FeatureConfig) -> Vec<Vec<Observation>> {
    let path = seed_hall::default_path();
    let scans = seed_hall::load(&path).unwrap_or_else(|e| {
        panic!(
            "the seed-hall recording is required at {} ({e})",
            path.display()
        )
    });
    let mut extractor = Extractor::new(config);
    scans
        .iter()
        .map(|ranges| {
            let Ok(features) = extractor.extract(&seed_hall::scan_input(ranges)) else {
                return Vec::new();
            };
            features
                .corners
                .iter()
                .map(|c| Observation {
                    x: c.x,
                    y: c.y,
                    heading: c.heading,
                    angle: c.angle,
                    covariance: c.covariance,
                })
                .collect()
        })
        .collect()
}
