//! The filter's particles, for a viewer: every particle's pose and weight, every few scans.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::chunked::chunked_message;
use super::pose::Pose2;
use crate::capacity::{CapacityError, MAX_CLOUD_CHUNK_PARTICLES};
use crate::header::Header;

/// One particle: its pose (`map_from_robot`) and its weight, normalised over the cloud.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, FromZeros, Serialize, Deserialize,
)]
#[type_name("slam::Particle::v1")]
pub struct Particle {
    pub pose: Pose2,
    pub weight: f64,
}

chunked_message! {
    /// Particles `first .. first + count` of a cloud of `total`, all at one scan, whose
    /// header (`seq`, `stamp_ns`) the piece carries, in frame `map`. A cloud of any size
    /// (mapping allows a million particles) travels as consecutive pieces, so the message
    /// stays the size of a scan's; the receiver has the cloud once it holds `total`.
    ParticleCloud, ParticleCloudRecord, Particle, MAX_CLOUD_CHUNK_PARTICLES,
    "slam::ParticleCloud::v1", "cloud particles", particles {}
}
