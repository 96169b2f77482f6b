//! # slam-eval
//!
//! Scores an estimated trajectory with the relative-pose metric of Kuemmerle et al. 2009
//! ("On measuring the accuracy of SLAM algorithms"), the library half of `slam-score`.
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
//! [`ScoreSummary`] is what a run's `metrics.json` keeps of a score (map-sink writes it,
//! slam-launch and slam-bench read it back).
//!
//! [`position_gaps`] compares a localization on a saved map with a trajectory in the same
//! frame (the mapping run's, or the truth moved into the map), pose by pose.
//!
//! Stamps are compared as integer nanoseconds, parsed exactly from their decimal text.

mod error;
mod gap;
mod pose;
mod relations;
mod score;
mod stats;
mod summary;
mod text;
mod trajectory;

pub use error::EvalError;
pub use gap::{Gaps, position_gaps};
pub use pose::{Pose, from_tum, from_xyz_rpy, magnitude};
pub use relations::{Relation, read_relations};
pub use score::{DEFAULT_TOLERANCE_NS, Score, Unmatched, score};
pub use stats::ErrorStats;
pub use summary::ScoreSummary;
pub use trajectory::Trajectory;
