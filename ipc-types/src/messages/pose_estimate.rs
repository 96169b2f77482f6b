//! The SLAM estimate for one scan.

use std::time::Instant;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::pose::Pose2;
use crate::header::Header;

/// Time spent in each stage of one SLAM update, nanoseconds.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, FromZeros, Serialize, Deserialize,
)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::StageTiming::v1")]
pub struct StageTiming {
    /// Scan-to-scan motion estimate.
    pub motion_ns: u64,
    /// Sampling every particle's new pose.
    pub predict_ns: u64,
    /// Association, map updates and weights of every particle.
    pub update_ns: u64,
    /// Normalisation, statistics and (when needed) resampling.
    pub resample_ns: u64,
    /// The whole update.
    pub total_ns: u64,
}

impl StageTiming {
    /// The stages' durations from the instants that bound them: the start, the ends of the
    /// motion estimate, the prediction and the update, and the end.
    pub fn between(instants: [Instant; 5]) -> Self {
        let [start, motion_done, predict_done, update_done, end] = instants;
        let ns =
            |from: Instant, to: Instant| u64::try_from((to - from).as_nanos()).unwrap_or(u64::MAX);
        Self {
            motion_ns: ns(start, motion_done),
            predict_ns: ns(motion_done, predict_done),
            update_ns: ns(predict_done, update_done),
            resample_ns: ns(update_done, end),
            total_ns: ns(start, end),
        }
    }
}

/// The pose estimate after one scan, in the map frame (the first pose is the origin).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::PoseEstimate::v3")]
pub struct PoseEstimate {
    /// The source scan's header; `sent_ns` is this message's.
    pub header: Header,
    /// When the source scan was published, for end-to-end latency.
    pub scan_sent_ns: u64,
    /// Pose of the particle with the highest weight.
    pub best: Pose2,
    /// Weighted mean pose of the particles (yaw by circular mean).
    pub mean: Pose2,
    /// The scan-to-scan motion estimate integrated alone, for comparison.
    pub dead_reckoning: Pose2,
    /// Row-major 3x3 covariance of (x, y, yaw) over the particles.
    pub covariance: [f64; 9],
    /// `1 / sum(w_i^2)` of the normalised weights.
    pub effective_particles: f64,
    pub particle_count: u32,
    /// Confirmed corners in the best particle's map.
    pub map_corners: u32,
    pub timing: StageTiming,
    /// [`PoseEstimate::MAPPING`], or, localizing on a saved map,
    /// [`PoseEstimate::SEARCHING`] until the particles have converged and
    /// [`PoseEstimate::CONVERGED`] while they are.
    pub localization: u32,
    /// Keeps the layout free of implicit padding; always 0.
    #[serde(skip)]
    pub reserved: u32,
    /// On a saved map (`--map`): the beams whose ends the map could judge so far, from the
    /// estimate (localizing: at the scans that weighted the converged particles; mapping:
    /// at the filter's updates) ...
    pub map_beams_judged: u64,
    /// ... and those of them that ended on one of its walls (`slam_eval::MapFit`); both 0
    /// without a saved map.
    pub map_beams_explained: u64,
}

impl PoseEstimate {
    /// SLAM: the map is being built.
    pub const MAPPING: u32 = 0;
    /// Localizing on a saved map; the particles are still spread (`covariance`).
    pub const SEARCHING: u32 = 1;
    /// Localizing on a saved map; the particles have converged on one pose.
    pub const CONVERGED: u32 = 2;
}
