//! The simulator's true pose as `foxglove.PoseInFrame` in the world frame.

use schemars::JsonSchema;
use serde::Serialize;

use crate::geometry::{Planar, Pose};
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// The simulated world's frame. Not `map`: SLAM's frame starts at the first pose, the world's
/// does not (docs/CONVENTIONS.md, "Ground truth and scoring").
pub const WORLD_FRAME: &str = "world";

/// The true pose at a scan: Foxglove's fields, then the scan's sequence number, send time and
/// the planar pose as sent.
#[derive(Debug, Serialize, JsonSchema)]
pub struct GroundTruthMessage {
    pub timestamp: Time,
    pub frame_id: &'static str,
    pub pose: Pose,
    pub seq: u64,
    pub sent_ns: u64,
    pub planar: Planar,
}

impl ChannelMessage for GroundTruthMessage {
    const TOPIC: &'static str = "/sim/ground_truth";
    const SCHEMA: &'static str = "foxglove.PoseInFrame";
}

impl GroundTruthMessage {
    pub fn new(t: &ipc_types::GroundTruthPose) -> Self {
        Self {
            timestamp: Time::from_ns(t.header.stamp_ns),
            frame_id: WORLD_FRAME,
            pose: t.pose.into(),
            seq: t.header.seq,
            sent_ns: t.header.sent_ns,
            planar: t.pose.into(),
        }
    }
}
