//! A whole trajectory, sent in pieces: the filter's at the end of a run, the back end's as
//! it improves and at the end.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::chunked::chunked_message;
use super::form::Form;
use super::pose::Pose2;
use crate::capacity::{CapacityError, MAX_PATH_CHUNK_POSES};
use crate::header::Header;
use crate::transport::{Outlet, PublishError};

/// One pose of a path: a scan's stamp and the pose (`map_from_robot`) at it.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, FromZeros, Serialize, Deserialize,
)]
#[type_name("slam::StampedPose::v1")]
pub struct StampedPose {
    pub stamp_ns: u64,
    pub pose: Pose2,
}

impl From<slam_geom::StampedPose> for StampedPose {
    fn from(p: slam_geom::StampedPose) -> Self {
        Self {
            stamp_ns: p.stamp_ns,
            pose: p.pose.into(),
        }
    }
}

impl From<StampedPose> for slam_geom::StampedPose {
    fn from(p: StampedPose) -> Self {
        Self {
            stamp_ns: p.stamp_ns,
            pose: p.pose.into(),
        }
    }
}

chunked_message! {
    /// A piece of a path: poses `first .. first + pose_count` of `total`, in stamp order. A
    /// path of any length travels as consecutive chunks; the receiver has it all once it
    /// holds `total` poses. The header's `seq` numbers the chunks of one path from 0, its
    /// `stamp_ns` is the last scan's; [`crate::FLAG_FINAL`] marks a path in its last form.
    PathChunk, PathChunkRecord, StampedPose, MAX_PATH_CHUNK_POSES, "slam::PathChunk::v1",
    "path poses", poses {}
}

impl Outlet<PathChunk> {
    /// Publishes a whole path as consecutive chunks numbered from 0 (their `seq`), each
    /// stamped `stamp_ns` (the last scan's) in frame `map`, flagged when `form` is final.
    pub fn publish_path(
        &self,
        path: &[StampedPose],
        stamp_ns: u64,
        form: Form,
    ) -> Result<(), PublishError> {
        let total = path.len() as u64;
        for (index, chunk) in path.chunks(MAX_PATH_CHUNK_POSES).enumerate() {
            self.publish(|message| {
                message.header = form.header(index as u64, stamp_ns);
                message.first = (index * MAX_PATH_CHUNK_POSES) as u64;
                message.total = total;
                // Chunks are cut to the capacity, so this cannot fail.
                let _ = message.set(chunk);
            })?;
        }
        Ok(())
    }
}
