//! The front end's settings: one set of defaults for every planar lidar log of the SICK /
//! Hokuyo family, derived from the sensor's noise and the motion of an indoor robot rather
//! than fitted to one recording.

use serde::{Deserialize, Serialize};

use crate::odometry_scale::OdometryScaleConfig;
use stage_kit::settings::{SettingError, check, check_counts, check_positive};

/// Every setting of [`crate::FrontEnd`]. Deserialises from a TOML/JSON table where any field
/// may be left out (its default is used) and an unknown field is an error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrontEndConfig {
    /// Standard deviation of one range reading, metres. SICK LMS and Hokuyo UTM datasheets
    /// give about 1 cm; it floors the fit's residual noise and sets the finest gate.
    pub range_sigma: f64,
    /// Edge of the voxels that thin scans and the local map, metres. A few times the range
    /// noise: finer adds points that carry the same information, coarser loses corners.
    pub voxel_size: f64,
    /// A scan with fewer usable points (valid, with a surface normal) is not matched, and
    /// a fit with fewer inliers does not overrule the odometry.
    pub min_points: usize,
    /// Widest gate between a scan point and its map neighbour, metres. Wider than any
    /// prior's plausible error at this rate; matches beyond it are clutter. Registration
    /// itself starts from a seed the correlative search has placed, and gates at six
    /// voxels at most (the search's coarse radius).
    pub max_correspondence: f64,
    /// The correlative search before registration spans the prior's 3-sigma window, but
    /// at most this far each way, metres...
    pub max_search_translation: f64,
    /// ...and this far in yaw, radians.
    pub max_search_yaw: f64,
    /// When the prior allows more than that window (a gap in the data) and the fit from
    /// it is weak, a wide search spans the prior's 3-sigma window up to this far each
    /// way, metres...
    pub recovery_translation: f64,
    /// ...and this far in yaw, radians (pi: a full turn).
    pub recovery_yaw: f64,
    /// Gauss-Newton iterations at most per scan.
    pub max_iterations: usize,
    /// The iteration stops once a step moves every point by less than this, metres: a
    /// tenth of the range noise, below which further steps change nothing measurable.
    pub convergence: f64,
    /// A new keyframe joins the local map after the robot has moved this far, metres...
    pub keyframe_distance: f64,
    /// ...or turned this much, radians.
    pub keyframe_angle: f64,
    /// Keyframes in the local map at most; the oldest leaves first.
    pub max_keyframes: usize,
    /// Without odometry, a fit that leaves a direction open adds a keyframe at least this
    /// often, seconds, however little the robot seems to have moved: what the map lacks
    /// along that direction (a door recess that came into view) may be in the scan, and
    /// the open direction's estimate (constant velocity) may be the very reason the robot
    /// seems to stand still. With odometry the wheels tell that, and keyframes by distance
    /// suffice.
    pub degenerate_keyframe_interval: f64,
    /// A direction (translation, or yaw scaled by the scan's spread) whose information is
    /// below this fraction of the strongest direction's is degenerate: left to the prior.
    pub degeneracy_ratio: f64,
    /// A match is confident enough to judge the odometry only with at least this fraction
    /// of its points as inliers.
    pub min_inlier_fraction: f64,
    /// A match overrules a contradicting odometry step only with at least this fraction of
    /// its points as inliers; a weaker one gives way to the odometry.
    pub strong_inlier_fraction: f64,
    /// Squared Mahalanobis distance between the odometry step and the match beyond which
    /// the odometry is rejected (chi-square, 3 degrees of freedom, p = 1e-6).
    pub odometry_gate: f64,
    /// Floor of the odometry step's standard deviation, metres: encoder quantisation and
    /// the timing between the odometry and the scan, which a stopped robot's zero growth
    /// of covariance would hide.
    pub odometry_min_sigma_xy: f64,
    /// The same floor for yaw, radians.
    pub odometry_min_sigma_yaw: f64,
    /// A step faster than this is not a robot's, m/s: rejected whatever its covariance.
    pub max_linear_speed: f64,
    /// Nor one turning faster than this, rad/s.
    pub max_angular_speed: f64,
    /// A wheel step that would change the wheels' pace faster than this, m/s^2, is a stale
    /// reading (odometry that lags the scan by a varying delay): the
    /// scan is registered as without odometry, and the next steps are measured from the
    /// last reading believed. Well above what a wheeled indoor robot does.
    pub max_linear_acceleration: f64,
    /// Without odometry the prior is constant velocity; its velocity may change by this
    /// much (one sigma) between scans, m/s.
    pub velocity_sigma_linear: f64,
    /// The same for the turn rate, rad/s.
    pub velocity_sigma_angular: f64,
    /// The wheels' distance scale is learnt where the scan fixes every direction, over
    /// about this much travel, metres (see [`crate::odometry_scale`]) ...
    pub odometry_scale_memory: f64,
    /// ... and used once the fits have measured this far, metres ...
    pub odometry_scale_min_evidence: f64,
    /// ... within `1 +-` this; 0 leaves the wheels' distances as they are.
    pub odometry_scale_max_correction: f64,
}

impl Default for FrontEndConfig {
    fn default() -> Self {
        Self {
            range_sigma: 0.01,
            voxel_size: 0.05,
            min_points: 30,
            max_correspondence: 0.5,
            max_search_translation: 0.5,
            max_search_yaw: 0.6,
            recovery_translation: 1.5,
            recovery_yaw: std::f64::consts::PI,
            max_iterations: 30,
            convergence: 1e-3,
            keyframe_distance: 0.3,
            keyframe_angle: 0.2,
            max_keyframes: 50,
            degenerate_keyframe_interval: 0.5,
            degeneracy_ratio: 0.02,
            min_inlier_fraction: 0.4,
            strong_inlier_fraction: 0.6,
            odometry_gate: 30.7,
            odometry_min_sigma_xy: 0.005,
            odometry_min_sigma_yaw: 0.005,
            max_linear_speed: 10.0,
            max_angular_speed: 10.0,
            max_linear_acceleration: 3.0,
            velocity_sigma_linear: 0.5,
            velocity_sigma_angular: 1.0,
            odometry_scale_memory: 50.0,
            odometry_scale_min_evidence: 5.0,
            odometry_scale_max_correction: 0.1,
        }
    }
}

impl FrontEndConfig {
    /// The odometry scale estimator's part of the settings.
    pub fn odometry_scale(&self) -> OdometryScaleConfig {
        OdometryScaleConfig {
            memory_m: self.odometry_scale_memory,
            min_evidence_m: self.odometry_scale_min_evidence,
            max_correction: self.odometry_scale_max_correction,
        }
    }

    /// Checks every field; the error names the first that is out of range.
    pub fn validate(&self) -> Result<(), SettingError> {
        check_positive(&stage_kit::named_fields!(self;
            range_sigma, voxel_size, max_correspondence, convergence, max_search_translation,
            max_search_yaw, recovery_translation, recovery_yaw, keyframe_distance, keyframe_angle,
            degenerate_keyframe_interval, degeneracy_ratio, odometry_gate, odometry_min_sigma_xy,
            odometry_min_sigma_yaw, max_linear_speed, max_angular_speed, max_linear_acceleration,
            velocity_sigma_linear, velocity_sigma_angular, odometry_scale_memory,
            odometry_scale_min_evidence,
        ))?;
        check(
            "voxel_size",
            self.voxel_size,
            self.voxel_size >= 1e-3,
            "must be at least 0.001 m",
        )?;
        check(
            "odometry_scale_max_correction",
            self.odometry_scale_max_correction,
            (0.0..0.5).contains(&self.odometry_scale_max_correction),
            "must be in [0, 0.5)",
        )?;
        check(
            "degeneracy_ratio",
            self.degeneracy_ratio,
            self.degeneracy_ratio < 1.0,
            "must be in (0, 1)",
        )?;
        check(
            "min_inlier_fraction",
            self.min_inlier_fraction,
            (0.0..=1.0).contains(&self.min_inlier_fraction),
            "must be in [0, 1]",
        )?;
        check(
            "strong_inlier_fraction",
            self.strong_inlier_fraction,
            (self.min_inlier_fraction..=1.0).contains(&self.strong_inlier_fraction),
            "must be in [min_inlier_fraction, 1]",
        )?;
        check(
            "max_correspondence",
            self.max_correspondence,
            self.max_correspondence >= self.voxel_size,
            "must be at least voxel_size",
        )?;
        check_counts(
            &stage_kit::named_fields!(self; min_points, max_iterations, max_keyframes),
            1..,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_partial_tables_fill_in() {
        FrontEndConfig::default().validate().unwrap();
        let config: FrontEndConfig = toml::from_str("voxel_size = 0.1").unwrap();
        assert_eq!(config.voxel_size, 0.1);
        assert_eq!(config.range_sigma, FrontEndConfig::default().range_sigma);
        assert!(toml::from_str::<FrontEndConfig>("voxel = 0.1").is_err());
    }

    #[test]
    fn bad_values_are_named() {
        let refused = |spoil: fn(&mut FrontEndConfig)| {
            stage_kit::settings::refused_field(spoil, FrontEndConfig::validate)
        };
        assert_eq!(refused(|c| c.range_sigma = -1.0), Some("range_sigma"));
        assert_eq!(refused(|c| c.max_keyframes = 0), Some("max_keyframes"));
        assert_eq!(
            refused(|c| c.max_linear_acceleration = 0.0),
            Some("max_linear_acceleration")
        );
        assert_eq!(
            refused(|c| c.odometry_scale_max_correction = 0.5),
            Some("odometry_scale_max_correction")
        );
        assert_eq!(
            refused(|c| c.degeneracy_ratio = f64::NAN),
            Some("degeneracy_ratio")
        );
        assert_eq!(
            refused(|c| c.max_correspondence = 0.01),
            Some("max_correspondence")
        );
    }
}
