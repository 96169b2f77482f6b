//! A submap's occupancy, as the map keeps it: the log-odds grid traced from the scans the
//! submap owns, in its own frame ([`OccupancyGrid`], the one grid tracer), at a byte a cell
//! and only over each row's known stretch. The run's grid is these laid out at the
//! submaps' solved poses and added ([`crate::global_grid`]): each scan is owned by one
//! submap, so the sum is the evidence of every scan, as one trace over the whole path would
//! have it; a closure that moves a submap moves its walls with it, and nothing is traced
//! again.

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::compact_scan::CompactScan;
use crate::global_grid::floor;
use crate::occupancy_grid::{CellState, GridConfig, GridError, OccupancyGrid, state_of};

/// Steps of log-odds a byte counts in: 32 a unit keeps the clamps (-2 to 3.5) within a
/// signed byte, and a step is far finer than a hit or a pass.
const STEPS_PER_UNIT: f32 = 32.0;

/// A submap's log-odds over the box its scans reached (submap frame).
#[derive(Debug, Clone)]
pub struct SubmapGrid {
    resolution: f64,
    /// Global index (in the submap frame) of cell `(0, 0)`.
    min_index: [i64; 2],
    width: usize,
    /// Per row from the lowest y: its first known column and where its cells start in
    /// `cells` (they run to the next row's start).
    rows: Vec<(u32, u32)>,
    /// The known stretches' log-odds, in steps of `1 / STEPS_PER_UNIT`.
    cells: Vec<i8>,
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

    /// `grid`, each row kept from its first to its last cell with any evidence.
    pub fn of(grid: &OccupancyGrid) -> Self {
        let step = |col, row| (grid.log_odds(col, row) * STEPS_PER_UNIT).round() as i8;
        let mut rows = Vec::with_capacity(grid.height());
        let mut cells = Vec::new();
        for row in 0..grid.height() {
            let known = |&col: &usize| step(col, row) != 0;
            let first = (0..grid.width()).find(known).unwrap_or(0);
            let last = (0..grid.width()).rev().find(known);
            rows.push((first as u32, cells.len() as u32));
            if let Some(last) = last {
                cells.extend((first..=last).map(|col| step(col, row)));
            }
        }
        Self {
            resolution: grid.resolution_m(),
            min_index: grid.min_index(),
            width: grid.width(),
            rows,
            cells,
        }
    }

    /// The log-odds of the cell holding `point` (submap frame): 0 where nothing is known.
    pub fn log_odds_at(&self, point: Vector2<f64>) -> f32 {
        let col = floor(point.x / self.resolution) - self.min_index[0];
        let row = floor(point.y / self.resolution) - self.min_index[1];
        self.cell(col, row)
    }

    /// What the scans it owns say of the cell holding `point` (submap frame).
    pub fn state_at(&self, point: Vector2<f64>) -> CellState {
        state_of(self.log_odds_at(point))
    }

    /// The centres of its occupied cells (submap frame).
    pub fn occupied_cells(&self) -> impl Iterator<Item = Vector2<f64>> + '_ {
        self.stretches()
            .flat_map(move |(first, count)| {
                (0..count).map(move |k| first + Vector2::new(k as f64 * self.resolution, 0.0))
            })
            .filter(|&centre| self.state_at(centre) == CellState::Occupied)
    }

    /// The corners of its box (submap frame).
    pub fn corners(&self) -> [Vector2<f64>; 4] {
        let lo = Vector2::new(self.min_index[0] as f64, self.min_index[1] as f64) * self.resolution;
        let size = Vector2::new(self.width as f64, self.rows.len() as f64) * self.resolution;
        [
            lo,
            lo + Vector2::new(size.x, 0.0),
            lo + size,
            lo + Vector2::new(0.0, size.y),
        ]
    }

    /// The log-odds at `out.len()` points from `from` on by steps of `step` (submap frame).
    pub fn sample_row(&self, from: Vector2<f64>, step: Vector2<f64>, out: &mut [f32]) {
        let x = from.x / self.resolution - self.min_index[0] as f64;
        let y = from.y / self.resolution - self.min_index[1] as f64;
        let (dx, dy) = (step.x / self.resolution, step.y / self.resolution);
        for (k, value) in out.iter_mut().enumerate() {
            let k = k as f64;
            *value = self.cell(floor(x + k * dx), floor(y + k * dy));
        }
    }

    /// The log-odds of cell `(col, row)` of the box: 0 where nothing is known.
    fn cell(&self, col: i64, row: i64) -> f32 {
        let (Ok(col), Ok(row)) = (usize::try_from(col), usize::try_from(row)) else {
            return 0.0;
        };
        let Some(&(first, start)) = self.rows.get(row) else {
            return 0.0;
        };
        let end = self
            .rows
            .get(row + 1)
            .map_or(self.cells.len(), |&(_, next)| next as usize);
        let Some(k) = col.checked_sub(first as usize) else {
            return 0.0;
        };
        let i = start as usize + k;
        if col >= self.width || i >= end {
            return 0.0;
        }
        f32::from(self.cells[i]) / STEPS_PER_UNIT
    }

    /// Each row's known stretch: the centre of its first cell (submap frame) and its
    /// length in cells.
    pub fn stretches(&self) -> impl Iterator<Item = (Vector2<f64>, usize)> + '_ {
        self.rows
            .iter()
            .enumerate()
            .filter_map(|(row, &(first, start))| {
                let end = self
                    .rows
                    .get(row + 1)
                    .map_or(self.cells.len(), |&(_, next)| next as usize);
                let count = end - start as usize;
                let col = self.min_index[0] + i64::from(first);
                let y = self.min_index[1] + row as i64;
                (count > 0).then(|| {
                    let centre = Vector2::new(col as f64 + 0.5, y as f64 + 0.5) * self.resolution;
                    (centre, count)
                })
            })
    }

    /// Edge of a cell, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Memory held, bytes.
    pub fn bytes(&self) -> usize {
        self.cells.capacity() + self.rows.capacity() * std::mem::size_of::<(u32, u32)>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cells_read_back_as_the_grid_had_them() {
        let ranges: Vec<f32> = (0..181).map(|_| 2.0).collect();
        let scan = CompactScan::new(-1.5, 3.0 / 180.0, 0.1, 30.0, &ranges, 0.0, 5.0);
        let config = GridConfig::default();
        let pose = Pose2::new(0.3, -0.2, 0.4);
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
                let error = (kept.log_odds_at(centre) - grid.log_odds(col, row)).abs();
                assert!(error <= 0.5 / STEPS_PER_UNIT, "{col} {row}: {error}");
            }
        }
        // Beyond the box nothing is known; inside, the beams' free space and ends are, and
        // the rows keep only their known stretch.
        assert_eq!(kept.log_odds_at(Vector2::new(50.0, 0.0)), 0.0);
        assert_eq!(kept.log_odds_at(Vector2::new(-50.0, 0.0)), 0.0);
        assert!(kept.log_odds_at(pose.position()) < 0.0);
        let wall = pose.transform(Vector2::new(2.0, 0.0));
        let near_wall = (-1..=1).flat_map(|dx| (-1..=1).map(move |dy| (dx, dy)));
        let hit = near_wall
            .map(|(dx, dy)| wall + Vector2::new(f64::from(dx), f64::from(dy)) * res)
            .any(|p| kept.log_odds_at(p) > 0.0);
        assert!(hit);
        assert!(kept.cells.len() < grid.width() * grid.height());
    }
}
