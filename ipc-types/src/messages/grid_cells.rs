//! A saved occupancy grid, for a viewer: its geometry and its cells, in pieces.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::chunked::chunked_message;
use crate::capacity::{CapacityError, MAX_GRID_CHUNK_CELLS};
use crate::header::Header;

/// Where a grid lies and how large it is, as map.yaml and map.pgm give it.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, FromZeros, Serialize, Deserialize,
)]
#[type_name("slam::GridGeometry::v1")]
pub struct GridGeometry {
    /// Edge of a cell, metres.
    pub resolution: f64,
    /// The map-frame position of the lower-left corner of cell (0, 0), metres (map.yaml's
    /// `origin`, whose yaw is 0).
    pub origin: [f64; 2],
    /// Cells across (x) and down (y).
    pub width: u32,
    pub height: u32,
}

chunked_message! {
    /// Cells `first .. first + count` of a grid of `total` (`width * height`) cells, row by
    /// row from the lowest y (row 0 is the image's last row, a ROS `OccupancyGrid`'s
    /// order), each the map image's trinary pixel (`map.pgm`: 0 occupied, 254 free, 205
    /// unknown). A grid of several megabytes travels as consecutive pieces; the receiver has
    /// it once it holds `total` cells. The header's `seq` numbers the pieces from 0, its
    /// `stamp_ns` is the run's last scan's.
    GridCells, GridCellsRecord, u8, MAX_GRID_CHUNK_CELLS, "slam::GridCells::v1", "grid cells",
    cells {
        grid: GridGeometry,
    }
}
