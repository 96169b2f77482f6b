//! slam-proc's sections: the filter and localization on a saved map.

use std::f64::consts::TAU;

use super::{Limit, Range, Section, set};

pub const SLAM: Section = Section {
    table: "slam",
    about: "slam-proc: FastSLAM over corner maps (docs/filter.md, docs/back-end.md).",
    settings: &[
        set(
            "seed",
            "",
            Range::ANY,
            "Seed of the filter's noise (--seed): the same seed gives the same run.",
        ),
        set(
            "particles",
            "",
            Range::closed(1.0, 1e6),
            "Particles of the filter (--particles); refused when the memory is not there.",
        ),
        set(
            "measured_xy_variance_per_metre",
            "m^2/m",
            Range::closed(0.0, 1.0),
            "The particles spread by the front end's drift: its translation variance per metre travelled.",
        ),
        set(
            "measured_xy_variance_per_radian",
            "m^2/rad",
            Range::closed(0.0, 1.0),
            "The front end's translation variance per radian turned.",
        ),
        set(
            "measured_yaw_variance_per_metre",
            "rad^2/m",
            Range::closed(0.0, 1.0),
            "The front end's rotation variance per metre travelled.",
        ),
        set(
            "measured_yaw_variance_per_radian",
            "rad^2/rad",
            Range::closed(0.0, 1.0),
            "The front end's rotation variance per radian turned.",
        ),
        set(
            "update_min_distance",
            "m",
            Range::NON_NEGATIVE,
            "The corners update the particles once the robot moved this far since they last did (0: every scan).",
        ),
        set(
            "update_min_rotation",
            "rad",
            Range::NON_NEGATIVE,
            "The corners also update the particles once the robot turned this far.",
        ),
        set(
            "view_range",
            "m",
            Range::closed(0.1, 100.0),
            "A corner closer than this is in view (at most the scanner's range); one in view and not seen is dropped while tentative.",
        ),
        set(
            "view_fov",
            "rad",
            Range::new(Limit::Excl(0.0), Limit::Incl(TAU)),
            "The scanner's field of view, centred on the robot's x axis.",
        ),
    ],
};

pub const LOCALIZE: Section = Section {
    table: "slam.localize",
    about: "slam-proc with --map DIR --localize: Monte Carlo localization (docs/localization.md); sigma_hit also holds a run mapped on a saved map.",
    settings: &[
        set(
            "min_particles",
            "",
            Range::at_least(1.0),
            "Fewest particles KLD-sampling keeps once converged.",
        ),
        set(
            "max_particles",
            "",
            Range::closed(1.0, 1e6).and("at least min_particles"),
            "Most particles; a global start spreads this many over the free space.",
        ),
        set(
            "beams",
            "",
            Range::at_least(1.0),
            "Beams of a scan that weight the particles.",
        ),
        set(
            "sigma_hit",
            "m",
            Range::POSITIVE,
            "Sigma of a beam end's distance to the nearest wall, once converged: the scanner's noise and the map's cell.",
        ),
        set(
            "update_min_distance",
            "m",
            Range::NON_NEGATIVE,
            "The scans weight the particles once the robot is this far from where they last did.",
        ),
        set(
            "update_min_rotation",
            "rad",
            Range::NON_NEGATIVE,
            "The scans also weight the particles once the robot turned this much since.",
        ),
        set(
            "xy_variance_per_metre",
            "m^2/m",
            Range::NON_NEGATIVE,
            "The particles' spread as they move: translation variance per metre travelled.",
        ),
        set(
            "xy_variance_per_radian",
            "m^2/rad",
            Range::NON_NEGATIVE,
            "Translation variance per radian turned.",
        ),
        set(
            "yaw_variance_per_metre",
            "rad^2/m",
            Range::NON_NEGATIVE,
            "Rotation variance per metre travelled.",
        ),
        set(
            "yaw_variance_per_radian",
            "rad^2/rad",
            Range::NON_NEGATIVE,
            "Rotation variance per radian turned.",
        ),
        set(
            "initial_sigma_xy",
            "m",
            Range::NON_NEGATIVE,
            "A known start (initial_pose) spreads the particles by this in x and y.",
        ),
        set(
            "initial_sigma_yaw",
            "rad",
            Range::NON_NEGATIVE,
            "A known start spreads the particles by this in yaw.",
        ),
    ],
};
