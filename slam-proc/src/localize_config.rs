//! Settings of localization on a saved map ([`crate::Localizer`]): the `[slam.localize]`
//! table of a run's TOML file.

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
    /// KLD-sampling's bound on the divergence between the particles and the posterior.
    pub kld_epsilon: f64,
    /// Upper standard normal quantile of KLD-sampling's confidence (2.326: 99 %).
    pub kld_z: f64,
    /// KLD-sampling's histogram bins: edge in x and y, metres, and in yaw, radians.
    pub kld_bin_xy: f64,
    pub kld_bin_yaw: f64,
    /// Beams of a scan that weight the particles, spread evenly over its valid beams.
    pub beams: usize,
    /// Standard deviation of a beam end's distance to the nearest wall, metres, once the
    /// particles have converged ...
    pub sigma_hit: f64,
    /// ... and while they search.
    pub search_sigma_hit: f64,
    /// Once converged, a beam end is scored against the wall faces a beam going its way
    /// can end on (an occupied cell with free space on the side it comes from, and the
    /// cell behind it), not against every occupied cell: ends that sink into a thick wall
    /// would otherwise score as well as ends on its face, and a forward-looking scanner
    /// would be drawn ahead of its pose.
    pub faced_walls: bool,
    /// A beam end far from every wall still scores this (relative to one on a wall at 1):
    /// unmapped things and people in the way cost a bounded amount.
    pub beam_floor: f64,
    /// Each beam's log-likelihood is multiplied by this: beams of one scan are not
    /// independent (AMCL cubes and sums for the same reason), and a cloud that believes
    /// every beam collapses before the robot has moved enough to tell places apart.
    pub beam_exponent: f64,
    /// A scan's likelihood is tempered (its exponent lowered) so that at least this fraction
    /// of the particles stays effective: no single scan collapses a spread cloud.
    pub min_effective_fraction: f64,
    /// While the particles have not converged, move each uphill on the scan's likelihood
    /// before weighting it (a few steps of halving size): a global start then needs far
    /// fewer particles than would have to fall on the true pose by chance.
    pub refine_while_searching: bool,
    /// The refinement scores every this many of the weighting beams (it runs on every
    /// particle dozens of times).
    pub refine_beam_stride: usize,
    /// Distance at which the field stops growing, metres.
    pub max_distance: f64,
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
    /// Converged: the weighted particles' position spread (the larger standard deviation of
    /// their x-y covariance) under this, metres, ...
    pub converged_sigma_xy: f64,
    /// ... and their yaw spread under this, radians.
    pub converged_sigma_yaw: f64,
    /// Once converged, the particles count as lost only when their spread exceeds this
    /// many times `converged_sigma_xy` or `converged_sigma_yaw`: a cloud that widens for a
    /// moment (the front end's step was off, a corridor says little along itself) keeps
    /// tracking on the sharp field instead of falling back to the global search, whose
    /// smooth field and wide hill-climbing steps can carry it to another place.
    pub lost_sigma_factor: f64,
}

impl Default for LocalizeConfig {
    fn default() -> Self {
        Self {
            min_particles: 200,
            max_particles: 10_000,
            kld_epsilon: 0.05,
            kld_z: 2.326,
            kld_bin_xy: 0.5,
            kld_bin_yaw: 10f64.to_radians(),
            beams: 120,
            sigma_hit: 0.05,
            search_sigma_hit: 0.2,
            faced_walls: true,
            beam_floor: 0.1,
            beam_exponent: 0.3,
            min_effective_fraction: 0.1,
            refine_while_searching: true,
            refine_beam_stride: 4,
            max_distance: 1.0,
            update_min_distance: 0.2,
            update_min_rotation: 0.1,
            xy_variance_per_metre: 0.001,
            xy_variance_per_radian: 0.002,
            yaw_variance_per_metre: 0.002,
            yaw_variance_per_radian: 0.01,
            initial_sigma_xy: 0.1,
            initial_sigma_yaw: 0.05,
            converged_sigma_xy: 0.15,
            converged_sigma_yaw: 0.05,
            lost_sigma_factor: 2.0,
        }
    }
}

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
            "localize.beams",
            self.beams as f64,
            self.beams >= 1,
            "must be at least 1",
        )?;
        check(
            "localize.lost_sigma_factor",
            self.lost_sigma_factor,
            self.lost_sigma_factor >= 1.0,
            "must be at least 1",
        )?;
        check(
            "localize.min_effective_fraction",
            self.min_effective_fraction,
            (0.0..1.0).contains(&self.min_effective_fraction),
            "must be in [0, 1)",
        )?;
        check_positive(&stage_kit::named_fields!(self, "localize.";
            kld_epsilon, kld_bin_xy, kld_bin_yaw, sigma_hit, search_sigma_hit, beam_floor,
            beam_exponent, max_distance, converged_sigma_xy, converged_sigma_yaw,
        ))?;
        check_non_negative(&stage_kit::named_fields!(self, "localize.";
            kld_z, update_min_distance, update_min_rotation, xy_variance_per_metre,
            xy_variance_per_radian, yaw_variance_per_metre, yaw_variance_per_radian,
            initial_sigma_xy, initial_sigma_yaw,
        ))?;
        Ok(())
    }
}
