//! What every message type has in common.

use std::fmt::Debug;

use iceoryx2::prelude::ZeroCopySend;

use crate::header::Header;
use crate::messages::{
    Features, GridCells, GroundTruthPose, LaserScan, MapSnapshot, Odometry, ParticleCloud,
    PathChunk, PoseEstimate, WorldCorners,
};
use crate::zeroed::Zeroable;

/// A message that can travel over a [`crate::Topic`]: fixed layout, zero-copy, valid when
/// zeroed, with a [`Header`].
pub trait Message: Debug + ZeroCopySend + Zeroable + 'static {
    fn header(&self) -> &Header;
    fn header_mut(&mut self) -> &mut Header;
}

macro_rules! impl_message {
    ($($t:ty),* $(,)?) => {
        $(
            impl Message for $t {
                fn header(&self) -> &Header {
                    &self.header
                }
                fn header_mut(&mut self) -> &mut Header {
                    &mut self.header
                }
            }
        )*
    };
}

impl_message!(
    LaserScan,
    Odometry,
    GroundTruthPose,
    WorldCorners,
    Features,
    PoseEstimate,
    MapSnapshot,
    PathChunk,
    ParticleCloud,
    GridCells,
);
