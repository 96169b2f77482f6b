//! The true corners of a simulated world.

use std::borrow::Cow;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::corner::TrueCorner;
use crate::capacity::{CapacityError, MAX_WORLD_CORNERS};
use crate::header::Header;

/// Every corner of the simulated world in the world frame, published once (with history, so
/// a late subscriber still gets it) so a map can be scored.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
#[type_name("slam::WorldCorners::v1")]
pub struct WorldCorners {
    pub header: Header,
    pub corners: BoundedArray<TrueCorner, MAX_WORLD_CORNERS>,
}

impl WorldCorners {
    pub fn corners(&self) -> &[TrueCorner] {
        self.corners.as_slice()
    }

    pub fn set(&mut self, corners: &[TrueCorner]) -> Result<(), CapacityError> {
        self.corners.set("world corners", corners)
    }

    pub fn to_record(&self) -> WorldCornersRecord<'_> {
        WorldCornersRecord {
            header: self.header,
            corners: Cow::Borrowed(self.corners()),
        }
    }

    pub fn from_record(record: &WorldCornersRecord<'_>) -> Result<Box<Self>, CapacityError> {
        let mut message = <Self as crate::Zeroable>::boxed_zeroed();
        message.header = record.header;
        message.set(&record.corners)?;
        Ok(message)
    }
}

/// [`WorldCorners`] without the unused capacity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
pub struct WorldCornersRecord<'a> {
    pub header: Header,
    pub corners: Cow<'a, [TrueCorner]>,
}

impl Serialize for WorldCorners {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_record().serialize(serializer)
    }
}
