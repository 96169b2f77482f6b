//! Where a saved grid's cells lie in the map frame, for the fields computed over them.

use saved_map::{CellState, GridMap};

/// A grid's cells in the map frame: row 0 the lowest y, cells indexed row by row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CellFrame {
    /// The lower-left corner of cell (0, 0), map frame.
    pub origin: [f64; 2],
    /// A cell's edge, metres.
    pub resolution: f64,
    pub width: usize,
    pub height: usize,
}

impl CellFrame {
    /// The frame of `grid`'s cells.
    pub fn of(grid: &GridMap) -> Self {
        Self {
            origin: [grid.yaml.origin[0], grid.yaml.origin[1]],
            resolution: grid.yaml.resolution,
            width: grid.width,
            height: grid.height,
        }
    }

    /// The index of the cell `(x, y)` (map frame) lies in; `None` off the grid.
    #[inline]
    pub fn index(&self, x: f64, y: f64) -> Option<usize> {
        let col = ((x - self.origin[0]) / self.resolution).floor();
        let row = ((y - self.origin[1]) / self.resolution).floor();
        // Written so that NaN fails every comparison.
        if col >= 0.0 && row >= 0.0 && col < self.width as f64 && row < self.height as f64 {
            Some(row as usize * self.width + col as usize)
        } else {
            None
        }
    }

    /// The centre of cell `index`, map frame.
    pub fn centre(&self, index: usize) -> [f64; 2] {
        let (col, row) = (index % self.width, index / self.width);
        [
            self.origin[0] + (col as f64 + 0.5) * self.resolution,
            self.origin[1] + (row as f64 + 0.5) * self.resolution,
        ]
    }
}

/// Which cells of a grid were seen, free or occupied: a beam ending in one can be judged by
/// a field of the grid, one ending in unknown space cannot.
#[derive(Debug, Clone)]
pub(crate) struct SeenCells {
    frame: CellFrame,
    seen: Vec<bool>,
}

impl SeenCells {
    /// The seen cells of `grid`.
    pub fn of(grid: &GridMap) -> Self {
        Self {
            frame: CellFrame::of(grid),
            seen: grid
                .cells
                .iter()
                .map(|c| *c != CellState::Unknown)
                .collect(),
        }
    }

    /// Whether `(x, y)` (map frame) lies in a seen cell.
    #[inline]
    pub fn contains(&self, x: f64, y: f64) -> bool {
        self.frame.index(x, y).is_some_and(|i| self.seen[i])
    }
}
