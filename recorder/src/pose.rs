//! The filter's estimate as `foxglove.PoseInFrame` in the map frame, with the rest of the
//! estimate beside it.

use schemars::JsonSchema;
use serde::Serialize;

use crate::geometry::{Planar, Pose};
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// The map frame: SLAM's own (docs/CONVENTIONS.md, "Saved maps").
pub const MAP_FRAME: &str = "map";

/// One scan's estimate: Foxglove's fields (`timestamp`, `frame_id`, `pose`: the particles'
/// weighted mean, the estimate map-sink records), then every field of our `PoseEstimate`.
#[derive(Debug, Serialize, JsonSchema)]
pub struct PoseMessage {
    pub timestamp: Time,
    pub frame_id: &'static str,
    pub pose: Pose,
    // Ours from here on.
    pub seq: u64,
    pub sent_ns: u64,
    pub scan_sent_ns: u64,
    pub best: Planar,
    pub mean: Planar,
    pub dead_reckoning: Planar,
    /// Row-major 3x3 over (x, y, yaw).
    pub covariance: [f64; 9],
    pub effective_particles: f64,
    pub particle_count: u32,
    pub map_corners: u32,
    pub timing: Timing,
    /// `mapping`, or on a saved map `searching` / `converged`.
    pub localization: &'static str,
}

/// `ipc_types::StageTiming`, nanoseconds.
#[derive(Debug, Serialize, JsonSchema)]
pub struct Timing {
    pub motion_ns: u64,
    pub predict_ns: u64,
    pub update_ns: u64,
    pub resample_ns: u64,
    pub total_ns: u64,
}

impl ChannelMessage for PoseMessage {
    const TOPIC: &'static str = "/slam/pose";
    const SCHEMA: &'static str = "foxglove.PoseInFrame";
}

impl PoseMessage {
    pub fn new(p: &ipc_types::PoseEstimate) -> Self {
        let t = p.timing;
        Self {
            timestamp: Time::from_ns(p.header.stamp_ns),
            frame_id: MAP_FRAME,
            pose: p.mean.into(),
            seq: p.header.seq,
            sent_ns: p.header.sent_ns,
            scan_sent_ns: p.scan_sent_ns,
            best: p.best.into(),
            mean: p.mean.into(),
            dead_reckoning: p.dead_reckoning.into(),
            covariance: p.covariance,
            effective_particles: p.effective_particles,
            particle_count: p.particle_count,
            map_corners: p.map_corners,
            timing: Timing {
                motion_ns: t.motion_ns,
                predict_ns: t.predict_ns,
                update_ns: t.update_ns,
                resample_ns: t.resample_ns,
                total_ns: t.total_ns,
            },
            localization: match p.localization {
                ipc_types::PoseEstimate::SEARCHING => "searching",
                ipc_types::PoseEstimate::CONVERGED => "converged",
                _ => "mapping",
            },
        }
    }
}
