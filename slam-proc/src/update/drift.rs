//! How far a particle may have drifted from the part of its map it saw long ago.
//!
//! FastSLAM conditions each map on its particle's path, so in theory a particle needs no
//! more pose uncertainty than its last step's. With a hundred particles, none may follow
//! the true drift over a long loop closely enough for the old corners to pass that gate,
//! and the loop would never close. A scan matcher's drift grows with the path: a revisit
//! associates the old corners under an uncertainty that grows with the path travelled
//! since they were last seen.

use nalgebra::{Matrix3, Vector3};

use crate::config::SlamConfig;

/// The pose covariance a revisit allows for after `length` metres of path: standard
/// deviations proportional to it, up to the configured largest.
pub(crate) fn revisit_covariance(length: f64, config: &SlamConfig) -> Matrix3<f64> {
    let length = length.max(0.0);
    let xy = (config.revisit_sigma_xy_per_metre * length).min(config.revisit_max_sigma_xy);
    let yaw = (config.revisit_sigma_yaw_per_metre * length).min(config.revisit_max_sigma_yaw);
    Matrix3::from_diagonal(&Vector3::new(xy * xy, xy * xy, yaw * yaw))
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
}
