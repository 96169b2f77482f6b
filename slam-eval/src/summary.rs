//! The score without its per-relation detail, as other programs store and read it back.

use serde::{Deserialize, Serialize};

use crate::pose_errors::PoseErrors;
use crate::score::Score;

/// What a run's metrics keep of a [`Score`]: the counts and the errors. The errors are
/// `None` when no relation had both poses, so an empty score never reads as a perfect one.
/// In JSON they stand beside the counts (`translation_m`, `rotation_deg`), absent when
/// `None`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreSummary {
    /// Relations in the file.
    pub relations: usize,
    /// Relations scored (both poses found).
    pub used: usize,
    /// Relations without a pose within the tolerance at one end or both.
    pub unmatched: usize,
    #[serde(flatten)]
    pub errors: Option<PoseErrors>,
}

impl From<&Score> for ScoreSummary {
    fn from(score: &Score) -> Self {
        Self {
            relations: score.relations,
            used: score.used,
            unmatched: score.unmatched.len(),
            errors: (score.used > 0).then_some(PoseErrors {
                translation_m: score.translation_m,
                rotation_deg: score.rotation_deg,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::ErrorStats;

    fn summary(errors: Option<PoseErrors>) -> ScoreSummary {
        ScoreSummary {
            relations: 3,
            used: if errors.is_some() { 2 } else { 0 },
            unmatched: 1,
            errors,
        }
    }

    #[test]
    fn the_errors_stand_beside_the_counts_in_json_and_read_back() {
        let errors = PoseErrors {
            translation_m: ErrorStats::of(&[0.1, 0.2]),
            rotation_deg: ErrorStats::of(&[1.0, 2.0]),
        };
        let scored = summary(Some(errors));
        let json: serde_json::Value = serde_json::to_value(scored).unwrap();
        assert_eq!(json["translation_m"]["max"], 0.2);
        assert_eq!(json["rotation_deg"]["mean"], 1.5);
        assert_eq!(
            serde_json::from_value::<ScoreSummary>(json).unwrap(),
            scored
        );

        let unscored = summary(None);
        let json: serde_json::Value = serde_json::to_value(unscored).unwrap();
        assert!(json.get("translation_m").is_none(), "{json}");
        assert_eq!(
            serde_json::from_value::<ScoreSummary>(json).unwrap(),
            unscored
        );
    }

    #[test]
    fn a_summary_written_with_null_errors_reads_as_unscored() {
        let json =
            r#"{"relations":3,"used":0,"unmatched":3,"translation_m":null,"rotation_deg":null}"#;
        let read: ScoreSummary = serde_json::from_str(json).unwrap();
        assert_eq!(read.errors, None);
        assert_eq!(read.unmatched, 3);
    }
}
