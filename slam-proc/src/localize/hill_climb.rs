//! A pose moved uphill on a scan's likelihood over a saved grid's likelihood field: moves
//! in x, y and yaw, from first steps that halve level by level. The localizer's particles,
//! spread at random, climb to the best fit near them, so the true place is found with far
//! fewer particles than would have to fall on it by chance (the field is only centimetres
//! wide around the walls); mapping on a saved map keeps its particles on the saved walls by
//! the same climb from smaller steps.

use slam_geom::Pose2;

use crate::localize::likelihood_field::LikelihoodField;

/// How a pose climbs: its first steps, and how often they halve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HillClimb {
    /// First step in x and in y, metres.
    pub xy: f64,
    /// First step in yaw, radians.
    pub yaw: f64,
    /// Levels of steps, each half the last's.
    pub levels: usize,
    /// Passes over the six moves at one level, at most.
    pub passes: usize,
}

impl HillClimb {
    /// The localizer's search: wide enough to reach the true place from a particle spread
    /// at random near it.
    pub const SEARCH: Self = Self {
        xy: 0.2,
        yaw: 0.1,
        levels: 4,
        passes: 3,
    };

    /// `pose` moved uphill on the likelihood of beam ends `points` (sensor frame).
    pub fn climb(&self, field: &LikelihoodField, points: &[[f64; 2]], pose: Pose2) -> Pose2 {
        self.climb_on(|pose| scan_score(field, points, pose), pose)
    }

    /// `pose` moved uphill on `score`, a scan's log-likelihood from a pose.
    pub fn climb_on(&self, score: impl Fn(&Pose2) -> f64, pose: Pose2) -> Pose2 {
        let mut best = pose;
        let mut best_score = score(&best);
        let (mut step_xy, mut step_yaw) = (self.xy, self.yaw);
        for _ in 0..self.levels {
            for _ in 0..self.passes {
                let mut moved = false;
                for (dx, dy, dyaw) in [
                    (step_xy, 0.0, 0.0),
                    (-step_xy, 0.0, 0.0),
                    (0.0, step_xy, 0.0),
                    (0.0, -step_xy, 0.0),
                    (0.0, 0.0, step_yaw),
                    (0.0, 0.0, -step_yaw),
                ] {
                    let candidate = Pose2::new(best.x + dx, best.y + dy, best.yaw + dyaw);
                    let candidate_score = score(&candidate);
                    if candidate_score > best_score {
                        (best, best_score) = (candidate, candidate_score);
                        moved = true;
                    }
                }
                if !moved {
                    break;
                }
            }
            step_xy *= 0.5;
            step_yaw *= 0.5;
        }
        best
    }
}

/// The log-likelihood of beam ends `points` (sensor frame) seen from `pose`.
pub fn scan_score(field: &LikelihoodField, points: &[[f64; 2]], pose: &Pose2) -> f64 {
    let (s, c) = pose.yaw.sin_cos();
    points
        .iter()
        .map(|[px, py]| field.score(pose.x + c * px - s * py, pose.y + s * px + c * py))
        .sum()
}
