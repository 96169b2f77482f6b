//! An occupancy grid, for a viewer and for the run's map: its geometry and its cells, in
//! pieces.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::bounded_array::BoundedArray;
use super::chunked::chunked_message;
use super::form::Form;
use crate::capacity::{CapacityError, MAX_GRID_CHUNK_CELLS};
use crate::header::Header;
use crate::transport::{Outlet, PublishError};

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

impl Outlet<GridCells> {
    /// Publishes a whole grid (`cells` row by row from the lowest y, trinary pixels) as
    /// consecutive pieces numbered from 0, each stamped `stamp_ns` (the last scan's).
    pub fn publish_grid(
        &self,
        grid: GridGeometry,
        cells: &[u8],
        stamp_ns: u64,
        form: Form,
    ) -> Result<(), PublishError> {
        for (index, piece) in cells.chunks(MAX_GRID_CHUNK_CELLS).enumerate() {
            self.publish(|message| {
                message.header = form.header(index as u64, stamp_ns);
                message.grid = grid;
                message.first = (index * MAX_GRID_CHUNK_CELLS) as u64;
                message.total = cells.len() as u64;
                // Pieces are cut to the capacity, so this cannot fail.
                let _ = message.set(piece);
            })?;
        }
        Ok(())
    }
}

/// A grid put together from its pieces.
#[derive(Debug, Clone, PartialEq)]
pub struct WholeGrid {
    /// The pieces' header (the last one's): its stamp and whether the grid is final.
    pub header: Header,
    pub geometry: GridGeometry,
    pub cells: Vec<u8>,
}

/// Collects a grid's pieces; they arrive in order on one lossless topic.
#[derive(Debug, Default)]
pub struct GridPieces {
    /// The grid's stamp and geometry, from its first piece.
    geometry: Option<(u64, GridGeometry)>,
    cells: Vec<u8>,
    /// Pieces that did not continue the grid where it stood (counted, not kept).
    pub out_of_place: u64,
}

impl GridPieces {
    /// Takes a piece; returns the whole grid when this piece completes it.
    pub fn add(&mut self, piece: &GridCells) -> Option<WholeGrid> {
        let geometry = (piece.header.stamp_ns, piece.grid);
        if piece.first == 0 {
            self.cells.clear();
            self.geometry = Some(geometry);
        }
        if piece.first != self.cells.len() as u64 || self.geometry != Some(geometry) {
            self.out_of_place += 1;
            return None;
        }
        self.cells.extend_from_slice(piece.cells());
        if !piece.is_last_piece() {
            return None;
        }
        let (_, geometry) = self.geometry.take()?;
        let cells = std::mem::take(&mut self.cells);
        let size = u64::from(geometry.width) * u64::from(geometry.height);
        if cells.len() as u64 != size || piece.total != size {
            // Pieces that do not make the grid they describe.
            self.out_of_place += 1;
            return None;
        }
        Some(WholeGrid {
            header: piece.header,
            geometry,
            cells,
        })
    }
}
