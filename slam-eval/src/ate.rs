//! Absolute trajectory error after rigid alignment.

use slam_geom::{Point2, Se2Alignment, WeightedPair, align_se2};

/// The absolute trajectory error of an estimate against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AteStats {
    /// The estimate-to-truth transform the errors were measured after.
    pub alignment: Se2Alignment,
    pub rmse_m: f64,
    pub max_m: f64,
    /// Error of the last pair: how far off the run ended.
    pub final_error_m: f64,
    pub pairs: usize,
}

/// Aligns `est` to `truth` with [`align_se2`] (every pair weighted alike) and measures the
/// position errors. The slices must be paired by index (the same scans, in time order);
/// `None` when they are empty or of different lengths, since then there is nothing
/// meaningful to score. Positions that fix no rotation (one pose, or a robot that never
/// moved) are aligned by translation alone.
pub fn ate(est: &[[f64; 2]], truth: &[[f64; 2]]) -> Option<AteStats> {
    if est.is_empty() || est.len() != truth.len() {
        return None;
    }
    let pairs: Vec<WeightedPair> = est
        .iter()
        .zip(truth)
        .map(|(e, t)| (Point2::from(*e), Point2::from(*t), 1.0))
        .collect();
    let alignment = align_se2(&pairs).unwrap_or_else(|| translation_only(&pairs));
    let errors: Vec<f64> = est
        .iter()
        .zip(truth)
        .map(|(e, t)| distance(alignment.apply(*e), *t))
        .collect();
    let sum_sq: f64 = errors.iter().map(|e| e * e).sum();
    Some(AteStats {
        alignment,
        rmse_m: (sum_sq / errors.len() as f64).sqrt(),
        max_m: errors.iter().copied().fold(0.0, f64::max),
        final_error_m: errors.last().copied().unwrap_or(0.0),
        pairs: errors.len(),
    })
}

/// The shift of the mean source point onto the mean target point, for pairs that fix no
/// rotation.
fn translation_only(pairs: &[WeightedPair]) -> Se2Alignment {
    let n = pairs.len().max(1) as f64;
    let shift = pairs.iter().map(|(s, t, _)| t - s).sum::<Point2>() / n;
    Se2Alignment {
        rotation: 0.0,
        translation: [shift.x, shift.y],
    }
}

/// The distance between two points, metres.
pub fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}
