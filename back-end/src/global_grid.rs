//! The run's occupancy grid: every submap's cells laid out at its solved pose. Each submap
//! that knows a world cell votes free or occupied; a cell is occupied when at least as many
//! submaps saw a surface there as saw free space (a wall seen from two submaps a cell apart
//! stays a wall), free when more saw it free (a person who walked through is gone), unknown
//! when none knows it.

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::occupancy_grid::{
    CellState, GridError, MAX_CELLS, MAX_LOG_ODDS, MIN_LOG_ODDS, OccupancyGrid,
};
use crate::submap_grid::SubmapGrid;

/// Lays `submaps` (each with its `world_from_submap`) out on a grid of `resolution`;
/// `None` when there is none.
pub fn render(
    submaps: &[(Pose2, &SubmapGrid)],
    resolution: f64,
) -> Result<Option<OccupancyGrid>, GridError> {
    let cell = |p: Vector2<f64>| {
        [
            (p.x / resolution).floor() as i64,
            (p.y / resolution).floor() as i64,
        ]
    };
    let boxes: Vec<([i64; 2], [i64; 2])> = submaps
        .iter()
        .map(|(pose, grid)| {
            let corners = grid.corners().map(|c| cell(pose.transform(c)));
            let lo = [0, 1].map(|a| corners.iter().map(|c| c[a]).min().unwrap_or(0));
            let hi = [0, 1].map(|a| corners.iter().map(|c| c[a]).max().unwrap_or(0));
            (lo, hi)
        })
        .collect();
    if boxes.is_empty() {
        return Ok(None);
    }
    let lo = [0, 1].map(|a| boxes.iter().map(|b| b.0[a]).min().unwrap_or(0));
    let hi = [0, 1].map(|a| boxes.iter().map(|b| b.1[a]).max().unwrap_or(0));
    let width = usize::try_from(hi[0] - lo[0] + 1).unwrap_or(usize::MAX);
    let height = usize::try_from(hi[1] - lo[1] + 1).unwrap_or(usize::MAX);
    if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
        return Err(GridError::TooLarge { width, height });
    }
    // Per world cell: submaps that saw it occupied, and free, and the last submap that
    // voted on it (its index + 1): each votes once per cell.
    let mut votes = vec![(0u16, 0u16); width * height];
    let mut voted = vec![0u32; width * height];
    for (number, (pose, grid)) in submaps.iter().enumerate() {
        let id = number as u32 + 1;
        let submap_from_world = pose.inverse();
        // Four samples a known cell, half a cell apart, find every world cell the submap
        // knows something of, however it is turned; each of those takes the state of the
        // submap's cell under its centre, so walls keep their place and width.
        let quarter = grid.resolution() / 4.0;
        let offsets = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
            .map(|(x, y)| pose.rotation() * Vector2::new(x, y) * quarter);
        for (centre, _) in grid.known_cells() {
            let at = pose.transform(centre);
            for offset in &offsets {
                let p = at + offset;
                let x = (p.x / resolution).floor() as i64;
                let y = (p.y / resolution).floor() as i64;
                let (col, row) = (x - lo[0], y - lo[1]);
                if col < 0 || row < 0 || col >= width as i64 || row >= height as i64 {
                    continue;
                }
                let i = row as usize * width + col as usize;
                if voted[i] == id {
                    continue;
                }
                voted[i] = id;
                let world_centre = Vector2::new(x as f64 + 0.5, y as f64 + 0.5) * resolution;
                match grid.state_at(submap_from_world.transform(world_centre)) {
                    CellState::Occupied => votes[i].0 = votes[i].0.saturating_add(1),
                    CellState::Free => votes[i].1 = votes[i].1.saturating_add(1),
                    CellState::Unknown => {}
                }
            }
        }
    }
    drop(voted);
    // The grid is cut to the cells some submap knows: a submap's box reaches as far as its
    // longest beam's end.
    let known = |i: usize| votes[i] != (0, 0);
    let rows: Vec<usize> = (0..height)
        .filter(|&y| (0..width).any(|x| known(y * width + x)))
        .collect();
    let cols: Vec<usize> = (0..width)
        .filter(|&x| rows.iter().any(|&y| known(y * width + x)))
        .collect();
    let (Some(&y0), Some(&y1), Some(&x0), Some(&x1)) =
        (rows.first(), rows.last(), cols.first(), cols.last())
    else {
        return Ok(None);
    };
    let log_odds = (y0..=y1)
        .flat_map(|y| (x0..=x1).map(move |x| y * width + x))
        .map(|i| match votes[i] {
            (occupied, free) if occupied > 0 && occupied >= free => MAX_LOG_ODDS,
            (_, free) if free > 0 => MIN_LOG_ODDS,
            _ => 0.0,
        })
        .collect();
    let min_index = [lo[0] + x0 as i64, lo[1] + y0 as i64];
    OccupancyGrid::from_log_odds(resolution, min_index, x1 - x0 + 1, log_odds).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compact_scan::CompactScan;
    use crate::occupancy_grid::GridConfig;

    /// A submap of a wall 2 m ahead, seen from its origin three times (free space is free
    /// after three passes).
    fn wall_submap() -> SubmapGrid {
        let ranges: Vec<f32> = (0..91)
            .map(|i| {
                let bearing = -0.7 + 1.4 * f64::from(i) / 90.0;
                (2.0 / bearing.cos()) as f32
            })
            .collect();
        let scan = CompactScan::new(-0.7, 1.4 / 90.0, 0.1, 30.0, &ranges, 0.0, 5.0);
        SubmapGrid::trace(&GridConfig::default(), &[(Pose2::IDENTITY, &scan); 3])
            .unwrap()
            .unwrap()
    }

    fn state(grid: &OccupancyGrid, p: Vector2<f64>) -> CellState {
        let res = grid.resolution_m();
        let [x0, y0] = grid.origin();
        let col = ((p.x - x0) / res).floor() as usize;
        let row = ((p.y - y0) / res).floor() as usize;
        grid.state(col, row)
    }

    #[test]
    fn a_submap_moved_by_the_graph_moves_its_wall() {
        let submap = wall_submap();
        let at = Pose2::new(10.0, -3.0, std::f64::consts::FRAC_PI_2);
        let grid = render(&[(at, &submap)], 0.05).unwrap().unwrap();
        // The wall 2 m ahead of the submap's origin, which now faces +y.
        assert_eq!(
            state(&grid, Vector2::new(10.0, -1.0 + 0.01)),
            CellState::Occupied
        );
        assert_eq!(state(&grid, Vector2::new(10.0, -2.0)), CellState::Free);
        assert_eq!(render(&[], 0.05).unwrap().map(|g| g.width()), None);
    }

    #[test]
    fn a_tie_keeps_the_wall_and_more_submaps_seeing_free_space_clear_it() {
        let wall = wall_submap();
        // A submap 0.3 m further on sees free space through the first one's wall.
        let further = Pose2::new(0.3, 0.0, 0.0);
        let first_wall = Vector2::new(2.01, 0.0);
        let tie = render(&[(Pose2::IDENTITY, &wall), (further, &wall)], 0.05)
            .unwrap()
            .unwrap();
        assert_eq!(state(&tie, first_wall), CellState::Occupied);
        let outvoted = render(
            &[(Pose2::IDENTITY, &wall), (further, &wall), (further, &wall)],
            0.05,
        )
        .unwrap()
        .unwrap();
        assert_eq!(state(&outvoted, first_wall), CellState::Free);
    }
}
