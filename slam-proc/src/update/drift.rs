//! How far a particle may have drifted from the part of its map it saw long ago.
//!
//! FastSLAM conditions each map on its particle's path, so in theory a particle needs no
//! more pose uncertainty than its last step's. With a hundred particles, none may follow
//! the true drift over a long loop closely enough for the old corners to pass that gate,
//! and the loop would never close. A scan matcher's drift grows with the path: a revisit
//! associates the old corners under an uncertainty that grows with the path travelled
//! since they were last seen.

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

use crate::config::SlamConfig;

/// The pose covariance a revisit allows for after `length` metres of path: standard
/// deviations proportional to it, up to the configured largest.
pub(crate) fn revisit_covariance(length: f64, config: &SlamConfig) -> Matrix3<f64> {
    let length = length.max(0.0);
    let xy = (config.revisit_sigma_xy_per_metre * length).min(config.revisit_max_sigma_xy);
    let yaw = (config.revisit_sigma_yaw_per_metre * length).min(config.revisit_max_sigma_yaw);
    Matrix3::from_diagonal(&Vector3::new(xy * xy, xy * xy, yaw * yaw))
}

/// Whether a revisit's `jump` (the landing's translation from the prediction, map frame)
/// lies within the `probability` region of the pose uncertainty it was associated under
/// (`covariance`, the allowance included): chi-square with 2 dof, whose quantile is
/// `-2 ln(1 - p)`. A covariance that cannot be inverted bounds nothing.
pub(crate) fn jump_within(
    jump: &Vector2<f64>,
    covariance: &Matrix3<f64>,
    probability: f64,
) -> bool {
    let xy: Matrix2<f64> = covariance.fixed_view::<2, 2>(0, 0).into();
    let Some(information) = xy.try_inverse() else {
        return true;
    };
    let squared = jump.dot(&(information * jump));
    squared <= -2.0 * (1.0 - probability).ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_allowance_grows_with_the_path_up_to_its_cap() {
        let config = SlamConfig {
            revisit_sigma_xy_per_metre: 0.02,
            revisit_sigma_yaw_per_metre: 0.002,
            revisit_max_sigma_xy: 3.0,
            revisit_max_sigma_yaw: 0.2,
            ..SlamConfig::default()
        };
        let p = revisit_covariance(50.0, &config);
        assert!((p[(0, 0)].sqrt() - 1.0).abs() < 1e-12);
        assert_eq!(p[(0, 0)], p[(1, 1)]);
        assert!((p[(2, 2)].sqrt() - 0.1).abs() < 1e-12);
        let far = revisit_covariance(1000.0, &config);
        assert!((far[(0, 0)].sqrt() - 3.0).abs() < 1e-12);
        assert!((far[(2, 2)].sqrt() - 0.2).abs() < 1e-12);
        assert_eq!(revisit_covariance(-1.0, &config), Matrix3::zeros());
    }

    #[test]
    fn a_jump_is_bounded_by_the_allowance_at_the_probability_asked() {
        // 2 m a side: the 95 % region of 2 dof reaches sqrt(5.99) = 2.45 sigma, 4.9 m.
        let covariance = Matrix3::from_diagonal(&Vector3::new(4.0, 4.0, 0.01));
        assert!(jump_within(&Vector2::new(3.2, 0.0), &covariance, 0.95));
        assert!(jump_within(&Vector2::new(3.4, -3.4), &covariance, 0.95));
        assert!(!jump_within(&Vector2::new(3.5, -3.5), &covariance, 0.95));
        assert!(!jump_within(&Vector2::new(0.0, 5.7), &covariance, 0.95));
        // The same jump is inside a wider region.
        assert!(jump_within(&Vector2::new(0.0, 5.7), &covariance, 0.99));
        // A degenerate covariance bounds nothing.
        assert!(jump_within(
            &Vector2::new(50.0, 0.0),
            &Matrix3::zeros(),
            0.95
        ));
    }
}
