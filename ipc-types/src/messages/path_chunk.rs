//! The filter's whole trajectory, sent in pieces at the end of a run.

use std::borrow::Cow;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::pose::Pose2;
use crate::capacity::{CapacityError, MAX_PATH_CHUNK_POSES};
use crate::header::Header;

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

/// A piece of a path: poses `first .. first + pose_count` of `total`, in stamp order. A path
/// of any length travels as consecutive chunks; the receiver has it all once it holds
/// `total` poses.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
#[type_name("slam::PathChunk::v1")]
pub struct PathChunk {
    /// `seq` numbers the chunks of one path from 0; `stamp_ns` is the last scan's.
    pub header: Header,
    /// Index in the whole path of this chunk's first pose.
    pub first: u64,
    /// Poses in the whole path.
    pub total: u64,
    pub poses: BoundedArray<StampedPose, MAX_PATH_CHUNK_POSES>,
}

impl PathChunk {
    pub fn poses(&self) -> &[StampedPose] {
        self.poses.as_slice()
    }

    pub fn set(&mut self, poses: &[StampedPose]) -> Result<(), CapacityError> {
        self.poses.set("path poses", poses)
    }

    pub fn to_record(&self) -> PathChunkRecord<'_> {
        PathChunkRecord {
            header: self.header,
            first: self.first,
            total: self.total,
            poses: Cow::Borrowed(self.poses()),
        }
    }

    pub fn from_record(record: &PathChunkRecord<'_>) -> Result<Box<Self>, CapacityError> {
        let mut message = <Self as crate::Zeroable>::boxed_zeroed();
        message.header = record.header;
        message.first = record.first;
        message.total = record.total;
        message.set(&record.poses)?;
        Ok(message)
    }
}

/// [`PathChunk`] without the unused capacity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PathChunkRecord<'a> {
    pub header: Header,
    pub first: u64,
    pub total: u64,
    pub poses: Cow<'a, [StampedPose]>,
}

impl Serialize for PathChunk {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_record().serialize(serializer)
    }
}
