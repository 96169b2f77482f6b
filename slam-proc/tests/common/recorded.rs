//! The real recording (shared data, seed-hall) as the filter sees it: each scan's corners
//! and wall lines from the feature extractor.

use feature_proc::{Extractor, FeatureConfig, seed_hall};
use slam_proc::{LineObservation, Observation};

/// One scan's features, in the filter's types.
#[derive(Debug, Clone, Default)]
pub struct ScanFeatures {
    pub corners: Vec<Observation>,
    pub lines: Vec<LineObservation>,
}

/// Every scan's features, extracted with `config`. Panics without the recording: the
/// tests and the bench that call this are about it.
pub fn seed_hall_features(config: FeatureConfig) -> Vec<ScanFeatures> {
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
                return ScanFeatures::default();
            };
            ScanFeatures {
                corners: features
                    .corners
                    .iter()
                    .map(|c| Observation {
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
                    })
                    .collect(),
            }
        })
        .collect()
}
