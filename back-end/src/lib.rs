//! # back-end
//!
//! Global SLAM, the layer above the scan-matching front end (Cartographer's split): the
//! front end's poses and scans build submaps; a scan that comes back near an old submap is
//! matched against it by a correlative search wide enough for the drift since, and the
//! match becomes a loop closure only when the scan agrees with the submap (a share of its
//! points explained, the same on every scanner); the path is a pose graph over the front
//! end's steps and the closures, solved with a robust loss so that a wrong closure cannot
//! bend it.
//!
//! [`PoseGraph`] ([`pose_graph`]) is that solver, the project's one: nodes joined by the
//! front end's steps (trusted) and by closures (not), each closure weighted by dynamic
//! covariance scaling, annealed so that loops that came back metres off still close, and
//! reported accepted or rejected; every step is an exact sparse Cholesky solve, so a
//! chain of 15,000 nodes with 500 closures is re-solved online in tens of milliseconds
//! (`examples/pose_graph_timing.rs`).

pub mod branch_bound;
pub mod closure;
pub mod compact_scan;
pub mod confirmation;
pub mod coverage;
pub mod global_grid;
pub mod global_slam;
pub mod occupancy_grid;
pub mod pose_graph;
pub mod submap;
pub mod submap_grid;
pub mod trim;

pub use global_slam::ScanRanges;
pub use global_slam::{GlobalConfig, GlobalError, GlobalSlam, GlobalStats};
pub use pose_graph::{
    ACCEPTED_SCALE, ClosureId, PoseGraph, PoseGraphError, PoseGraphSettings, SolveReport,
};
