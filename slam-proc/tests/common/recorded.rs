//! The real recording (shared data, seed-hall) as the filter sees it: each scan's corners
//! and wall lines from the feature extractor, the scans as `lidar-replay` publishes them.

use feature_proc::{Extractor, FeatureConfig, ScanInput};
use slam_proc::{LineObservation, MeasuredCorner};

/// One scan's features, in the filter's types.
#[derive(Debug, Clone, Default)]
pub struct ScanFeatures {
    pub corners: Vec<MeasuredCorner>,
    pub lines: Vec<LineObservation>,
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
            ScanFeatures {
                corners: features
                    .corners
                    .iter()
                    .map(|c| MeasuredCorner {
                        x: c.x,
                        y: c.y,
                        heading: c.heading,
                        angle: c.angle,
                        covariance: c.covariance,
                    })
                    .collect(),
                lines: features
                    .lines
                    .iter()
                    .map(|l| LineObservation {
                        rho: l.rho,
                        theta: l.theta,
                        covariance: l.covariance,
                        start: l.start.into(),
                        end: l.end.into(),
                    })
                    .collect(),
            }
        })
        .collect()
}
