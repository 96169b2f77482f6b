//! The numbers that summarise a run, as map-sink writes them to `metrics.json` and the
//! launcher, the benchmark and the tests read them back.

use serde::{Deserialize, Serialize};

use crate::incomplete_output::IncompleteOutput;
use crate::map_fit::MapFitSummary;
use crate::run_score::RelativePoseErrors;

/// How many scans the pipeline published, processed and dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct FrameCounts {
    pub published: u64,
    pub processed: u64,
    pub dropped: u64,
}

/// The summary of a run. Serialises with keys in field order; the ground-truth scores are
/// absent (not null) when there was no truth to score against, while a value that is merely
/// undefined (no latency samples, zero wall time) is `null`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    pub frames_published: u64,
    pub frames_processed: u64,
    pub frames_dropped: u64,
    /// Length of the estimated trajectory.
    pub path_length_m: f64,
    pub map_corners: usize,
    /// From the first message recorded to the last.
    pub wall_s: f64,
    /// From the first processed scan's stamp to the last one's: for a replay, how long the
    /// log took to record, so `duration_s / wall_s` is the speed against real time.
    #[serde(default)]
    pub duration_s: Option<f64>,
    /// `frames_processed / wall_s`.
    pub scans_per_s: Option<f64>,
    /// Scan stamp to pose published, milliseconds.
    pub latency_ms_p50: Option<f64>,
    pub latency_ms_p99: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ate_rmse_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ate_max_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_error_m: Option<f64>,
    /// Map corners moved by the trajectory alignment, each to its nearest true corner.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_corner_rmse_m: Option<f64>,
    /// The dead-reckoning trajectory scored on its own alignment, as a baseline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dead_reckoning_ate_rmse_m: Option<f64>,
    /// The online estimate (each scan's weighted mean, `trajectory_online.tum`) scored on its
    /// own alignment; `ate_rmse_m` is the final path's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub online_ate_rmse_m: Option<f64>,
    /// The trajectories scored against ground-truth relations, when there were any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relative_pose_error: Option<RelativePoseErrors>,
    /// Localizing on a saved map: the first scan (sequence number) whose pose had
    /// converged, and its stamp (seconds, as in the TUM files); absent when it never did
    /// or the run mapped. The scores above (ATE, final error, map corners, relative-pose
    /// errors) cover the poses from this scan on: the search before it is scored apart
    /// (`search_phase`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converged_at_scan: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converged_at_stamp: Option<String>,
    /// Localizing on a saved map: the poses before convergence (all of them when it never
    /// converged), which the scores above leave out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_phase: Option<SearchPhase>,
    /// On a saved map (localizing, or mapping on its grid): how well it explained the run's
    /// scans. Localizing, a map that does not fit fails the run; mapping, it was set aside
    /// and not merged: the run's files hold this run's map alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_fit: Option<MapFitSummary>,
    /// The run's files that stopped short or were not written (a full disk); absent when
    /// every file is whole.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub incomplete_outputs: Vec<IncompleteOutput>,
}

/// A localization's search for its pose, before the particles converged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchPhase {
    /// Poses before the first converged one.
    pub scans: u64,
    /// Their positions against the truth, moved by the alignment of the converged poses
    /// (by their own, when the run never converged); absent without truth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ate_rmse_m: Option<f64>,
}
