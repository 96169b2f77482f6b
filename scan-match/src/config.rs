//! The front end's settings: one set of defaults for every planar lidar log of the SICK /
//! Hokuyo family, derived from the sensor's noise and the motion of an indoor robot rather
//! than fitted to one recording. Only what another scanner or robot needs changed is a
//! setting; the rest are constants in the modules that use them.

use serde::{Deserialize, Serialize};

use crate::front_end::MAX_CORRESPONDENCE;
use crate::odometry_scale::{
    ODOMETRY_SCALE_MEMORY_M, ODOMETRY_SCALE_MIN_EVIDENCE_M, OdometryScaleConfig,
};
use stage_kit::settings::{SettingError, check, check_positive, check_within};

/// The settings of [`crate::FrontEnd`] a user with another scanner or robot changes: the
/// scanner's noise, the map's resolution, the keyframes' spacing and the robot's motion.
/// Everything else is a constant beside the code that uses it. Deserialises from a TOML/JSON
/// table where any field may be left out (its default is used) and an unknown field is an
/// error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrontEndConfig {
    /// Standard deviation of one range reading, metres. SICK LMS and Hokuyo UTM datasheets
    /// give about 1 cm; it floors the fit's residual noise and sets the finest gate. The
    /// corner extractor (`[features]`) reads it too.
    pub range_sigma: f64,
    /// Edge of the voxels that thin scans and the local map, metres. A few times the range
    /// noise: finer adds points that carry the same information, coarser loses corners.
    pub voxel_size: f64,
    /// A new keyframe joins the local map after the robot has moved this far, metres...
    pub keyframe_distance: f64,
    /// ...or turned this much, radians.
    pub keyframe_angle: f64,
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
    /// The wheels' distance scale, learnt where the scan fixes every direction (see
    /// [`crate::odometry_scale`]), is kept within `1 +-` this; 0 leaves the wheels'
    /// distances as they are.
    pub odometry_scale_max_correction: f64,
}

impl Default for FrontEndConfig {
    fn default() -> Self {
        Self {
            range_sigma: 0.01,
            voxel_size: 0.05,
            keyframe_distance: 0.3,
            keyframe_angle: 0.2,
            max_linear_speed: 10.0,
            max_angular_speed: 10.0,
            max_linear_acceleration: 3.0,
            velocity_sigma_linear: 0.5,
            velocity_sigma_angular: 1.0,
            odometry_scale_max_correction: 0.1,
        }
    }
}

impl FrontEndConfig {
    /// The odometry scale estimator's part of the settings.
    pub fn odometry_scale(&self) -> OdometryScaleConfig {
        OdometryScaleConfig {
            memory_m: ODOMETRY_SCALE_MEMORY_M,
            min_evidence_m: ODOMETRY_SCALE_MIN_EVIDENCE_M,
            max_correction: self.odometry_scale_max_correction,
        }
    }

    /// Checks every field; the error names the first that is out of range.
    pub fn validate(&self) -> Result<(), SettingError> {
        check_positive(&stage_kit::named_fields!(self;
            range_sigma, voxel_size, keyframe_distance, keyframe_angle, max_linear_speed,
            max_angular_speed, max_linear_acceleration, velocity_sigma_linear,
            velocity_sigma_angular,
        ))?;
        check(
            "voxel_size",
            self.voxel_size,
            self.voxel_size >= 1e-3,
            "must be at least 0.001 m",
        )?;
        // A scan point's map neighbour is up to a voxel away: the widest gate must reach it.
        check_within(
            &stage_kit::named_fields!(self; voxel_size),
            0.0..=MAX_CORRESPONDENCE,
            "m (at most the widest correspondence gate)",
        )?;
        check(
            "odometry_scale_max_correction",
            self.odometry_scale_max_correction,
            (0.0..0.5).contains(&self.odometry_scale_max_correction),
            "must be in [0, 0.5)",
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
        assert_eq!(refused(|c| c.voxel_size = 0.6), Some("voxel_size"));
        assert_eq!(
            refused(|c| c.max_linear_acceleration = 0.0),
            Some("max_linear_acceleration")
        );
        assert_eq!(
            refused(|c| c.odometry_scale_max_correction = 0.5),
            Some("odometry_scale_max_correction")
        );
        assert_eq!(
            refused(|c| c.keyframe_distance = f64::NAN),
            Some("keyframe_distance")
        );
    }
}
