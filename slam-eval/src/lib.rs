//! # slam-eval
//!
//! The workspace's one evaluation library: how a run is scored, and the typed summary a run
//! leaves behind.
//!
//! * [`ate`] aligns an estimate to the truth with the rigid SE(2) fit of
//!   docs/CONVENTIONS.md ([`slam_geom::align_se2`], as `evo_ape -a`) and takes the absolute
//!   trajectory error; [`nearest_rmse`] scores map corners (moved by that alignment)
//!   against the world's true corners; [`percentile`] summarises latencies;
//! * [`Metrics`] is `metrics.json`: map-sink writes it, slam-launch, slam-bench and the
//!   end-to-end tests read it back typed (the file's name and those of the trajectory files
//!   are in [`run_files`]);
//!
//! It also scores an estimated trajectory with the relative-pose metric of Kuemmerle et al.
//! 2009 ("On measuring the accuracy of SLAM algorithms"), the library half of `slam-score`:
//!
//! * [`Trajectory::read_tum`] reads the estimate (TUM: `stamp x y z qx qy qz qw`, as
//!   map-sink writes it, stamps = the log's own);
//! * [`read_relations`] reads the ground truth (`t1 t2 x y z roll pitch yaw`: the pose at
//!   `t2` in the frame of the pose at `t1`);
//! * [`score`] finds the poses at each relation's stamps (the nearest within a tolerance),
//!   compares the estimated relative motion with the true one and reports the mean and
//!   standard deviation of the translational (m) and rotational (deg) errors, plain and
//!   squared, as the paper's tables do.
//!
//! [`ScoreSummary`] is what a run's `metrics.json` keeps of a score (its [`PoseErrors`]); [`score_run`] scores
//! every trajectory file of a run directory into [`RelativePoseErrors`].
//!
//! [`position_gaps`] compares a localization on a saved map with a trajectory in the same
//! frame (the mapping run's, or the truth moved into the map), pose by pose.
//!
//! Stamps are compared as integer nanoseconds, parsed exactly from their decimal text.

mod ate;
mod corner_score;
mod error;
mod gap;
mod incomplete_output;
mod map_fit;
mod metrics;
mod percentile;
mod pose;
mod pose_errors;
mod relations;
pub mod run_files;
mod run_score;
mod score;
mod stats;
mod summary;
mod text;
mod trajectory;

pub use ate::{AteStats, ate, distance};
pub use corner_score::nearest_rmse;
pub use incomplete_output::IncompleteOutput;
pub use map_fit::{
    FitVerdict, MAP_FIT_BEAMS_PER_SCAN, MAP_FIT_FLOOR, MAP_FIT_MIN_BEAMS, MAP_FIT_WITHIN_M, MapFit,
    MapFitSummary,
};
pub use metrics::{FrameCounts, Metrics, SearchPhase};
pub use percentile::percentile;
pub use run_files::{
    DEAD_RECKONING_FILE, GROUND_TRUTH_FILE, METRICS_FILE, TRAJECTORY_FILE, TRAJECTORY_ONLINE_FILE,
};
pub use run_score::{RelationsFile, RelativePoseErrors, score_run, score_tum_file};

pub use error::EvalError;
pub use gap::{Gaps, position_gaps};
pub use pose::{Pose, from_tum, from_xyz_rpy, magnitude};
pub use pose_errors::PoseErrors;
pub use relations::{
    MAX_RELATION_SPEED_M_S, RELATION_SLACK_M, RELATIONS_INPUT, Relation, RelationsRead,
    read_relations, read_relations_noted,
};
pub use score::{DEFAULT_TOLERANCE_NS, Score, Unmatched, score};
pub use stats::ErrorStats;
pub use summary::ScoreSummary;
pub use trajectory::{TRAJECTORY_INPUT, Trajectory};
