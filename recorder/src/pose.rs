//! The filter's estimate as `foxglove.PoseInFrame` in the map frame, with the whole
//! estimate beside it.

use ipc_types::PoseEstimate;

use crate::pose_in_frame::{PoseInFrame, PoseTopic};

/// The map frame: SLAM's own (docs/CONVENTIONS.md, "Saved maps").
pub const MAP_FRAME: &str = "map";

/// One scan's estimate: Foxglove's `pose` is the particles' weighted mean (the estimate
/// map-sink records), and every field of our `PoseEstimate` follows in its serde form.
pub type PoseMessage = PoseInFrame<PoseEstimate>;

impl PoseTopic for PoseEstimate {
    const TOPIC: &'static str = "/slam/pose";
}

impl PoseMessage {
    pub fn new(p: &PoseEstimate) -> Self {
        Self::at(p.header.stamp_ns, MAP_FRAME, p.mean, *p)
    }
}
