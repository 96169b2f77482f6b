//! The true corners of a simulated world.

use iceoryx2::prelude::ZeroCopySend;
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::corner::TrueCorner;
use super::corner_list::{CornerListRecord, corner_list_message};
use crate::capacity::{CapacityError, MAX_WORLD_CORNERS};
use crate::header::Header;

corner_list_message! {
    /// Every corner of the simulated world in the world frame, published once (with
    /// history, so a late subscriber still gets it) so a map can be scored.
    WorldCorners, TrueCorner, MAX_WORLD_CORNERS, "slam::WorldCorners::v1", "world corners"
}

/// [`WorldCorners`] without the unused capacity.
pub type WorldCornersRecord<'a> = CornerListRecord<'a, TrueCorner>;
