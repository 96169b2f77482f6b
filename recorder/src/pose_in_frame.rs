//! `foxglove.PoseInFrame`, with our fields after Foxglove's.

use schemars::JsonSchema;
use serde::Serialize;

use ipc_types::Pose2;

use crate::geometry::Pose;
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// A pose in a named frame: Foxglove's fields (`timestamp`, `frame_id`, `pose`), then the
/// fields of `ours` beside them, so that what the pipeline said is kept whole.
#[derive(Debug, Serialize, JsonSchema)]
pub struct PoseInFrame<T> {
    pub timestamp: Time,
    pub frame_id: &'static str,
    pub pose: Pose,
    #[serde(flatten)]
    pub ours: T,
}

/// What a [`PoseInFrame`] carries beside Foxglove's fields names the topic it is recorded on.
pub trait PoseTopic {
    const TOPIC: &'static str;
}

impl<T: PoseTopic + Serialize + JsonSchema> ChannelMessage for PoseInFrame<T> {
    const TOPIC: &'static str = T::TOPIC;
    const SCHEMA: &'static str = "foxglove.PoseInFrame";
}

impl<T> PoseInFrame<T> {
    /// `planar` at `stamp_ns` in `frame_id`, with `ours`.
    pub fn at(stamp_ns: u64, frame_id: &'static str, planar: Pose2, ours: T) -> Self {
        Self {
            timestamp: Time::from_ns(stamp_ns),
            frame_id,
            pose: planar.into(),
            ours,
        }
    }
}
