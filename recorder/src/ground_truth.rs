//! The simulator's true pose as `foxglove.PoseInFrame` in the world frame.

use schemars::JsonSchema;
use serde::Serialize;

use ipc_types::{GroundTruthPose, Pose2};

use crate::pose_in_frame::{PoseInFrame, PoseTopic};

/// The simulated world's frame. Not `map`: SLAM's frame starts at the first pose, the world's
/// does not (docs/CONVENTIONS.md, "Ground truth and scoring").
pub const WORLD_FRAME: &str = "world";

/// What a true pose adds to Foxglove's fields: the scan's sequence number, send time and the
/// planar pose as sent.
#[derive(Debug, Serialize, JsonSchema)]
pub struct TruthFields {
    pub seq: u64,
    pub sent_ns: u64,
    pub planar: Pose2,
}

/// The true pose at a scan.
pub type GroundTruthMessage = PoseInFrame<TruthFields>;

impl PoseTopic for TruthFields {
    const TOPIC: &'static str = "/sim/ground_truth";
}

impl GroundTruthMessage {
    pub fn new(t: &GroundTruthPose) -> Self {
        let ours = TruthFields {
            seq: t.header.seq,
            sent_ns: t.header.sent_ns,
            planar: t.pose,
        };
        Self::at(t.header.stamp_ns, WORLD_FRAME, t.pose, ours)
    }
}
