//! The field a converged localizer weighs its particles on: by the wall faces a beam can
//! end on ([`FacedField`]), or, with `faced_walls` off, every occupied cell
//! ([`LikelihoodField`]). Tools that judge a map as the localizer sees it use the same.

use map_sink::GridMap;
use slam_geom::Pose2;

use crate::localize::faced_field::{FacedField, faced_scan_score};
use crate::localize::hill_climb::scan_score;
use crate::localize::likelihood_field::{BeamModel, LikelihoodField};
use crate::localize_config::LocalizeConfig;

/// The converged localizer's field.
#[derive(Debug, Clone)]
pub enum TrackingField {
    /// Every occupied cell is a wall, seen from any side.
    Plain(LikelihoodField),
    /// A beam end counts against the faces a beam going its way can end on.
    Faced(FacedField),
}

impl TrackingField {
    /// The field `config` asks for over `grid`, with its sharp beam model (`sigma_hit`).
    pub fn new(grid: &GridMap, config: &LocalizeConfig) -> Self {
        let model = BeamModel {
            sigma_hit: config.sigma_hit,
            floor: config.beam_floor,
        };
        if config.faced_walls {
            Self::Faced(FacedField::new(grid, config.max_distance, model))
        } else {
            Self::Plain(LikelihoodField::new(grid, config.max_distance, model))
        }
    }

    /// The log-likelihood of beam ends `points` (sensor frame), whose beams left the sensor
    /// at `bearings` (sensor frame, radians; only the faced field reads them), from `pose`.
    pub fn scan_score(&self, points: &[[f64; 2]], bearings: &[f64], pose: &Pose2) -> f64 {
        match self {
            Self::Plain(field) => scan_score(field, points, pose),
            Self::Faced(field) => faced_scan_score(field, points, bearings, pose),
        }
    }
}

/// The bearings (sensor frame, radians) of the beams that ended at `points`, into `out`.
pub fn beam_bearings(points: &[[f64; 2]], out: &mut Vec<f64>) {
    out.clear();
    out.extend(points.iter().map(|[x, y]| y.atan2(*x)));
}
