//! feature-proc's sections: the corner extractor and the scan-matching front end.

use super::{Limit, Range, Section, set};

pub const FEATURES: Section = Section {
    table: "features",
    about: "feature-proc's extractor: scan -> segments -> lines -> corners (its range noise is [front_end] range_sigma).",
    settings: &[
        set(
            "max_range",
            "m",
            Range::POSITIVE,
            "Readings beyond this are dropped, on top of the scan's own range_max: far corners flicker.",
        ),
        set(
            "bearing_sigma",
            "rad",
            Range::NON_NEGATIVE,
            "Standard deviation of a beam's bearing (small for a spinning mirror).",
        ),
        set(
            "min_line_points",
            "",
            Range::closed(3.0, 1000.0),
            "Fewest points a line is fitted to: fewer for a scanner with coarser beam spacing.",
        ),
    ],
};

pub const FRONT_END: Section = Section {
    table: "front_end",
    about: "The scan-matching front end (run by feature-proc; graph-proc registers as it does): docs/front-end.md.",
    settings: &[
        set(
            "range_sigma",
            "m",
            Range::POSITIVE,
            "Standard deviation of one range reading (the scanner's datasheet); the corner extractor allows twice it about a wall.",
        ),
        set(
            "voxel_size",
            "m",
            Range::closed(0.001, 0.5),
            "Edge of the voxels that thin the scans and the local map (the back end's submaps too).",
        ),
        set(
            "keyframe_distance",
            "m",
            Range::POSITIVE,
            "A new keyframe joins the local map (and the back end a node) after the robot moved this far.",
        ),
        set(
            "keyframe_angle",
            "rad",
            Range::POSITIVE,
            "A new keyframe also joins after the robot turned this much.",
        ),
        set(
            "max_linear_speed",
            "m/s",
            Range::POSITIVE,
            "A wheel step faster than this is not the robot's: rejected.",
        ),
        set(
            "max_angular_speed",
            "rad/s",
            Range::POSITIVE,
            "A wheel step turning faster than this is not the robot's either.",
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
            "Without odometry, how much the constant-velocity prior's turn rate may change between scans.",
        ),
        set(
            "odometry_scale_max_correction",
            "",
            Range::new(Limit::Incl(0.0), Limit::Excl(0.5)),
            "The wheels' distance scale, learnt from the fits, stays within 1 +- this; 0 leaves the wheels' distances as they are.",
        ),
    ],
};
