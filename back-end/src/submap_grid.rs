//! A submap's occupancy, as the map keeps it: the occupancy grid traced from the submap's
//! own scans in its own frame ([`OccupancyGrid`], the one grid tracer), thresholded to free,
//! occupied or unknown at two bits a cell. The run's grid is these laid out at the submaps'
//! solved poses ([`crate::global_grid`]): a closure that moves a submap moves its walls
//! with it, and nothing is traced again.

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::compact_scan::CompactScan;
use crate::occupancy_grid::{CellState, GridConfig, GridError, OccupancyGrid};

/// Cells a byte holds.
const PER_BYTE: usize = 4;

/// A submap's cells, thresholded, over the box its scans reached (submap frame).
#[derive(Debug, Clone)]
pub struct SubmapGrid {
    resolution: f64,
    /// Global index (in the submap frame) of cell `(0, 0)`.
    min_index: [i64; 2],
    width: usize,
    height: usize,
    /// Two bits a cell, row by row from the lowest y: [`CellState`] as 0 unknown, 1 free,
    /// 2 occupied.
    bits: Vec<u8>,
}

impl SubmapGrid {
    /// Traces `scans` (each at its sensor pose in the submap frame); `None` when no beam
    /// is left to trace.
    pub fn trace(
        config: &GridConfig,
        scans: &[(Pose2, &CompactScan)],
    ) -> Result<Option<Self>, GridError> {
        Ok(OccupancyGrid::build(config, scans)?.map(|grid| Self::of(&grid)))
    }

    /// `grid` thresholded.
    pub fn of(grid: &OccupancyGrid) -> Self {
        let (width, height) = (grid.width(), grid.height());
        let mut bits = vec![0u8; (width * height).div_ceil(PER_BYTE)];
        for row in 0..height {
            for col in 0..width {
                let code = match grid.state(col, row) {
                    CellState::Unknown => 0,
                    CellState::Free => 1,
                    CellState::Occupied => 2,
                };
                let i = row * width + col;
                bits[i / PER_BYTE] |= code << (2 * (i % PER_BYTE));
            }
        }
        Self {
            resolution: grid.resolution_m(),
            min_index: grid.min_index(),
            width,
            height,
            bits,
        }
    }

    /// The state of the cell holding `point` (submap frame).
    pub fn state_at(&self, point: Vector2<f64>) -> CellState {
        let col = (point.x / self.resolution).floor() as i64 - self.min_index[0];
        let row = (point.y / self.resolution).floor() as i64 - self.min_index[1];
        if col < 0 || row < 0 || col >= self.width as i64 || row >= self.height as i64 {
            return CellState::Unknown;
        }
        let i = row as usize * self.width + col as usize;
        match (self.bits[i / PER_BYTE] >> (2 * (i % PER_BYTE))) & 3 {
            1 => CellState::Free,
            2 => CellState::Occupied,
            _ => CellState::Unknown,
        }
    }

    /// The corners of the box the cells cover, submap frame.
    pub fn corners(&self) -> [Vector2<f64>; 4] {
        let lo = Vector2::new(self.min_index[0] as f64, self.min_index[1] as f64) * self.resolution;
        let hi = lo + Vector2::new(self.width as f64, self.height as f64) * self.resolution;
        [lo, Vector2::new(hi.x, lo.y), hi, Vector2::new(lo.x, hi.y)]
    }

    /// Every known cell: its centre (submap frame) and whether it is occupied. Whole
    /// bytes of unknown cells are skipped at once: most of a submap's box is unknown.
    pub fn known_cells(&self) -> impl Iterator<Item = (Vector2<f64>, bool)> + '_ {
        self.bits
            .iter()
            .enumerate()
            .filter(|(_, byte)| **byte != 0)
            .flat_map(move |(b, &byte)| {
                (0..PER_BYTE).filter_map(move |k| {
                    let code = (byte >> (2 * k)) & 3;
                    let i = b * PER_BYTE + k;
                    (code != 0 && i < self.width * self.height).then(|| {
                        let col = (i % self.width) as i64 + self.min_index[0];
                        let row = (i / self.width) as i64 + self.min_index[1];
                        let centre =
                            Vector2::new(col as f64 + 0.5, row as f64 + 0.5) * self.resolution;
                        (centre, code == 2)
                    })
                })
            })
    }

    /// Edge of a cell, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Memory held, bytes.
    pub fn bytes(&self) -> usize {
        self.bits.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thresholded_cells_read_back_where_the_grid_had_them() {
        let ranges: Vec<f32> = (0..181).map(|_| 2.0).collect();
        let scan = CompactScan::new(-1.5, 3.0 / 180.0, 0.1, 30.0, &ranges, 0.0, 5.0);
        let config = GridConfig::default();
        let pose = Pose2::new(0.3, -0.2, 0.4);
        // Free space is free after three passes.
        let grid = OccupancyGrid::build(&config, &[(pose, &scan); 3])
            .unwrap()
            .unwrap();
        let kept = SubmapGrid::of(&grid);
        let res = grid.resolution_m();
        let [x0, y0] = grid.origin();
        for row in 0..grid.height() {
            for col in 0..grid.width() {
                let centre =
                    Vector2::new(x0 + (col as f64 + 0.5) * res, y0 + (row as f64 + 0.5) * res);
                assert_eq!(kept.state_at(centre), grid.state(col, row), "{col} {row}");
            }
        }
        // Beyond the box nothing is known; inside, the beams' free space and ends are.
        assert_eq!(kept.state_at(Vector2::new(50.0, 0.0)), CellState::Unknown);
        assert_eq!(kept.state_at(pose.position()), CellState::Free);
        let wall = pose.transform(Vector2::new(2.0, 0.0));
        let near_wall = (-1..=1).flat_map(|dx| (-1..=1).map(move |dy| (dx, dy)));
        let occupied = near_wall
            .map(|(dx, dy)| wall + Vector2::new(f64::from(dx), f64::from(dy)) * res)
            .filter(|&p| kept.state_at(p) == CellState::Occupied)
            .count();
        assert!(occupied >= 1, "{occupied}");
    }
}
