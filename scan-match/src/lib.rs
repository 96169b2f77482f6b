//! # scan-match
//!
//! The scan-matching front end of the pipeline: every scan is registered against a local
//! map of recent keyframes (all valid points, not features) and fused with the odometry, so
//! the motion the filter receives is the scan's wherever the scan is sure of it and the
//! odometry's where it is not.
//!
//! Per scan ([`FrontEnd::process`] on a [`ScanInput`]):
//! 1. valid beams become points with surface normals, thinned to one per voxel
//!    ([`points`], with the beams' directions kept between scans: [`bearings`]);
//! 2. the prior step is the odometry increment with the growth of its covariance, its
//!    distance scaled by what the fits have measured of the wheels ([`odometry_scale`]), or
//!    constant velocity without odometry ([`prior`]; without any wheels the speed is the
//!    median of the last steps', so that one fit's correction is not taken for a speed);
//! 3. where the prior is too uncertain, a correlative search picks the basin ([`search`]);
//!    after a gap in the data, or a stretch of scans that did not register, that outgrows
//!    its window, a wide search up to a full turn proposes a few candidates, refined and
//!    ranked by their registered fits ([`recovery`]); such a stretch is carried on at
//!    constant velocity for a second at most, then held, its uncertainty adding up;
//! 4. point-to-line Gauss-Newton with a Cauchy loss and a shrinking gate registers the scan
//!    against the local map from the seed ([`registration`]); the fit's Hessian says which
//!    directions the scan fixes and which it leaves open ([`constraint`]: a corridor's
//!    length is left to the prior);
//! 5. an odometry step the match contradicts (Mahalanobis), or that is not finite or
//!    faster than a robot, is rejected and counted; otherwise the two are fused by their
//!    information ([`fusion`]);
//! 6. the scan joins the local map when the robot has moved or turned enough
//!    ([`local_map`]). Queries go through a lookup raster over the map (the nearest point
//!    per cell and normal direction), stamped only where a keyframe adds voxels, so a
//!    query costs a table lookup rather than a grid search.
//!
//! The result ([`FrontEndOutput`]) is the pose in the front end's own frame (the identity
//! at the first scan), the increment with its covariance, and what happened (matched,
//! degenerate and along which direction, failed; odometry used or rejected; counts; time).
//! [`FrontEnd::stats`] counts over the run. The settings a user changes are in
//! [`FrontEndConfig`]; the rest are constants beside the code that uses them.

pub mod bearings;
mod cell_hash;
mod config;
pub mod constraint;
mod error;
mod front_end;
pub mod fusion;
mod input;
pub mod local_map;
mod nearest_field;
mod odometry_anchor;
pub mod odometry_scale;
mod output;
pub mod points;
pub mod prior;
pub mod recovery;
pub mod registration;
mod scan_clock;
pub mod search;
mod velocity;
mod wheel_pace;

pub use config::FrontEndConfig;
pub use error::InputError;
pub use front_end::FrontEnd;
pub use input::{OdometryInput, ScanInput};
pub use output::{
    FrontEndOutput, FrontEndStats, MatchFailure, MatchStatus, OdometryRejections, OdometryStatus,
};
pub use prior::OdometryRejection;
pub use stage_kit::SettingError;
