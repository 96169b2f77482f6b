//! The field a converged localizer weighs its particles on: by the wall faces a beam can
//! end on ([`FacedField`]), not every occupied cell: ends that sink into a thick wall would
//! otherwise score as well as ends on its face, and a forward-looking scanner would be
//! drawn ahead of its pose. Tools that judge a map as the localizer sees it use the same.

use saved_map::GridMap;
use slam_geom::Pose2;

use crate::localize::faced_field::{FacedField, faced_scan_score};
use crate::localize::likelihood_field::{BEAM_FLOOR, BeamModel, MAX_DISTANCE_M};
use crate::localize_config::LocalizeConfig;

/// The converged localizer's field: a beam end counts against the faces a beam going its
/// way can end on.
#[derive(Debug, Clone)]
pub struct TrackingField(FacedField);

impl TrackingField {
    /// The field over `grid`, with `config`'s sharp beam model (`sigma_hit`).
    pub fn new(grid: &GridMap, config: &LocalizeConfig) -> Self {
        let model = BeamModel {
            sigma_hit: config.sigma_hit,
            floor: BEAM_FLOOR,
        };
        Self(FacedField::new(grid, MAX_DISTANCE_M, model))
    }

    /// The log-likelihood of beam ends `points` (sensor frame), whose beams left the sensor
    /// at `bearings` (sensor frame, radians), from `pose`.
    pub fn scan_score(&self, points: &[[f64; 2]], bearings: &[f64], pose: &Pose2) -> f64 {
        faced_scan_score(&self.0, points, bearings, pose)
    }
}

/// The bearings (sensor frame, radians) of the beams that ended at `points`, into `out`.
pub fn beam_bearings(points: &[[f64; 2]], out: &mut Vec<f64>) {
    out.clear();
    out.extend(points.iter().map(|[x, y]| y.atan2(*x)));
}
