//! Settings of localization on a saved map ([`crate::Localizer`]): the `[slam.localize]`
//! table of a run's TOML file. Only what another robot, scanner or map needs changed is a
//! setting; the rest are constants in the modules that use them.

use serde::{Deserialize, Serialize};

use stage_kit::settings::{SettingError, check, check_non_negative, check_positive};

/// Localization parameters. Metres, radians.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LocalizeConfig {
    /// Fewest particles KLD-sampling may keep (once converged).
    pub min_particles: usize,
    /// Most particles: a global start spreads this many over the free space.
    pub max_particles: usize,
    /// Beams of a scan that weight the particles, spread evenly over its valid beams.
    pub beams: usize,
    /// Standard deviation of a beam end's distance to the nearest wall once the particles
    /// have converged, metres: the scanner's noise and the map's cell together.
    pub sigma_hit: f64,
    /// The scans weight the particles once the robot is this far from where they last did,
    /// metres, ...
    pub update_min_distance: f64,
    /// ... or turned this much, radians, since they last did.
    pub update_min_rotation: f64,
    /// The particles' spread as they move by the front end's steps: translation variance
    /// per metre travelled (m^2/m) and per radian turned (m^2/rad) ... Several times what
    /// the front end's steps are off by on real logs, so that the cloud still covers a step
    /// it got wrong; not more, or along a corridor, whose walls fix little along it, the
    /// estimate wanders with the spread.
    pub xy_variance_per_metre: f64,
    pub xy_variance_per_radian: f64,
    /// ... and rotation variance per metre (rad^2/m) and per radian (rad^2/rad).
    pub yaw_variance_per_metre: f64,
    pub yaw_variance_per_radian: f64,
    /// A known start (`--initial-pose`) spreads the particles by these standard deviations.
    pub initial_sigma_xy: f64,
    pub initial_sigma_yaw: f64,
}

impl Default for LocalizeConfig {
    fn default() -> Self {
        Self {
            min_particles: 200,
            max_particles: 10_000,
            beams: 120,
            sigma_hit: 0.05,
            update_min_distance: 0.2,
            update_min_rotation: 0.1,
            xy_variance_per_metre: 0.001,
            xy_variance_per_radian: 0.002,
            yaw_variance_per_metre: 0.002,
            yaw_variance_per_radian: 0.01,
            initial_sigma_xy: 0.1,
            initial_sigma_yaw: 0.05,
        }
    }
}

/// The most particles a localizer may hold: a global start places them all, and every
/// weighting scores each; a million poses are a few tens of megabytes and seconds a scan.
pub const MAX_PARTICLES: usize = 1_000_000;

impl LocalizeConfig {
    /// Checks that every parameter is usable; [`crate::Localizer::new`] refuses one that
    /// fails this.
    pub fn validate(&self) -> Result<(), SettingError> {
        check(
            "localize.min_particles",
            self.min_particles as f64,
            self.min_particles >= 1,
            "must be at least 1",
        )?;
        check(
            "localize.max_particles",
            self.max_particles as f64,
            self.max_particles >= self.min_particles,
            "must be at least localize.min_particles",
        )?;
        check(
            "localize.max_particles",
            self.max_particles as f64,
            self.max_particles <= MAX_PARTICLES,
            "must be at most 1000000",
        )?;
        check(
            "localize.beams",
            self.beams as f64,
            self.beams >= 1,
            "must be at least 1",
        )?;
        check_positive(&stage_kit::named_fields!(self, "localize."; sigma_hit))?;
        check_non_negative(&stage_kit::named_fields!(self, "localize.";
            update_min_distance, update_min_rotation, xy_variance_per_metre,
            xy_variance_per_radian, yaw_variance_per_metre, yaw_variance_per_radian,
            initial_sigma_xy, initial_sigma_yaw,
        ))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stage_kit::settings::refused_field;

    #[test]
    fn the_particle_counts_are_bounded() {
        let refused =
            |spoil: fn(&mut LocalizeConfig)| refused_field(spoil, LocalizeConfig::validate);
        assert_eq!(refused(|_| {}), None);
        assert_eq!(
            refused(|c| c.min_particles = 0),
            Some("localize.min_particles")
        );
        assert_eq!(
            refused(|c| c.max_particles = MAX_PARTICLES + 1),
            Some("localize.max_particles")
        );
        assert_eq!(
            refused(|c| c.max_particles = c.min_particles - 1),
            Some("localize.max_particles")
        );
        assert_eq!(refused(|c| c.beams = 0), Some("localize.beams"));
        assert_eq!(refused(|c| c.sigma_hit = 0.0), Some("localize.sigma_hit"));
    }
}
