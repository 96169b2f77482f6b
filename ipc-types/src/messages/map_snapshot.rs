//! The map of the best particle.

use std::borrow::Cow;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};

use super::corner::MapCorner;
use crate::capacity::{CapacityError, MAX_MAP_CORNERS, fill, used};
use crate::header::Header;

/// The confirmed corners of the best particle's map, in the map frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("slam::MapSnapshot::v1")]
pub struct MapSnapshot {
    /// Header of the last scan the map includes.
    pub header: Header,
    pub corner_count: u32,
    /// Keeps the layout free of implicit padding; always 0.
    pub reserved: u32,
    pub corners: [MapCorner; MAX_MAP_CORNERS],
}

impl MapSnapshot {
    pub fn corners(&self) -> &[MapCorner] {
        used(&self.corners, self.corner_count)
    }

    pub fn set(&mut self, corners: &[MapCorner]) -> Result<(), CapacityError> {
        self.corner_count = fill("map corners", &mut self.corners, corners)?;
        Ok(())
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
