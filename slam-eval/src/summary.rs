//! The score without its per-relation detail, as other programs store and read it back.

use serde::{Deserialize, Serialize};

use crate::score::Score;
use crate::stats::ErrorStats;

/// What a run's metrics keep of a [`Score`]: the counts and the error statistics. The
/// statistics are `None` when no relation had both poses, so an empty score never reads as
/// a perfect one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreSummary {
    /// Relations in the file.
    pub relations: usize,
    /// Relations scored (both poses found).
    pub used: usize,
    /// Relations without a pose within the tolerance at one end or both.
    pub unmatched: usize,
    /// Translational error, metres.
    pub translation_m: Option<ErrorStats>,
    /// Rotational error, degrees.
    pub rotation_deg: Option<ErrorStats>,
}

impl From<&Score> for ScoreSummary {
    fn from(score: &Score) -> Self {
        let scored = score.used > 0;
        Self {
            relations: score.relations,
            used: score.used,
            unmatched: score.unmatched.len(),
            translation_m: scored.then_some(score.translation_m),
            rotation_deg: scored.then_some(score.rotation_deg),
        }
    }
}
