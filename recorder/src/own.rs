//! Our messages that no Foxglove schema fits, recorded whole under schemas of our own
//! (`slam.*`), so that nothing the pipeline said is lost. Each is the message's own serde
//! form (ipc-types, with its JSON schema), so its fields are listed once, in the message.

use schemars::JsonSchema;
use serde::Serialize;

use ipc_types::{Corner, FeaturesRecord, Header, MapSnapshot, Odometry, WorldCornersRecord};

use crate::schema::ChannelMessage;

impl ChannelMessage for Odometry {
    const TOPIC: &'static str = "/robot/odometry";
    const SCHEMA: &'static str = "slam.Odometry";
}

impl ChannelMessage for FeaturesRecord<'_> {
    const TOPIC: &'static str = "/perception/features";
    const SCHEMA: &'static str = "slam.Features";
}

impl ChannelMessage for WorldCornersRecord<'_> {
    const TOPIC: &'static str = "/sim/world_corners";
    const SCHEMA: &'static str = "slam.WorldCorners";
}

/// `ipc_types::MapSnapshot`: the best particle's corners, in the map frame. Owned, as a
/// snapshot may be held back until a later one replaces it.
#[derive(Debug, Serialize, JsonSchema)]
pub struct MapMessage {
    pub header: Header,
    pub corners: Vec<ObservedCorner>,
}

/// A map corner as one object: the corner's fields and the scans that saw it beside them.
#[derive(Debug, Serialize, JsonSchema)]
pub struct ObservedCorner {
    #[serde(flatten)]
    pub corner: Corner,
    pub observations: u32,
}

impl ChannelMessage for MapMessage {
    const TOPIC: &'static str = "/slam/map";
    const SCHEMA: &'static str = "slam.MapSnapshot";
}

impl MapMessage {
    pub fn new(m: &MapSnapshot) -> Self {
        Self {
            header: m.header,
            corners: m
                .corners()
                .iter()
                .map(|c| ObservedCorner {
                    corner: c.corner,
                    observations: c.observations,
                })
                .collect(),
        }
    }
}
