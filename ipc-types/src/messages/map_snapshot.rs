//! The map of the best particle.

use iceoryx2::prelude::ZeroCopySend;
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::corner::MapCorner;
use super::corner_list::{CornerListRecord, corner_list_message};
use crate::capacity::{CapacityError, MAX_MAP_CORNERS};
use crate::header::Header;

corner_list_message! {
    /// The confirmed corners of the best particle's map, in the map frame, with the header
    /// of the last scan the map includes.
    MapSnapshot, MapCorner, MAX_MAP_CORNERS, "slam::MapSnapshot::v1", "map corners"
}

/// A [`MapSnapshot`] without the unused capacity.
pub type MapSnapshotRecord<'a> = CornerListRecord<'a, MapCorner>;
