//! The names of the files in a run's directory that evaluation reads (map-sink writes them).

/// The estimated trajectory: the filter's final path (the best particle's, consistent with
/// its map), written atomically at the end of the run; the online estimates when no final
/// path came (a run whose filter died).
pub const TRAJECTORY_FILE: &str = "trajectory.tum";
/// The online estimate: each scan's weighted mean pose, appended as the run goes.
pub const TRAJECTORY_ONLINE_FILE: &str = "trajectory_online.tum";
/// The front end's own motion estimate, appended as it grows (only when one is recorded).
pub const DEAD_RECKONING_FILE: &str = "dead_reckoning.tum";
/// The simulator's true trajectory, appended as it grows (only when truth is recorded).
pub const GROUND_TRUTH_FILE: &str = "ground_truth.tum";
/// The summary ([`Metrics`](crate::Metrics)), written atomically and last: its presence
/// means the run was finished.
pub const METRICS_FILE: &str = "metrics.json";
