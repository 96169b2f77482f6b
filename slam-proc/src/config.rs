//! The filter's settings, with defaults for a planar lidar at 10-40 Hz on a ground robot or
//! a UAV (steps up to ~0.2 m and ~0.2 rad between scans). Only what another robot, scanner or
//! log needs changed is a setting; the rest are constants in the modules that use them.

use serde::{Deserialize, Serialize};
use stage_kit::settings::{
    SettingError, check, check_counts, check_non_negative, check_positive, check_within,
};

use crate::localize_config::LocalizeConfig;

/// The FastSLAM settings a user with another robot, scanner or log changes: the particle
/// count, the front end's drift the particles spread by, how far the robot moves between
/// corner updates, and what the scanner sees. Metres and radians. Everything else is a
/// constant beside the code that uses it.
///
/// Read from the `[slam]` section of a run's TOML file; every field is optional and an
/// unknown key is an error, so a typo cannot silently leave a default in place.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlamConfig {
    /// Number of particles.
    pub particles: usize,
    /// A step the front end measured spreads the particles by the front end's drift, which
    /// grows with the path rather than with the scan count (it registers against keyframes,
    /// so a robot standing still does not drift): translation variance per metre
    /// travelled, m^2/m.
    pub measured_xy_variance_per_metre: f64,
    /// Translation variance per radian turned, m^2/rad.
    pub measured_xy_variance_per_radian: f64,
    /// Rotation variance per metre travelled, rad^2/m.
    pub measured_yaw_variance_per_metre: f64,
    /// Rotation variance per radian turned, rad^2/rad.
    pub measured_yaw_variance_per_radian: f64,
    /// With measured motion, the corners update the particles only once the robot has
    /// moved this far since the last update, metres (0: every scan). Scans a few
    /// centimetres apart see a corner from one viewpoint with one error, which counted
    /// again at every scan would make the weights and the map overconfident.
    pub update_min_distance: f64,
    /// Or turned this far, radians.
    pub update_min_rotation: f64,
    /// A corner closer than this to the robot is in view, metres (at most the sensor's
    /// range): a tentative corner in view and not seen for a few scans is dropped.
    pub view_range: f64,
    /// The scanner's field of view, centred on the robot's x axis, radians.
    pub view_fov: f64,
    /// Localization on a saved map (`slam-proc --map DIR --localize`), and the beam model
    /// that holds a run mapped on top of a saved map in its frame.
    pub localize: LocalizeConfig,
}

impl Default for SlamConfig {
    fn default() -> Self {
        Self {
            particles: 100,
            measured_xy_variance_per_metre: 1.6e-6,
            measured_xy_variance_per_radian: 1.6e-6,
            measured_yaw_variance_per_metre: 1.6e-7,
            measured_yaw_variance_per_radian: 1.6e-6,
            update_min_distance: 0.5,
            update_min_rotation: 0.25,
            view_range: 14.0,
            view_fov: 270f64.to_radians(),
            localize: LocalizeConfig::default(),
        }
    }
}

impl SlamConfig {
    /// Checks that every setting is usable; [`crate::FastSlam::new`] refuses a
    /// configuration that fails this.
    pub fn validate(&self) -> Result<(), SettingError> {
        check_positive(&stage_kit::named_fields!(self; view_range, view_fov))?;
        check_non_negative(&stage_kit::named_fields!(self;
            measured_xy_variance_per_metre, measured_xy_variance_per_radian,
            measured_yaw_variance_per_metre, measured_yaw_variance_per_radian, update_min_distance,
            update_min_rotation,
        ))?;
        // The ranges that bound the work a scan costs: the view within the sensor's reach,
        // and drift that still says something about the motion (beyond it the particles
        // scatter over the plane).
        check_within(
            &stage_kit::named_fields!(self; view_range),
            MIN_VIEW_RANGE_M..=SENSOR_REACH_M,
            "m",
        )?;
        check_within(
            &stage_kit::named_fields!(self;
                measured_xy_variance_per_metre, measured_xy_variance_per_radian,
                measured_yaw_variance_per_metre, measured_yaw_variance_per_radian,
            ),
            0.0..=MAX_DRIFT,
            "(m^2 or rad^2 per metre or radian)",
        )?;
        check_counts(&stage_kit::named_fields!(self; particles), 1..=1_000_000)?;
        let fov = self.view_fov;
        check(
            "view_fov",
            fov,
            fov <= std::f64::consts::TAU,
            "must be at most 2 pi",
        )?;
        self.localize.validate()
    }
}

/// Farther than any planar lidar measures (the longest-reaching SICK, 80 m): a radius
/// beyond it searches for what no scan can have seen.
pub const SENSOR_REACH_M: f64 = 100.0;
/// The shortest view: a corner nearer than this is inside the robot.
const MIN_VIEW_RANGE_M: f64 = 0.1;
/// A drift of a metre (or radian) per metre (or radian) of motion says nothing about the
/// motion any more.
const MAX_DRIFT: f64 = 1.0;

#[cfg(test)]
mod tests {
    use super::*;
    use stage_kit::settings::refused_field;

    #[test]
    fn defaults_are_valid() {
        assert_eq!(SlamConfig::default().validate(), Ok(()));
    }

    #[test]
    fn toml_sets_fields_and_refuses_unknown_keys() {
        let config: SlamConfig =
            toml::from_str("particles = 7\n[localize]\nmax_particles = 500").unwrap();
        let defaults = SlamConfig::default();
        assert_eq!((config.particles, config.localize.max_particles), (7, 500));
        assert_eq!(config.view_range, defaults.view_range);
        assert_eq!(
            config.localize.min_particles,
            defaults.localize.min_particles
        );
        for (text, key) in [
            ("particle = 7", "particle"),
            // A constant now, not a setting.
            ("search_radius = 1.5", "search_radius"),
            ("[localize]\nmax_partcles = 5", "max_partcles"),
        ] {
            let refusal = toml::from_str::<SlamConfig>(text).unwrap_err().to_string();
            assert!(
                refusal.contains(&format!("unknown field `{key}`")),
                "{refusal}"
            );
        }
    }

    #[test]
    fn invalid_values_name_their_field() {
        let refused = |spoil: fn(&mut SlamConfig)| refused_field(spoil, SlamConfig::validate);
        assert_eq!(refused(|_| {}), None);
        assert_eq!(refused(|c| c.particles = 0), Some("particles"));
        assert_eq!(refused(|c| c.particles = 1_000_001), Some("particles"));
        assert_eq!(
            refused(|c| c.update_min_distance = -0.5),
            Some("update_min_distance")
        );
        for (spoil, field) in [
            (
                (|c| c.view_range = 1e9) as fn(&mut SlamConfig),
                "view_range",
            ),
            (|c| c.view_range = 0.05, "view_range"),
            (|c| c.view_fov = 7.0, "view_fov"),
            (
                |c| c.measured_xy_variance_per_metre = 1e9,
                "measured_xy_variance_per_metre",
            ),
        ] {
            assert_eq!(refused(spoil), Some(field));
        }
    }
}
