//! `foxglove.FrameTransform` on `/tf`: where the robot is in the map, and where the sensor
//! is on the robot, so the 3D panel can draw every frame in the map.

use schemars::JsonSchema;
use serde::Serialize;

use crate::geometry::{Quaternion, Vector3};
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// The robot body frame (REP 105).
pub const BASE_FRAME: &str = "base_link";

/// Exactly Foxglove's fields.
#[derive(Debug, Serialize, JsonSchema)]
pub struct TransformMessage<'a> {
    pub timestamp: Time,
    pub parent_frame_id: &'a str,
    pub child_frame_id: &'a str,
    pub translation: Vector3,
    pub rotation: Quaternion,
}

impl ChannelMessage for TransformMessage<'_> {
    const TOPIC: &'static str = "/tf";
    const SCHEMA: &'static str = "foxglove.FrameTransform";
}

impl<'a> TransformMessage<'a> {
    /// `parent_from_child` as a planar pose.
    pub fn planar(stamp_ns: u64, parent: &'a str, child: &'a str, p: ipc_types::Pose2) -> Self {
        Self {
            timestamp: Time::from_ns(stamp_ns),
            parent_frame_id: parent,
            child_frame_id: child,
            translation: Vector3 {
                x: p.x,
                y: p.y,
                z: 0.0,
            },
            rotation: Quaternion::from_yaw(p.yaw),
        }
    }
}
