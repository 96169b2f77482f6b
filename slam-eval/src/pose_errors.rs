//! The two errors of a relative-pose score, kept together: a score has both or neither.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::stats::ErrorStats;

/// Translational and rotational errors over the same relations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseErrors {
    /// Translational error, metres.
    pub translation_m: ErrorStats,
    /// Rotational error, degrees.
    pub rotation_deg: ErrorStats,
}

impl PoseErrors {
    /// The errors of several scores taken together, each part weighted by the relations it
    /// was taken over (see [`ErrorStats::pooled`]); `None` if no part has any.
    pub fn pooled(parts: &[(usize, PoseErrors)]) -> Option<Self> {
        let pool = |pick: fn(&PoseErrors) -> ErrorStats| {
            let stats: Vec<(usize, ErrorStats)> =
                parts.iter().map(|(n, e)| (*n, pick(e))).collect();
            ErrorStats::pooled(&stats)
        };
        Some(Self {
            translation_m: pool(|e| e.translation_m)?,
            rotation_deg: pool(|e| e.rotation_deg)?,
        })
    }
}

/// Means and standard deviations, as the progress lines show them: `0.580 +- 1.782 m, 2.60
/// +- 6.04 deg`.
impl fmt::Display for PoseErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (t, r) = (&self.translation_m, &self.rotation_deg);
        write!(
            f,
            "{:.3} +- {:.3} m, {:.2} +- {:.2} deg",
            t.mean, t.std, r.mean, r.std
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pooling_keeps_translation_and_rotation_apart() {
        let part = |translation: &[f64], rotation: &[f64]| PoseErrors {
            translation_m: ErrorStats::of(translation),
            rotation_deg: ErrorStats::of(rotation),
        };
        let pooled = PoseErrors::pooled(&[
            (2, part(&[0.1, 0.3], &[1.0, 3.0])),
            (1, part(&[0.5], &[8.0])),
        ])
        .unwrap();
        assert!(
            (pooled.translation_m.mean - 0.3).abs() < 1e-12,
            "{pooled:?}"
        );
        assert!((pooled.rotation_deg.mean - 4.0).abs() < 1e-12, "{pooled:?}");
        assert_eq!(pooled.rotation_deg.max, 8.0);
        assert_eq!(PoseErrors::pooled(&[]), None);
        assert_eq!(PoseErrors::pooled(&[(0, part(&[], &[]))]), None);
        assert_eq!(pooled.to_string(), "0.300 +- 0.163 m, 4.00 +- 2.94 deg");
    }
}
