//! A saved map's occupancy grid as prior evidence, for a run that maps on top of it.
//!
//! The saved image is trinary: it says a cell was occupied, free or unknown, not how sure
//! the run that drew it was. So an occupied pixel counts as one return's worth of evidence
//! and a free one as three passes' worth: each just past its threshold, so that a cell the
//! new run does not see keeps the state it was saved with, and one it sees is decided by
//! what it sees there a few times. A saved wall that the new run's beams pass through three
//! times becomes unknown and twelve times free (a door that was closed and is open now: a
//! pass lowers a wall cell less than a free one, see [`back_end::occupancy_grid`]); a saved
//! free cell that its returns hit three times becomes occupied (a new wall).
//!
//! The saved grid is laid onto this run's cells, which line up with multiples of the run's
//! resolution. A map this pipeline saved at the run's resolution lines up cell for cell;
//! any other (another resolution, an origin off the multiples of it) is resampled: a cell
//! takes the state of the saved cells it overlaps, occupied if any of them is, else free if
//! any is, so that a thin wall survives a coarser grid. A rotated grid (origin yaw other
//! than 0) is refused.

use back_end::occupancy_grid::{
    CellState, GridError, HIT_LOG_ODDS, MAX_CELLS, MISS_LOG_ODDS, OccupancyGrid, RESOLUTION_RANGE_M,
};
use saved_map::GridMap;

/// The evidence of a saved occupied cell: one return's, just above the occupied threshold.
pub const PRIOR_OCCUPIED_LOG_ODDS: f32 = HIT_LOG_ODDS;
/// The evidence of a saved free cell: three passes', just below the free threshold.
pub const PRIOR_FREE_LOG_ODDS: f32 = 3.0 * MISS_LOG_ODDS;

/// Cell fractions below this are rounding, not overlap: a saved cell whose edge lies on a
/// run cell's edge does not overlap it.
const EDGE_TOLERANCE: f64 = 1e-6;

/// Why a saved grid cannot be the prior of a run's grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PriorGridError {
    #[error("its grid is rotated (origin yaw {yaw} rad), which is not supported")]
    Rotated { yaw: f64 },
    #[error("its grid's resolution {resolution} m is outside {min} to {max} m")]
    Resolution { resolution: f64, min: f64, max: f64 },
    #[error(
        "its grid's origin ({x}, {y}) is not within {} m of the map frame's",
        saved_map::MAX_MAP_COORDINATE_M
    )]
    Origin { x: f64, y: f64 },
    #[error("its grid on cells of {resolution_m} m: {source}")]
    Size {
        resolution_m: f64,
        #[source]
        source: GridError,
    },
}

/// The saved grid `saved` as log-odds on the cells of a grid at `resolution_m` (a valid
/// resolution), covering every cell the saved one overlaps. `None` for an empty image.
pub fn prior_grid(
    saved: &GridMap,
    resolution_m: f64,
) -> Result<Option<OccupancyGrid>, PriorGridError> {
    let [ox, oy, yaw] = saved.yaml.origin;
    if yaw != 0.0 {
        return Err(PriorGridError::Rotated { yaw });
    }
    let saved_res = saved.yaml.resolution;
    if !RESOLUTION_RANGE_M.contains(&saved_res) {
        return Err(PriorGridError::Resolution {
            resolution: saved_res,
            min: *RESOLUTION_RANGE_M.start(),
            max: *RESOLUTION_RANGE_M.end(),
        });
    }
    // Beyond it, cell indices would overflow.
    let far = |v: f64| v.is_nan() || v.abs() > saved_map::MAX_MAP_COORDINATE_M;
    if far(ox) || far(oy) {
        return Err(PriorGridError::Origin { x: ox, y: oy });
    }
    if saved.width == 0 || saved.height == 0 {
        return Ok(None);
    }
    let too_large = |width, height| PriorGridError::Size {
        resolution_m,
        source: GridError::TooLarge { width, height },
    };
    // The run's cells (global indices) that each saved column or row overlaps, one axis.
    let axis = |origin: f64, cells: usize| {
        let first = (origin / resolution_m + EDGE_TOLERANCE).floor() as i64;
        let end = origin + cells as f64 * saved_res;
        let last = (end / resolution_m - EDGE_TOLERANCE).ceil() as i64 - 1;
        // The saved cells each run cell overlaps, clamped to the image.
        let spans: Vec<(usize, usize)> = (first..=last)
            .map(|index| {
                let from = (index as f64 * resolution_m - origin) / saved_res;
                let to = ((index + 1) as f64 * resolution_m - origin) / saved_res;
                let lo = ((from + EDGE_TOLERANCE).floor().max(0.0) as usize).min(cells - 1);
                let hi = ((to - EDGE_TOLERANCE).ceil().max(0.0) as usize).clamp(lo + 1, cells);
                (lo, hi)
            })
            .collect();
        (first, spans)
    };
    let (first_col, columns) = axis(ox, saved.width);
    let (first_row, rows) = axis(oy, saved.height);
    let (width, height) = (columns.len(), rows.len());
    if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
        return Err(too_large(width, height));
    }
    let mut log_odds = Vec::new();
    log_odds
        .try_reserve_exact(width * height)
        .map_err(|_| too_large(width, height))?;
    for &(row_lo, row_hi) in &rows {
        for &(col_lo, col_hi) in &columns {
            let mut state = CellState::Unknown;
            'overlap: for row in row_lo..row_hi {
                for col in col_lo..col_hi {
                    match saved.state(col, row) {
                        CellState::Occupied => {
                            state = CellState::Occupied;
                            break 'overlap;
                        }
                        CellState::Free => state = CellState::Free,
                        CellState::Unknown => {}
                    }
                }
            }
            log_odds.push(match state {
                CellState::Occupied => PRIOR_OCCUPIED_LOG_ODDS,
                CellState::Free => PRIOR_FREE_LOG_ODDS,
                CellState::Unknown => 0.0,
            });
        }
    }
    OccupancyGrid::from_log_odds(resolution_m, [first_col, first_row], width, log_odds)
        .map(Some)
        .map_err(|source| PriorGridError::Size {
            resolution_m,
            source,
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use back_end::compact_scan::CompactScan;
    use back_end::occupancy_grid::GridConfig;
    use saved_map::MapYaml;
    use slam_geom::Pose2;

    /// A saved grid of cells of `resolution` whose lower-left corner is at `origin`, from
    /// rows listed from the lowest y: `#` occupied, `.` free, anything else unknown.
    fn saved(resolution: f64, origin: [f64; 2], rows: &[&str]) -> GridMap {
        let width = rows[0].len();
        let cells = rows
            .iter()
            .flat_map(|row| {
                row.chars().map(|c| match c {
                    '#' => CellState::Occupied,
                    '.' => CellState::Free,
                    _ => CellState::Unknown,
                })
            })
            .collect();
        GridMap {
            yaml: MapYaml::trinary("map.pgm", resolution, origin),
            width,
            height: rows.len(),
            cells,
        }
    }

    /// The state of the cell holding the world point `(x, y)`.
    fn state_at(grid: &OccupancyGrid, x: f64, y: f64) -> CellState {
        let res = grid.resolution_m();
        let [x0, y0] = grid.origin();
        let col = ((x - x0) / res).floor();
        let row = ((y - y0) / res).floor();
        assert!(
            col >= 0.0 && row >= 0.0,
            "({x}, {y}) is outside the grid at ({x0}, {y0})"
        );
        let (col, row) = (col as usize, row as usize);
        assert!(col < grid.width() && row < grid.height(), "({x}, {y})");
        grid.state(col, row)
    }

    fn rows_of(grid: &OccupancyGrid) -> Vec<String> {
        (0..grid.height())
            .map(|row| {
                (0..grid.width())
                    .map(|col| match grid.state(col, row) {
                        CellState::Occupied => '#',
                        CellState::Free => '.',
                        CellState::Unknown => '?',
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn a_grid_saved_at_the_run_s_resolution_is_laid_on_cell_for_cell() {
        let map = saved(0.1, [-0.3, 0.2], &["#..?", "##.?"]);
        let prior = prior_grid(&map, 0.1).expect("a valid grid").expect("cells");
        assert_eq!(prior.min_index(), [-3, 2]);
        assert_eq!((prior.width(), prior.height()), (4, 2));
        assert_eq!(rows_of(&prior), ["#..?", "##.?"]);
        // Each state just past its threshold: the weakest evidence that still says it.
        assert_eq!(
            prior.probability(0, 0),
            1.0 - 1.0 / (1.0 + f64::from(PRIOR_OCCUPIED_LOG_ODDS).exp())
        );
    }

    #[test]
    fn another_resolution_or_origin_is_resampled_keeping_thin_walls() {
        // A wall one 5 cm cell thick, on a grid whose origin is off the 10 cm multiples.
        let map = saved(
            0.05,
            [0.025, 0.0],
            &["..#...", "..#...", "......", "......"],
        );
        let prior = prior_grid(&map, 0.1).expect("a valid grid").expect("cells");
        // x from 0.025 to 0.325: the cells of 0.0 to 0.4; y from 0 to 0.2: two rows.
        assert_eq!(prior.min_index(), [0, 0]);
        assert_eq!(rows_of(&prior), [".#..", "...."]);
        // Finer than saved: each saved cell becomes four.
        let fine = prior_grid(&map, 0.025)
            .expect("a valid grid")
            .expect("cells");
        assert_eq!(fine.min_index(), [1, 0]);
        assert_eq!(fine.width(), 12);
        assert_eq!(state_at(&fine, 0.15, 0.01), CellState::Occupied);
        assert_eq!(state_at(&fine, 0.11, 0.01), CellState::Free);
    }

    #[test]
    fn a_rotated_grid_is_refused() {
        let mut map = saved(0.1, [0.0, 0.0], &["#"]);
        map.yaml.origin[2] = 0.3;
        let error = prior_grid(&map, 0.1).expect_err("rotated");
        assert_eq!(error, PriorGridError::Rotated { yaw: 0.3 });
        assert!(error.to_string().contains("rotated"), "{error}");
    }

    /// A sensor at (0.02, 0.02) facing +x, its beams ending on a wall 1 m ahead.
    fn wall_scan() -> CompactScan {
        let ranges = vec![1.0_f32; 41];
        CompactScan::new(-0.2, 0.01, 0.1, 30.0, &ranges, 0.0, 5.0)
    }

    /// The grid of the saved `map` with `wall_scan` seen `times` times added.
    fn merged(map: &GridMap, times: usize) -> OccupancyGrid {
        let config = GridConfig {
            resolution_m: 0.1,
            ..GridConfig::default()
        };
        let prior = prior_grid(map, 0.1).expect("valid").expect("cells");
        let scan = wall_scan();
        let scans: Vec<(Pose2, &CompactScan)> = (0..times)
            .map(|_| (Pose2::new(0.02, 0.02, 0.0), &scan))
            .collect();
        OccupancyGrid::build_on(&config, Some(&prior), &scans)
            .expect("fits")
            .expect("cells")
    }

    #[test]
    fn the_merged_grid_covers_both_and_keeps_what_the_run_did_not_see() {
        // Saved: a room to the west of the new run's view, two cells of wall and free floor.
        let map = saved(0.1, [-3.0, -1.0], &["#..", "#.?"]);
        let grid = merged(&map, 3);
        // From the saved corner to the new wall's cell at x = 1.0 m and the beams' spread.
        assert_eq!(grid.min_index()[0], -30);
        assert!(grid.min_index()[1] <= -10);
        assert_eq!(state_at(&grid, -2.95, -0.95), CellState::Occupied);
        assert_eq!(state_at(&grid, -2.85, -0.85), CellState::Free);
        assert_eq!(state_at(&grid, -2.75, -0.85), CellState::Unknown);
        // And what the run saw.
        assert_eq!(state_at(&grid, 1.05, 0.02), CellState::Occupied);
        assert_eq!(state_at(&grid, 0.55, 0.02), CellState::Free);
        // Far from both: never seen.
        assert_eq!(state_at(&grid, -1.0, 0.1), CellState::Unknown);
    }

    #[test]
    fn a_few_new_passes_outweigh_the_saved_state() {
        // Saved: a wall at x = 0.5 m that is gone (the beams pass it), free floor at x = 1 m
        // where a wall stands now.
        let map = saved(0.1, [0.0, 0.0], &[".....#....."]);
        let at = |grid: &OccupancyGrid| (state_at(grid, 0.55, 0.05), state_at(grid, 1.05, 0.05));
        assert_eq!(at(&merged(&map, 0)), (CellState::Occupied, CellState::Free));
        // One pass: the saved floor is in doubt; a wall is lowered less by a pass than floor
        // is, and still stands.
        assert_eq!(
            at(&merged(&map, 1)),
            (CellState::Occupied, CellState::Unknown)
        );
        // Three: the new wall is there; the old one is in doubt.
        assert_eq!(
            at(&merged(&map, 3)),
            (CellState::Unknown, CellState::Occupied)
        );
        // Eleven: still in doubt; twelve: the old wall is free floor.
        assert_eq!(
            at(&merged(&map, 11)),
            (CellState::Unknown, CellState::Occupied)
        );
        assert_eq!(
            at(&merged(&map, 12)),
            (CellState::Free, CellState::Occupied)
        );
    }
}
