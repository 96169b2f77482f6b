//! The real recording (shared data, seed-hall) as the filter sees it: each scan's corners
//! and wall lines from the feature extractor, the scans as `lidar-replay` publishes them.

use feature_proc::{Extractor, FeatureConfig, ScanInput};
use slam_proc::{MeasuredCorner, MeasuredLine};

/// One scan's features: the extractor's output, the filter's input.
#[derive(Debug, Clone, Default)]
pub struct ScanFeatures {
    pub corners: Vec<MeasuredCorner>,
    pub lines: Vec<MeasuredLine>,
}

/// Every scan's features, extracted with `config`. Panics without the recording: the
/// tests and the bench that call this are about it.
pub fn seed_hall_features(config: FeatureConfig) -> Vec<ScanFeatures> {
    let mut extractor = Extractor::new(config);
    test_data::seed_hall_scans()
        .iter()
        .map(|scan| {
            let input = ScanInput {
                geometry: scan.geometry,
                ranges: &scan.ranges,
            };
            let Ok(features) = extractor.extract(&input) else {
                return ScanFeatures::default();
            };
            // The extractor's features are the filter's input as they are.
            ScanFeatures {
                corners: features.corners.clone(),
                lines: features.lines.clone(),
            }
        })
        .collect()
}
