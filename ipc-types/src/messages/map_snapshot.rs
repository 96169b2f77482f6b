//! The map of the best particle.

use std::borrow::Cow;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::corner::MapCorner;
use crate::capacity::{CapacityError, MAX_MAP_CORNERS};
use crate::header::Header;

/// The confirmed corners of the best particle's map, in the map frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
#[type_name("slam::MapSnapshot::v1")]
pub struct MapSnapshot {
    /// Header of the last scan the map includes.
    pub header: Header,
    pub corners: BoundedArray<MapCorner, MAX_MAP_CORNERS>,
}

impl MapSnapshot {
    pub fn corners(&self) -> &[MapCorner] {
        self.corners.as_slice()
    }

    pub fn set(&mut self, corners: &[MapCorner]) -> Result<(), CapacityError> {
        self.corners.set("map corners", corners)
    }

    pub fn to_record(&self) -> MapSnapshotRecord<'_> {
        MapSnapshotRecord {
            header: self.header,
            corners: Cow::Borrowed(self.corners()),
        }
    }

    pub fn from_record(record: &MapSnapshotRecord<'_>) -> Result<Box<Self>, CapacityError> {
        let mut message = <Self as crate::Zeroable>::boxed_zeroed();
        message.header = record.header;
        message.set(&record.corners)?;
        Ok(message)
    }
}

/// A [`MapSnapshot`] without the unused capacity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapSnapshotRecord<'a> {
    pub header: Header,
    pub corners: Cow<'a, [MapCorner]>,
}

impl Serialize for MapSnapshot {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_record().serialize(serializer)
    }
}
