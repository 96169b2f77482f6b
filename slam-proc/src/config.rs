//! Every parameter of the filter, with defaults for a planar lidar at 10-40 Hz on a ground
//! robot or a UAV (steps up to ~0.2 m and ~0.2 rad between scans).

use serde::{Deserialize, Serialize};
use stage_kit::settings::{
    SettingError, check, check_counts, check_non_negative, check_positive, check_within,
};

use crate::localize_config::LocalizeConfig;

/// FastSLAM parameters. Metres, radians, probabilities in `(0, 1)`.
///
/// Read from the `[slam]` section of a run's TOML file; every field is optional and an
/// unknown key is an error, so a typo cannot silently leave a default in place.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlamConfig {
    /// Number of particles.
    pub particles: usize,
    /// Resample when the effective number of particles falls below this fraction of the
    /// particle count. Resampling only then keeps diversity that constant resampling loses.
    pub resample_threshold: f64,

    /// Largest believable translation between consecutive scans, metres. A corner fit
    /// beyond it is a wrong match, and the prior is used instead.
    pub motion_max_translation: f64,
    /// Largest believable rotation between consecutive scans, radians.
    pub motion_max_rotation: f64,
    /// Standard deviation of the constant-velocity prior's translation, metres. Generous:
    /// it only has to keep the true matches inside the gate.
    pub motion_prior_sigma_xy: f64,
    /// Standard deviation of the constant-velocity prior's rotation, radians.
    pub motion_prior_sigma_yaw: f64,
    /// Standard deviation of the prior's translation when wall lines are matched between
    /// consecutive scans, metres (at most the prior's own). Lines match on two numbers, not
    /// four like corners, and parallel walls alias: they need a tighter prior.
    pub line_prior_sigma_xy: f64,
    /// Standard deviation of the prior's rotation for line matching, radians.
    pub line_prior_sigma_yaw: f64,
    /// Gate for candidate matches between consecutive scans under the motion prior.
    pub motion_gate_probability: f64,
    /// Gate for inliers of a motion hypothesis (no prior uncertainty left).
    pub motion_inlier_probability: f64,
    /// Candidate matches kept per corner of the current scan, best first. Bounds the
    /// hypotheses of the robust fit, which tries every pair of candidates.
    pub motion_candidates: usize,
    /// Smallest standard deviation of an odometry increment's translation, metres: a
    /// reported covariance that does not grow would otherwise make the prior absolute.
    pub odometry_min_sigma_xy: f64,
    /// Smallest standard deviation of an odometry increment's rotation, radians.
    pub odometry_min_sigma_yaw: f64,

    /// Particle translation noise per step, at most (the model): `sigma = base + per_metre
    /// * |t| + per_radian * |dyaw|`.
    pub noise_xy_base: f64,
    pub noise_xy_per_metre: f64,
    pub noise_xy_per_radian: f64,
    /// Particle rotation noise per step: `sigma = base + per_radian * |dyaw| + per_metre * |t|`.
    pub noise_yaw_base: f64,
    pub noise_yaw_per_radian: f64,
    pub noise_yaw_per_metre: f64,
    /// After association, draw each particle's pose from the Gaussian posterior of its
    /// prediction (covariance: the motion noise) given the corners it associated, as the
    /// FastSLAM 2.0 proposal does (Montemerlo et al. 2003), instead of keeping the
    /// prediction. The particles then stay where their scans put them and far fewer lose
    /// their weight. The posterior is centred on each particle's noisy prediction rather
    /// than on the noise-free one: that keeps more diversity.
    pub observation_proposal: bool,
    /// A corner-fitted step spreads the particles by this multiple of the fit's own
    /// standard deviations (within the model above): the fit knows how well it did.
    pub noise_fit_scale: f64,
    /// Move the particles by the front end's measured motion when the features bring one
    /// (scan matching fused with odometry), instead of estimating the motion from the
    /// scan's corners and lines.
    pub use_measured_motion: bool,
    /// A measured step spreads the particles by the front end's drift, which grows with
    /// the path rather than with the scan count (it registers against keyframes, so a
    /// robot standing still does not drift): translation variance per metre travelled,
    /// m^2/m.
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
    /// Smallest translation noise of a fitted step, metres: particles must stay diverse.
    pub noise_xy_floor: f64,
    /// Smallest rotation noise of a fitted step, radians.
    pub noise_yaw_floor: f64,
    /// Noise multiplier for a step at constant velocity (no corner fit, no odometry): the
    /// motion is a guess, so the particles must spread wider. A step on odometry alone
    /// spreads by the odometry's reported uncertainty, at least as wide as a fitted step.
    pub fallback_noise_scale: f64,

    /// Added in quadrature to each observation's position standard deviation, metres:
    /// covers what the extractor's propagated covariance leaves out (wall roughness,
    /// timing, a moving sensor).
    pub observation_extra_sigma_xy: f64,
    /// Added in quadrature to each observation's heading and angle standard deviations.
    pub observation_extra_sigma_angle: f64,

    /// Gate probability of the individual (4 dof) and joint (4k dof) chi-square tests.
    pub association_probability: f64,
    /// Map corners farther than this from an observation's predicted position are not
    /// considered for it, metres. Must cover the gate: pose and corner uncertainty at range.
    pub search_radius: f64,
    /// Cell size of each map's spatial hash grid, metres. At least twice the search radius
    /// keeps a query to four cells.
    pub grid_cell_size: f64,
    /// Search nodes JCBB may visit per particle and scan before it settles for the best
    /// hypothesis found so far. Bounds the time of pathological scans.
    pub jcbb_max_nodes: usize,

    /// Log density of an observation that no map corner explains (a new or spurious
    /// corner), over `(x, y, heading, angle)`. Roughly `-ln(visible area * 2 pi * pi)`.
    pub new_corner_log_likelihood: f64,
    /// Observations after which a corner is confirmed; before that it is tentative, left
    /// out of the published map and dropped when it is not seen again.
    pub confirm_observations: u32,
    /// A tentative corner is dropped after this many scans in which it was in view and not
    /// observed.
    pub tentative_max_misses: u32,
    /// A corner closer than this to the robot is in view, metres (at most the sensor's range).
    pub view_range: f64,
    /// Field of view, centred on the robot's x axis, radians.
    pub view_fov: f64,
    /// An unexplained observation within this distance of a map corner of similar heading
    /// starts no new corner (it is that corner, seen badly), metres.
    pub duplicate_radius: f64,
    /// Headings closer than this are similar for the duplicate test, radians.
    pub duplicate_heading: f64,
    /// Mapping on a saved map (`--map DIR` without `--localize`): at every corner update,
    /// each particle climbs this scan's likelihood on the saved grid (the localizer's
    /// field and beam model, `[slam.localize]`'s `sigma_hit`, `beam_floor` and
    /// `max_distance`) before its corners correct it, so the new run stays in the saved
    /// map's frame between corner sightings instead of drifting with the front end.
    pub saved_grid_refine: bool,
    /// The particle moves this fraction of the way to the grid's best fit, in (0, 1]: less
    /// than all of it smooths the fit's own jitter out of the path.
    pub saved_grid_pull: f64,
    /// ... and the scan's likelihood on the saved grid, times this, joins each particle's
    /// log weight (per beam, as `localize.beam_exponent`; 0: not weighted by the grid).
    pub saved_grid_weight: f64,
    /// Beams of a scan that fit the particles to the saved grid, spread evenly over its
    /// valid beams.
    pub saved_grid_beams: usize,
    /// Only the beams that end in the saved grid's seen cells count (from the best
    /// particle's pose: the same beams for every particle); with fewer than this fraction
    /// of them the grid is left out of the scan. High: at the saved map's edge the grid
    /// holds walls seen from afar, and a climb on a few of them pulls the run off its own.
    pub saved_grid_min_known: f64,
    /// Back on the saved grid after this much path off it, metres, the particles may have
    /// drifted beyond the tracking climb's reach: they climb once from the localizer's
    /// wider search steps, and take the fit if it lies within three standard deviations
    /// of what the front end can have drifted over the path off the grid.
    pub saved_grid_search_after: f64,
    /// That drift: translation standard deviation per metre of path off the grid, m/m.
    pub saved_grid_drift_xy_per_metre: f64,
    /// Rotation standard deviation per metre of path off the grid, rad/m.
    pub saved_grid_drift_yaw_per_metre: f64,
    /// The largest translation standard deviation of that drift, metres.
    pub saved_grid_max_drift_xy: f64,
    /// The largest rotation standard deviation of that drift, radians.
    pub saved_grid_max_drift_yaw: f64,
    /// Localization on a saved map (`slam-proc --map DIR --localize`).
    pub localize: LocalizeConfig,
}

impl Default for SlamConfig {
    fn default() -> Self {
        Self {
            particles: 100,
            resample_threshold: 0.5,
            motion_max_translation: 0.5,
            motion_max_rotation: 0.5,
            motion_prior_sigma_xy: 0.25,
            motion_prior_sigma_yaw: 0.25,
            line_prior_sigma_xy: 0.05,
            line_prior_sigma_yaw: 0.05,
            motion_gate_probability: 0.999,
            motion_inlier_probability: 0.99,
            motion_candidates: 4,
            odometry_min_sigma_xy: 0.005,
            odometry_min_sigma_yaw: 0.002,
            noise_xy_base: 0.01,
            noise_xy_per_metre: 0.05,
            noise_xy_per_radian: 0.02,
            noise_yaw_base: 0.004,
            noise_yaw_per_radian: 0.05,
            noise_yaw_per_metre: 0.01,
            noise_fit_scale: 2.0,
            use_measured_motion: true,
            measured_xy_variance_per_metre: 1.6e-6,
            measured_xy_variance_per_radian: 1.6e-6,
            measured_yaw_variance_per_metre: 1.6e-7,
            measured_yaw_variance_per_radian: 1.6e-6,
            update_min_distance: 0.5,
            update_min_rotation: 0.25,
            noise_xy_floor: 0.002,
            noise_yaw_floor: 0.0005,
            fallback_noise_scale: 3.0,
            observation_proposal: true,
            observation_extra_sigma_xy: 0.01,
            observation_extra_sigma_angle: 0.01,
            association_probability: 0.999,
            search_radius: 1.5,
            grid_cell_size: 3.0,
            jcbb_max_nodes: 10_000,
            new_corner_log_likelihood: -9.0,
            confirm_observations: 2,
            tentative_max_misses: 3,
            view_range: 14.0,
            view_fov: 270f64.to_radians(),
            duplicate_radius: 0.5,
            duplicate_heading: 30f64.to_radians(),
            saved_grid_refine: true,
            saved_grid_pull: 0.5,
            saved_grid_weight: 0.0,
            saved_grid_beams: 120,
            saved_grid_min_known: 0.8,
            saved_grid_search_after: 10.0,
            saved_grid_drift_xy_per_metre: 0.02,
            saved_grid_drift_yaw_per_metre: 0.002,
            saved_grid_max_drift_xy: 3.0,
            saved_grid_max_drift_yaw: 0.2,
            localize: LocalizeConfig::default(),
        }
    }
}

impl SlamConfig {
    /// Checks that every parameter is usable; [`crate::FastSlam::new`] refuses a
    /// configuration that fails this.
    pub fn validate(&self) -> Result<(), SettingError> {
        self.validate_extents()?;
        check_positive(&stage_kit::named_fields!(self;
            motion_max_translation, motion_max_rotation, motion_prior_sigma_xy,
            motion_prior_sigma_yaw, line_prior_sigma_xy, line_prior_sigma_yaw,
            odometry_min_sigma_xy, odometry_min_sigma_yaw, noise_xy_base, noise_yaw_base,
            noise_fit_scale, noise_xy_floor, noise_yaw_floor, search_radius, grid_cell_size,
            view_range, view_fov,
        ))?;
        check_non_negative(&stage_kit::named_fields!(self;
            noise_xy_per_metre, noise_xy_per_radian, noise_yaw_per_radian, noise_yaw_per_metre,
            observation_extra_sigma_xy, observation_extra_sigma_angle, duplicate_radius,
            duplicate_heading, measured_xy_variance_per_metre, measured_xy_variance_per_radian,
            measured_yaw_variance_per_metre, measured_yaw_variance_per_radian, update_min_distance,
            update_min_rotation, saved_grid_weight, saved_grid_search_after,
            saved_grid_drift_xy_per_metre, saved_grid_drift_yaw_per_metre,
            saved_grid_max_drift_xy, saved_grid_max_drift_yaw,
        ))?;
        check(
            "saved_grid_pull",
            self.saved_grid_pull,
            self.saved_grid_pull > 0.0 && self.saved_grid_pull <= 1.0,
            "must be in (0, 1]",
        )?;
        check(
            "saved_grid_min_known",
            self.saved_grid_min_known,
            (0.0..=1.0).contains(&self.saved_grid_min_known),
            "must be in [0, 1]",
        )?;
        let probabilities = [
            ("motion_gate_probability", self.motion_gate_probability),
            ("motion_inlier_probability", self.motion_inlier_probability),
            ("association_probability", self.association_probability),
        ];
        for (field, value) in probabilities {
            check(
                field,
                value,
                value > 0.0 && value < 1.0,
                "must be in (0, 1)",
            )?;
        }
        let r = self.resample_threshold;
        check(
            "resample_threshold",
            r,
            (0.0..=1.0).contains(&r),
            "must be in [0, 1]",
        )?;
        let s = self.fallback_noise_scale;
        check(
            "fallback_noise_scale",
            s,
            s.is_finite() && s >= 1.0,
            "must be finite and >= 1",
        )?;
        let l = self.new_corner_log_likelihood;
        check(
            "new_corner_log_likelihood",
            l,
            l.is_finite(),
            "must be finite",
        )?;
        check_counts(&stage_kit::named_fields!(self; particles), 1..=1_000_000)?;
        check_counts(&stage_kit::named_fields!(self; motion_candidates), 1..=64)?;
        check_counts(&stage_kit::named_fields!(self; jcbb_max_nodes), 1..)?;
        let confirm = usize::try_from(self.confirm_observations).unwrap_or(usize::MAX);
        check_counts(&[("confirm_observations", confirm)], 1..)?;
        let fov = self.view_fov;
        check(
            "view_fov",
            fov,
            fov <= std::f64::consts::TAU,
            "must be at most 2 pi",
        )?;
        self.localize.validate()
    }

    /// The ranges that bound the work a scan costs: distances within the sensor's reach
    /// and a corner lookup's span of grid cells, drift and noise that still say something
    /// about the motion (beyond them the particles scatter over the plane and the grid
    /// with them).
    fn validate_extents(&self) -> Result<(), SettingError> {
        check_within(
            &stage_kit::named_fields!(self; grid_cell_size, view_range),
            MIN_GRID_CELL_M..=SENSOR_REACH_M,
            "m",
        )?;
        let reach = SENSOR_REACH_M.min(MAX_LOOKUP_CELLS * self.grid_cell_size);
        check_within(
            &stage_kit::named_fields!(self; search_radius, duplicate_radius),
            0.0..=reach,
            "m (the sensor's reach, and 32 cells of grid_cell_size)",
        )?;
        check_within(
            &stage_kit::named_fields!(self;
                measured_xy_variance_per_metre, measured_xy_variance_per_radian,
                measured_yaw_variance_per_metre, measured_yaw_variance_per_radian,
            ),
            0.0..=MAX_DRIFT,
            "(m^2 or rad^2 per metre or radian)",
        )?;
        check_within(
            &stage_kit::named_fields!(self;
                noise_xy_base, noise_xy_per_metre, noise_xy_per_radian, noise_yaw_base,
                noise_yaw_per_radian, noise_yaw_per_metre, saved_grid_drift_xy_per_metre,
                saved_grid_drift_yaw_per_metre,
            ),
            0.0..=MAX_DRIFT,
            "(m or rad, per metre or radian)",
        )?;
        check_within(
            &stage_kit::named_fields!(self; saved_grid_max_drift_xy),
            0.0..=SENSOR_REACH_M,
            "m",
        )
    }
}

/// Farther than any planar lidar measures (the longest-reaching SICK, 80 m): a radius
/// beyond it searches for what no scan can have seen.
pub const SENSOR_REACH_M: f64 = 100.0;
/// The finest corner grid: corners closer than this are one corner anyway.
const MIN_GRID_CELL_M: f64 = 0.1;
/// A corner lookup spans at most this many grid cells each way, whatever its radius.
const MAX_LOOKUP_CELLS: f64 = 32.0;
/// A drift or noise of a metre (or radian) per metre (or radian) of motion says nothing
/// about the motion any more.
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
        assert_eq!(config.search_radius, defaults.search_radius);
        assert_eq!(
            config.localize.min_particles,
            defaults.localize.min_particles
        );
        for (text, key) in [
            ("particle = 7", "particle"),
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
        assert_eq!(
            refused(|c| c.association_probability = 1.0),
            Some("association_probability")
        );
        assert_eq!(refused(|c| c.particles = 0), Some("particles"));
        assert_eq!(
            refused(|c| c.motion_candidates = 65),
            Some("motion_candidates")
        );
        assert_eq!(
            refused(|c| c.confirm_observations = 0),
            Some("confirm_observations")
        );
        assert_eq!(
            refused(|c| c.update_min_distance = -0.5),
            Some("update_min_distance")
        );
        for (spoil, field) in [
            (
                (|c| c.search_radius = 1e9) as fn(&mut SlamConfig),
                "search_radius",
            ),
            (
                |c| c.saved_grid_max_drift_xy = 1e9,
                "saved_grid_max_drift_xy",
            ),
            (|c| c.duplicate_radius = 1e9, "duplicate_radius"),
            (|c| c.grid_cell_size = 1e-9, "grid_cell_size"),
            (
                |c| c.measured_xy_variance_per_metre = 1e9,
                "measured_xy_variance_per_metre",
            ),
        ] {
            assert_eq!(refused(spoil), Some(field));
        }
    }
}
