//! How well the map's corners match the world's true corners.

use crate::ate::distance;

/// RMSE over `points` of each one's distance to the nearest of `targets`; the points must
/// already be in the targets' frame. `None` when either set is empty.
///
/// Nearest-neighbour rather than a one-to-one assignment: a duplicated map corner still
/// scores its position error, and a missing one is not a position error at all (the number
/// of corners is reported on its own).
pub fn nearest_rmse(points: &[[f64; 2]], targets: &[[f64; 2]]) -> Option<f64> {
    if points.is_empty() || targets.is_empty() {
        return None;
    }
    let sum_sq: f64 = points
        .iter()
        .map(|p| {
            targets
                .iter()
                .map(|t| distance(*p, *t))
                .fold(f64::INFINITY, f64::min)
                .powi(2)
        })
        .sum();
    Some((sum_sq / points.len() as f64).sqrt())
}
