//! The simulator's true pose of the sensor.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::pose::Pose2;
use crate::header::Header;

/// The true pose (`world_from_robot`) at the time of the scan with the same sequence number.
/// Only a simulator can publish it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[type_name("slam::GroundTruthPose::v1")]
pub struct GroundTruthPose {
    pub header: Header,
    pub pose: Pose2,
}
