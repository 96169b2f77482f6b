//! The final path as `foxglove.PosesInFrame`, once all its chunks are in.

use schemars::JsonSchema;
use serde::Serialize;

use ipc_types::{PathChunk, Pose2, StampedPose};

use crate::geometry::Pose;
use crate::pose::MAP_FRAME;
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// The best particle's whole path, one message: Foxglove draws the latest message of a
/// topic, so the path must not arrive as the chunks it travels in. Foxglove's fields, then
/// each pose's stamp and planar pose.
#[derive(Debug, Serialize, JsonSchema)]
pub struct PathMessage {
    /// The last pose's stamp.
    pub timestamp: Time,
    pub frame_id: &'static str,
    pub poses: Vec<Pose>,
    pub stamps_ns: Vec<u64>,
    pub planar: Vec<Pose2>,
}

impl ChannelMessage for PathMessage {
    const TOPIC: &'static str = "/slam/path";
    const SCHEMA: &'static str = "foxglove.PosesInFrame";
}

impl PathMessage {
    pub fn new(poses: &[StampedPose]) -> Self {
        Self {
            timestamp: Time::from_ns(poses.last().map_or(0, |p| p.stamp_ns)),
            frame_id: MAP_FRAME,
            poses: poses.iter().map(|p| p.pose.into()).collect(),
            stamps_ns: poses.iter().map(|p| p.stamp_ns).collect(),
            planar: poses.iter().map(|p| p.pose).collect(),
        }
    }
}

/// The final path as map-sink wrote it (`trajectory.tum`), one message at the end, in the
/// form of [`PathMessage`].
#[derive(Debug, Serialize, JsonSchema)]
#[serde(transparent)]
pub struct MapPathMessage(pub PathMessage);

impl ChannelMessage for MapPathMessage {
    const TOPIC: &'static str = "/map/path";
    const SCHEMA: &'static str = "foxglove.PosesInFrame";
}

/// The back end's path (graph-proc's pose graph, solved), one message at the end of the
/// stream, in the form of [`PathMessage`].
#[derive(Debug, Serialize, JsonSchema)]
#[serde(transparent)]
pub struct GraphPathMessage(pub PathMessage);

impl ChannelMessage for GraphPathMessage {
    const TOPIC: &'static str = "/graph/path";
    const SCHEMA: &'static str = "foxglove.PosesInFrame";
}

/// Collects a path's chunks; they arrive in order on one lossless topic.
#[derive(Debug, Default)]
pub struct PathChunks {
    poses: Vec<StampedPose>,
    /// Chunks that did not continue the path where it stood (counted, not recorded).
    pub out_of_place: u64,
}

impl PathChunks {
    /// Takes a chunk; returns the whole path when this chunk completes it.
    pub fn add(&mut self, chunk: &PathChunk) -> Option<Vec<StampedPose>> {
        if chunk.first == 0 {
            // A new path (a source that sends more than one) starts over.
            self.poses.clear();
        }
        if chunk.first != self.poses.len() as u64 {
            self.out_of_place += 1;
            return None;
        }
        self.poses.extend_from_slice(chunk.poses());
        (self.poses.len() as u64 == chunk.total).then(|| std::mem::take(&mut self.poses))
    }
}
