//! feature-proc's sections: the corner extractor and the scan-matching front end.

use std::f64::consts::{FRAC_PI_2, PI};

use super::{Limit, Range, Section, set};

pub const FEATURES: Section = Section {
    table: "features",
    about: "feature-proc's extractor: scan -> segments -> lines -> corners.",
    settings: &[
        set(
            "max_range",
            "m",
            Range::POSITIVE,
            "Readings beyond this are dropped, on top of the scan's own range_max.",
        ),
        set(
            "range_sigma",
            "m",
            Range::POSITIVE,
            "Standard deviation of a range reading: breakpoints, wall membership, covariances.",
        ),
        set(
            "bearing_sigma",
            "rad",
            Range::NON_NEGATIVE,
            "Standard deviation of a beam's bearing.",
        ),
        set(
            "breakpoint_lambda",
            "rad",
            Range::new(Limit::Excl(0.0), Limit::Incl(FRAC_PI_2)),
            "Shallowest beam-to-surface angle still followed as one segment (Borges & Aldon).",
        ),
        set(
            "max_invalid_gap",
            "beams",
            Range::closed(0.0, 100.0),
            "Invalid beams bridged inside a segment.",
        ),
        set(
            "split_threshold",
            "m",
            Range::POSITIVE,
            "Split a run of points where one lies farther than this from its chord.",
        ),
        set(
            "merge_angle",
            "rad",
            Range::POSITIVE,
            "Neighbouring lines closer in direction than this are merged when still straight.",
        ),
        set(
            "merge_max_gap",
            "m",
            Range::NON_NEGATIVE,
            "Largest gap between neighbouring lines a merge may bridge.",
        ),
        set(
            "min_line_points",
            "",
            Range::closed(3.0, 1000.0),
            "Fewest points a line is fitted to.",
        ),
        set(
            "min_line_length",
            "m",
            Range::POSITIVE,
            "Shortest arm of a corner, from the intersection to each line's far end.",
        ),
        set(
            "corner_min_angle",
            "rad",
            Range::POSITIVE.and("below corner_max_angle"),
            "Smallest opening angle of a corner.",
        ),
        set(
            "corner_max_angle",
            "rad",
            Range::new(Limit::None, Limit::Excl(PI)),
            "Largest opening angle of a corner.",
        ),
        set(
            "corner_max_gap",
            "m",
            Range::POSITIVE,
            "Largest gap between one line's end and the next line's start for a corner.",
        ),
        set(
            "corner_max_extension",
            "m",
            Range::POSITIVE,
            "Largest distance from a line's near end to the intersection (else an occlusion).",
        ),
    ],
};

pub const FRONT_END: Section = Section {
    table: "front_end",
    about: "The scan-matching front end (run by feature-proc): docs/front-end.md.",
    settings: &[
        set(
            "range_sigma",
            "m",
            Range::POSITIVE,
            "Standard deviation of one range reading; floors the fit's noise.",
        ),
        set(
            "voxel_size",
            "m",
            Range::POSITIVE,
            "Edge of the voxels that thin the scans and the local map.",
        ),
        set(
            "min_points",
            "",
            Range::at_least(1.0),
            "Fewer usable points: the scan is not matched, and a fit with fewer inliers does not overrule the wheels.",
        ),
        set(
            "max_correspondence",
            "m",
            Range::POSITIVE.and("at least voxel_size"),
            "Widest gate between a scan point and its map neighbour.",
        ),
        set(
            "max_search_translation",
            "m",
            Range::POSITIVE,
            "The correlative search before registration spans at most this far each way.",
        ),
        set(
            "max_search_yaw",
            "rad",
            Range::POSITIVE,
            "... and this far in yaw.",
        ),
        set(
            "recovery_translation",
            "m",
            Range::POSITIVE,
            "After a gap, a weak fit gets a wide search up to this far each way ...",
        ),
        set(
            "recovery_yaw",
            "rad",
            Range::POSITIVE,
            "... and this far in yaw (pi: a full turn).",
        ),
        set(
            "max_iterations",
            "",
            Range::at_least(1.0),
            "Gauss-Newton iterations per scan, at most.",
        ),
        set(
            "convergence",
            "m",
            Range::POSITIVE,
            "Registration stops once a step moves every point by less than this.",
        ),
        set(
            "keyframe_distance",
            "m",
            Range::POSITIVE,
            "A new keyframe joins the local map after the robot moved this far ...",
        ),
        set(
            "keyframe_angle",
            "rad",
            Range::POSITIVE,
            "... or turned this much.",
        ),
        set(
            "max_keyframes",
            "",
            Range::at_least(1.0),
            "Keyframes in the local map, at most; the oldest leaves first.",
        ),
        set(
            "degenerate_keyframe_interval",
            "s",
            Range::POSITIVE,
            "Without odometry, a fit that leaves a direction open adds a keyframe at least this often.",
        ),
        set(
            "degeneracy_ratio",
            "",
            Range::PROBABILITY,
            "A direction with less than this fraction of the strongest one's information is left to the prior.",
        ),
        set(
            "min_inlier_fraction",
            "",
            Range::FRACTION,
            "A fit judges the odometry only with at least this fraction of its points as inliers.",
        ),
        set(
            "strong_inlier_fraction",
            "",
            Range::new(Limit::None, Limit::Incl(1.0)).and("at least min_inlier_fraction"),
            "A fit overrules a contradicting wheel step only with at least this fraction as inliers.",
        ),
        set(
            "odometry_gate",
            "",
            Range::POSITIVE,
            "Squared Mahalanobis distance between wheel step and fit beyond which the wheels are rejected.",
        ),
        set(
            "odometry_min_sigma_xy",
            "m",
            Range::POSITIVE,
            "Floor of a wheel step's standard deviation.",
        ),
        set(
            "odometry_min_sigma_yaw",
            "rad",
            Range::POSITIVE,
            "Floor of a wheel step's yaw standard deviation.",
        ),
        set(
            "max_linear_speed",
            "m/s",
            Range::POSITIVE,
            "A step faster than this is not a robot's: rejected.",
        ),
        set(
            "max_angular_speed",
            "rad/s",
            Range::POSITIVE,
            "Nor one turning faster than this.",
        ),
        set(
            "max_linear_acceleration",
            "m/s^2",
            Range::POSITIVE,
            "A wheel step changing the wheels' pace faster than this is a stale reading.",
        ),
        set(
            "velocity_sigma_linear",
            "m/s",
            Range::POSITIVE,
            "Without odometry, how much the constant-velocity prior's speed may change between scans.",
        ),
        set(
            "velocity_sigma_angular",
            "rad/s",
            Range::POSITIVE,
            "The same for the turn rate.",
        ),
        set(
            "odometry_scale_memory",
            "m",
            Range::POSITIVE,
            "The wheels' distance scale is learnt over about this much travel ...",
        ),
        set(
            "odometry_scale_min_evidence",
            "m",
            Range::POSITIVE,
            "... and used once the fits have measured this far ...",
        ),
        set(
            "odometry_scale_max_correction",
            "",
            Range::new(Limit::Incl(0.0), Limit::Excl(0.5)),
            "... within 1 +- this; 0 leaves the wheels' distances as they are.",
        ),
    ],
};
