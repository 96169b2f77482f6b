//! The log-odds occupancy grid, traced from the scans and the poses they were taken at.
//!
//! Each beam lowers the cells it passes through and raises the cell it ends in (a return);
//! a beam without a return lowers the cells up to [`GridConfig::no_return_reach_m`]. Within
//! one scan a cell changes at most once and a return wins over a pass: near the sensor many
//! beams of one scan cross the same cell, and counting each would let one scan outvote the
//! many that saw a wall there, and a beam grazing a wall would erase the cell its neighbour
//! hit.
//!
//! A pass lowers a cell that returns have made likelier occupied than not by much less than
//! it lowers one they have not ([`SURFACE_MISS_LOG_ODDS`], [`MISS_LOG_ODDS`]). A wall seen
//! along a corridor is met at a shallow angle by the beams that end farther down it, and
//! each of them crosses the wall's cells nearer the sensor on its way (a beam meeting a wall
//! at 10 degrees runs through its 5 cm cells for its last 0.3 m). Weighed as free space is,
//! those passes erase what the returns drew: on a real log corridors lose stretches of their
//! walls and the walls' ends move, and the scans that saw them no longer fit the map they
//! drew. So a cell that returns hit stays occupied while about one beam in ten that reaches
//! it ends there (Karto's occupancy threshold is one in ten, GMapping's one in four), and a
//! cell no return hit is still free after three passes.

use crate::compact_scan::{Beam, CompactScan};
use slam_geom::Pose2;

/// Log-odds added by a return: `ln(0.7 / 0.3)`, a hit makes a cell 70 % likely occupied.
pub const HIT_LOG_ODDS: f32 = 0.847;
/// Log-odds added by a pass through a cell that returns have not made likelier occupied
/// than not: `ln(0.4 / 0.6)`, so that free space is free after three passes.
pub const MISS_LOG_ODDS: f32 = -0.405;
/// Log-odds added by a pass through a cell that returns have made likelier occupied than
/// not: `ln(0.475 / 0.525)`. A surface the beams graze, a thin wall, a chair's leg, a
/// glass pane is missed by most of the beams that reach it; it stays occupied while about
/// one in ten ends there, and an object that is gone (a door opened) is cleared by a few
/// dozen passes.
pub const SURFACE_MISS_LOG_ODDS: f32 = -0.1;
/// Clamps: a cell never becomes so certain that a changed world (a door opened, a person who
/// stood still) could not be corrected by a few dozen later scans.
pub const MIN_LOG_ODDS: f32 = -2.0;
pub const MAX_LOG_ODDS: f32 = 3.5;
/// A cell is occupied above this probability and free below [`FREE_PROBABILITY`]; in
/// between, or never seen, unknown. These are the thresholds of the map_server
/// convention the grid is written in (see `map_yaml`).
pub const OCCUPIED_PROBABILITY: f64 = 0.65;
pub const FREE_PROBABILITY: f64 = 0.25;
/// [`OCCUPIED_PROBABILITY`] as log-odds, `ln(0.65 / 0.35)`: thresholding needs no `exp`.
const OCCUPIED_THRESHOLD_LOG_ODDS: f32 = 0.619_039_2;
/// [`FREE_PROBABILITY`] as log-odds, `ln(0.25 / 0.75)`.
const FREE_THRESHOLD_LOG_ODDS: f32 = -1.098_612_3;

/// A cell of these log-odds thresholded: occupied above [`OCCUPIED_PROBABILITY`], free
/// below [`FREE_PROBABILITY`], unknown in between.
pub fn state_of(log_odds: f32) -> CellState {
    if log_odds > OCCUPIED_THRESHOLD_LOG_ODDS {
        CellState::Occupied
    } else if log_odds < FREE_THRESHOLD_LOG_ODDS {
        CellState::Free
    } else {
        CellState::Unknown
    }
}

/// More cells than this are refused: at 8 bytes a cell (log-odds and a per-scan mark) this
/// is 800 MB; such an area wants a coarser resolution.
pub const MAX_CELLS: usize = 100_000_000;

/// How the grid is built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridConfig {
    /// Edge of a cell, metres.
    pub resolution_m: f64,
    /// How far a beam without a return clears free space, metres. Short, because nothing says
    /// how far the free space went: Cartographer's `missing_data_ray_length` is 5 m too.
    pub no_return_reach_m: f64,
}

/// The finest and coarsest resolutions accepted, metres: finer than 5 mm is below any
/// scanner's noise, coarser than 5 m is no map of a building.
pub const RESOLUTION_RANGE_M: std::ops::RangeInclusive<f64> = 0.005..=5.0;

impl GridConfig {
    /// Refuses a resolution outside [`RESOLUTION_RANGE_M`] or a reach that is not a positive
    /// number of metres, saying which.
    pub fn validate(&self) -> Result<(), String> {
        let resolution = self.resolution_m;
        if !RESOLUTION_RANGE_M.contains(&resolution) {
            return Err(format!(
                "the grid resolution must be from {} to {} m, not {resolution}",
                RESOLUTION_RANGE_M.start(),
                RESOLUTION_RANGE_M.end()
            ));
        }
        let reach = self.no_return_reach_m;
        if !(reach.is_finite() && reach > 0.0) {
            return Err(format!(
                "the reach of beams without a return must be a positive number of metres, not {reach}"
            ));
        }
        Ok(())
    }
}

impl Default for GridConfig {
    fn default() -> Self {
        Self {
            resolution_m: 0.05,
            no_return_reach_m: 5.0,
        }
    }
}

/// What a cell is, thresholded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellState {
    Free,
    Occupied,
    Unknown,
}

/// The map image's pixel of an occupied cell (map_server's trinary convention, `map.pgm`).
pub const OCCUPIED_PIXEL: u8 = 0;
/// The pixel of a free cell.
pub const FREE_PIXEL: u8 = 254;
/// The pixel of a cell never seen, or seen too little to say.
pub const UNKNOWN_PIXEL: u8 = 205;

/// The trinary pixel of a cell.
pub fn trinary_pixel(state: CellState) -> u8 {
    match state {
        CellState::Occupied => OCCUPIED_PIXEL,
        CellState::Free => FREE_PIXEL,
        CellState::Unknown => UNKNOWN_PIXEL,
    }
}

/// A cell known to be free or occupied, by its global index: it covers
/// `[index * resolution, (index + 1) * resolution)` in x and y.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GridCell {
    pub index: [i64; 2],
    pub occupied: bool,
}

/// Why a grid could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GridError {
    #[error(
        "the occupancy grid would be {width} x {height} cells, more than {MAX_CELLS}; \
         choose a coarser resolution"
    )]
    TooLarge { width: usize, height: usize },
}

/// A dense grid of log-odds over the cells that any pose or beam reached. Cell `(col, row)`
/// covers `[(min_index.x + col) * res, ... + res)` in x and likewise in y, so row 0 is the
/// lowest y; cells line up with multiples of the resolution, whatever the data.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    resolution_m: f64,
    min_index: [i64; 2],
    width: usize,
    height: usize,
    log_odds: Vec<f32>,
}

impl OccupancyGrid {
    /// Traces every scan from its pose (the sensor sits at the robot's origin). `None` when
    /// no scan has a beam to trace.
    pub fn build(
        config: &GridConfig,
        scans: &[(Pose2, &CompactScan)],
    ) -> Result<Option<Self>, GridError> {
        Self::build_on(config, None, scans)
    }

    /// [`build`](Self::build) on top of `prior` (a saved map's grid as evidence, made by
    /// [`crate::prior_grid`] at `config`'s resolution, which is why only the crate calls
    /// this): the grid covers both, starts from the prior's log-odds and adds the scans'
    /// hits and passes to them. `None` when there is neither a prior nor a scan with a beam
    /// to trace.
    pub fn build_on(
        config: &GridConfig,
        prior: Option<&OccupancyGrid>,
        scans: &[(Pose2, &CompactScan)],
    ) -> Result<Option<Self>, GridError> {
        let res = config.resolution_m;
        let ends = |pose: &Pose2, scan| beam_ends(*pose, scan, config.no_return_reach_m);
        let cell = |p: [f64; 2]| [(p[0] / res).floor() as i64, (p[1] / res).floor() as i64];
        let finite = |p: [f64; 2]| p[0].is_finite() && p[1].is_finite();

        let mut min = [i64::MAX; 2];
        let mut max = [i64::MIN; 2];
        let mut include = |c: [i64; 2]| {
            for a in 0..2 {
                min[a] = min[a].min(c[a]);
                max[a] = max[a].max(c[a]);
            }
        };
        if let Some(prior) = prior {
            let [x, y] = prior.min_index;
            include([x, y]);
            include([x + prior.width as i64 - 1, y + prior.height as i64 - 1]);
        }
        for (pose, scan) in scans {
            if scan.is_empty() || !finite(pose.position().into()) || !pose.yaw.is_finite() {
                continue;
            }
            include(cell(pose.position().into()));
            for (end, _) in ends(pose, scan) {
                include(cell(end));
            }
        }
        if min[0] > max[0] {
            return Ok(None);
        }
        let span =
            |a: usize| usize::try_from(max[a].saturating_sub(min[a])).map(|s| s.saturating_add(1));
        let (width, height) = match (span(0), span(1)) {
            (Ok(w), Ok(h)) if w.checked_mul(h).is_some_and(|n| n <= MAX_CELLS) => (w, h),
            (w, h) => {
                return Err(GridError::TooLarge {
                    width: w.unwrap_or(usize::MAX),
                    height: h.unwrap_or(usize::MAX),
                });
            }
        };
        let mut grid = Self {
            resolution_m: res,
            min_index: min,
            width,
            height,
            log_odds: vec![0.0; width * height],
        };
        if let Some(prior) = prior {
            for row in 0..prior.height {
                let from = row * prior.width;
                let to = grid.offset([prior.min_index[0], prior.min_index[1] + row as i64]);
                grid.log_odds[to..to + prior.width]
                    .copy_from_slice(&prior.log_odds[from..from + prior.width]);
            }
        }
        // The scan that last changed each cell (its number + 1), so a scan changes it once.
        let mut mark = vec![0_u32; width * height];
        for (number, (pose, scan)) in scans.iter().enumerate() {
            if scan.is_empty() || !finite(pose.position().into()) || !pose.yaw.is_finite() {
                continue;
            }
            let id = number as u32 + 1;
            for (end, beam) in ends(pose, scan) {
                if matches!(beam, Beam::Hit(_)) {
                    let i = grid.offset(cell(end));
                    if mark[i] != id {
                        mark[i] = id;
                        grid.add(i, HIT_LOG_ODDS);
                    }
                }
            }
            let from = grid.local(pose.position().into());
            for (end, beam) in ends(pose, scan) {
                let include_end = beam == Beam::NoReturn;
                trace(from, grid.local(end), include_end, |col, row| {
                    let i = row * width + col;
                    if mark[i] != id {
                        mark[i] = id;
                        grid.pass(i);
                    }
                });
            }
        }
        Ok(Some(grid))
    }

    /// A grid of the given log-odds, row by row from the lowest y, whose cell `(0, 0)` is
    /// the global cell `min_index`. Refused past the size [`build`](Self::build) refuses.
    pub fn from_log_odds(
        resolution_m: f64,
        min_index: [i64; 2],
        width: usize,
        log_odds: Vec<f32>,
    ) -> Result<Self, GridError> {
        let height = log_odds.len().checked_div(width).unwrap_or(0);
        if log_odds.len() > MAX_CELLS {
            return Err(GridError::TooLarge { width, height });
        }
        Ok(Self {
            resolution_m,
            min_index,
            width,
            height,
            log_odds,
        })
    }

    /// A grid of trinary pixels ([`OCCUPIED_PIXEL`], [`FREE_PIXEL`], anything else unknown),
    /// row by row from the lowest y, cell `(0, 0)`'s lower-left corner at `origin`: each
    /// known cell as certain as a cell can be, so that laid over another grid
    /// ([`crate::global_grid`]) it decides where it knows.
    pub fn from_pixels(
        resolution_m: f64,
        origin: [f64; 2],
        width: usize,
        pixels: &[u8],
    ) -> Result<Self, GridError> {
        let log_odds = pixels
            .iter()
            .map(|&pixel| match pixel {
                OCCUPIED_PIXEL => MAX_LOG_ODDS,
                FREE_PIXEL => MIN_LOG_ODDS,
                _ => 0.0,
            })
            .collect();
        let min_index = origin.map(|o| (o / resolution_m).round() as i64);
        Self::from_log_odds(resolution_m, min_index, width, log_odds)
    }

    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Columns (x).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows (y).
    pub fn height(&self) -> usize {
        self.height
    }

    /// The world position of the lower-left corner of cell `(0, 0)`, metres.
    pub fn origin(&self) -> [f64; 2] {
        [
            self.min_index[0] as f64 * self.resolution_m,
            self.min_index[1] as f64 * self.resolution_m,
        ]
    }

    /// The global index of cell `(0, 0)`: cell `(col, row)` is `min_index + (col, row)`.
    pub fn min_index(&self) -> [i64; 2] {
        self.min_index
    }

    /// The log-odds of cell `(col, row)` (0 for a cell never seen).
    pub fn log_odds(&self, col: usize, row: usize) -> f32 {
        self.log_odds[row * self.width + col]
    }

    /// The probability that cell `(col, row)` is occupied (0.5 for a cell never seen).
    pub fn probability(&self, col: usize, row: usize) -> f64 {
        let l = f64::from(self.log_odds(col, row));
        1.0 - 1.0 / (1.0 + l.exp())
    }

    /// The cell thresholded.
    pub fn state(&self, col: usize, row: usize) -> CellState {
        state_of(self.log_odds(col, row))
    }

    /// The free and occupied cells, row by row from the lowest y (unknown ones left out).
    pub fn known_cells(&self) -> Vec<GridCell> {
        let mut cells = Vec::new();
        for row in 0..self.height {
            for col in 0..self.width {
                let occupied = match self.state(col, row) {
                    CellState::Occupied => true,
                    CellState::Free => false,
                    CellState::Unknown => continue,
                };
                cells.push(GridCell {
                    index: [
                        self.min_index[0] + col as i64,
                        self.min_index[1] + row as i64,
                    ],
                    occupied,
                });
            }
        }
        cells
    }

    /// Every cell's trinary pixel, row by row from the lowest y.
    pub fn pixels(&self) -> Vec<u8> {
        (0..self.height)
            .flat_map(|row| (0..self.width).map(move |col| trinary_pixel(self.state(col, row))))
            .collect()
    }

    /// Bytes the grid holds; building it took twice as many (the per-scan marks).
    pub fn bytes(&self) -> usize {
        self.log_odds.capacity() * std::mem::size_of::<f32>()
    }

    fn add(&mut self, i: usize, delta: f32) {
        let l = &mut self.log_odds[i];
        *l = (*l + delta).clamp(MIN_LOG_ODDS, MAX_LOG_ODDS);
    }

    /// A beam passed through cell `i`.
    fn pass(&mut self, i: usize) {
        let miss = if self.log_odds[i] > 0.0 {
            SURFACE_MISS_LOG_ODDS
        } else {
            MISS_LOG_ODDS
        };
        self.add(i, miss);
    }

    /// The offset of a global cell index inside the grid (which covers every cell `build`
    /// reaches).
    fn offset(&self, index: [i64; 2]) -> usize {
        let col = (index[0] - self.min_index[0]) as usize;
        let row = (index[1] - self.min_index[1]) as usize;
        row * self.width + col
    }

    /// A world point in cell units relative to the grid's corner.
    fn local(&self, p: [f64; 2]) -> [f64; 2] {
        [
            p[0] / self.resolution_m - self.min_index[0] as f64,
            p[1] / self.resolution_m - self.min_index[1] as f64,
        ]
    }
}

/// Where each beam of `scan` taken at `pose` ends (a no-return's at `no_return_reach_m`),
/// in the map frame, with what it saw.
fn beam_ends(
    pose: Pose2,
    scan: &CompactScan,
    no_return_reach_m: f64,
) -> impl Iterator<Item = ([f64; 2], Beam)> + '_ {
    scan.beams().map(move |(bearing, beam)| {
        let reach = match beam {
            Beam::Hit(r) => r,
            Beam::NoReturn => no_return_reach_m,
        };
        let (s, c) = (pose.yaw + bearing).sin_cos();
        ([pose.x + reach * c, pose.y + reach * s], beam)
    })
}

/// Visits the cells a segment crosses from `a` to `b` (cell units, both inside the grid), in
/// order (Amanatides-Woo), the last one only if `include_end`. It takes exactly as many steps
/// as the two end cells are apart (in x plus in y), so rounding can never walk it past the
/// end cell or off the grid.
fn trace(a: [f64; 2], b: [f64; 2], include_end: bool, mut visit: impl FnMut(usize, usize)) {
    let start = [a[0].floor() as i64, a[1].floor() as i64];
    let end = [b[0].floor() as i64, b[1].floor() as i64];
    let d = [b[0] - a[0], b[1] - a[1]];
    let mut step = [0_i64; 2];
    let mut t_max = [f64::INFINITY; 2];
    let mut t_delta = [f64::INFINITY; 2];
    for k in 0..2 {
        if d[k] > 0.0 {
            step[k] = 1;
            t_delta[k] = 1.0 / d[k];
            t_max[k] = (start[k] as f64 + 1.0 - a[k]) / d[k];
        } else if d[k] < 0.0 {
            step[k] = -1;
            t_delta[k] = -1.0 / d[k];
            t_max[k] = (a[k] - start[k] as f64) / -d[k];
        }
    }
    let mut c = start;
    loop {
        if c == end {
            if include_end {
                visit(c[0] as usize, c[1] as usize);
            }
            return;
        }
        visit(c[0] as usize, c[1] as usize);
        let k = if c[1] == end[1] || (c[0] != end[0] && t_max[0] < t_max[1]) {
            0
        } else {
            1
        };
        c[k] += step[k];
        t_max[k] += t_delta[k];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn traced(a: [f64; 2], b: [f64; 2], include_end: bool) -> Vec<(usize, usize)> {
        let mut cells = Vec::new();
        trace(a, b, include_end, |c, r| cells.push((c, r)));
        cells
    }

    #[test]
    fn the_thresholds_in_log_odds_are_the_probabilities() {
        let log_odds = |p: f64| (p / (1.0 - p)).ln() as f32;
        assert!((OCCUPIED_THRESHOLD_LOG_ODDS - log_odds(OCCUPIED_PROBABILITY)).abs() < 1e-6);
        assert!((FREE_THRESHOLD_LOG_ODDS - log_odds(FREE_PROBABILITY)).abs() < 1e-6);
        assert_eq!(state_of(0.62), CellState::Occupied);
        assert_eq!(state_of(0.61), CellState::Unknown);
        assert_eq!(state_of(-1.09), CellState::Unknown);
        assert_eq!(state_of(-1.1), CellState::Free);
    }

    #[test]
    fn a_grids_pixels_are_its_cells_thresholded_row_by_row_from_the_lowest_y() {
        let ranges: Vec<f32> = (0..91).map(|i| 1.0 + 0.02 * i as f32).collect();
        let scan = CompactScan::new(-1.2, 2.4 / 90.0, 0.1, 30.0, &ranges, 0.0, 5.0);
        let pose = Pose2::new(0.4, 0.1, 0.3);
        let grid = OccupancyGrid::build(&GridConfig::default(), &[(pose, &scan); 3])
            .unwrap()
            .unwrap();
        let pixels = grid.pixels();
        assert!(pixels.contains(&OCCUPIED_PIXEL) && pixels.contains(&FREE_PIXEL));
        assert_eq!(pixels.len(), grid.width() * grid.height());
        for row in 0..grid.height() {
            for col in 0..grid.width() {
                let pixel = pixels[row * grid.width() + col];
                assert_eq!(pixel, trinary_pixel(grid.state(col, row)), "{col} {row}");
            }
        }
        // Read back from its pixels, the grid is the same, cell for cell and in place.
        let read =
            OccupancyGrid::from_pixels(grid.resolution_m(), grid.origin(), grid.width(), &pixels)
                .unwrap();
        assert_eq!(read.min_index(), grid.min_index());
        assert_eq!(read.pixels(), pixels);
    }

    #[test]
    fn a_trace_walks_every_crossed_cell_to_the_end() {
        assert_eq!(
            traced([0.5, 0.5], [3.5, 0.5], false),
            [(0, 0), (1, 0), (2, 0)]
        );
        assert_eq!(
            traced([3.5, 0.5], [0.5, 0.5], true),
            [(3, 0), (2, 0), (1, 0), (0, 0)]
        );
        // A diagonal through cell corners still moves one cell at a time and stops at the end.
        let cells = traced([0.5, 0.5], [3.5, 2.5], true);
        assert_eq!(cells.first(), Some(&(0, 0)));
        assert_eq!(cells.last(), Some(&(3, 2)));
        assert_eq!(cells.len(), 6);
        for w in cells.windows(2) {
            let dx = w[1].0.abs_diff(w[0].0);
            let dy = w[1].1.abs_diff(w[0].1);
            assert_eq!(dx + dy, 1, "{cells:?}");
        }
        assert_eq!(traced([1.2, 1.7], [1.9, 1.1], false), []);
    }

    /// The grid, in cells of 0.1 m, of `scan` seen `times` times from `pose`, no returns
    /// clearing up to `no_return_reach_m`.
    fn grid_of_repeated(
        scan: &CompactScan,
        pose: Pose2,
        times: usize,
        no_return_reach_m: f64,
    ) -> Result<OccupancyGrid, GridError> {
        let scans: Vec<(Pose2, &CompactScan)> = (0..times).map(|_| (pose, scan)).collect();
        let config = GridConfig {
            resolution_m: 0.1,
            no_return_reach_m,
        };
        let grid = OccupancyGrid::build(&config, &scans)?;
        Ok(grid.expect("a grid of a few cells"))
    }

    #[test]
    fn a_wall_seen_from_a_room_is_occupied_behind_free_space() -> Result<(), GridError> {
        // A sensor at the origin looking at a wall 1 m ahead, over and over.
        let ranges = vec![1.0_f32; 41];
        let scan = CompactScan::new(-0.2, 0.01, 0.1, 30.0, &ranges, 0.0, 5.0);
        let reach = GridConfig::default().no_return_reach_m;
        let grid = grid_of_repeated(&scan, Pose2::new(0.02, 0.02, 0.0), 10, reach)?;
        let [x0, y0] = grid.origin();
        let at = |x: f64, y: f64| {
            let col = ((x - x0) / 0.1).floor() as usize;
            let row = ((y - y0) / 0.1).floor() as usize;
            grid.state(col, row)
        };
        assert_eq!(at(1.05, 0.02), CellState::Occupied);
        assert_eq!(at(0.5, 0.02), CellState::Free);
        assert_eq!(at(0.05, 0.05), CellState::Free);
        assert_eq!(at(0.05, 0.25), CellState::Unknown, "outside the beams");
        // The grid is aligned to multiples of the resolution.
        assert_eq!(grid.origin(), [0.0, -0.2]);
        Ok(())
    }

    #[test]
    fn a_wall_that_beams_pass_stays_until_they_outnumber_its_returns_many_times()
    -> Result<(), GridError> {
        // One beam straight ahead from the origin: a return from a wall 1 m away, or a beam
        // that passes the wall's cell to end 2 m away (a beam grazing the wall, or one after
        // the wall is gone).
        let beam = |range: f32| CompactScan::new(0.0, 0.01, 0.1, 30.0, &[range], 0.0, 5.0);
        let (wall, beyond) = (beam(1.02), beam(2.02));
        let sensor = Pose2::new(0.01, 0.01, 0.0);
        let grid_after = |returns: usize, passes: usize| {
            let scans: Vec<(Pose2, &CompactScan)> = std::iter::repeat_n(&wall, returns)
                .chain(std::iter::repeat_n(&beyond, passes))
                .map(|scan| (sensor, scan))
                .collect();
            let config = GridConfig {
                resolution_m: 0.1,
                ..GridConfig::default()
            };
            OccupancyGrid::build(&config, &scans).map(|grid| grid.expect("a grid of a few cells"))
        };
        // The wall's cell is the 11th along the beam; the 6th is only ever passed.
        let (wall_cell, free_cell) = ((10, 0), (5, 0));
        let state = |grid: &OccupancyGrid, (col, row)| grid.state(col, row);

        // Three returns, then ten beams that pass: still a wall (at the weight free space is
        // cleared with, two passes undo a return and the wall would be gone).
        let grid = grid_after(3, 10)?;
        assert_eq!(state(&grid, wall_cell), CellState::Occupied);
        // Free space still clears after three passes.
        assert_eq!(state(&grid_after(0, 3)?, free_cell), CellState::Free);
        assert_eq!(state(&grid, free_cell), CellState::Free);
        // A wall that is gone (a door opened) is cleared by a few dozen passes.
        assert_eq!(state(&grid_after(3, 40)?, wall_cell), CellState::Free);
        Ok(())
    }

    #[test]
    fn no_returns_clear_up_to_their_reach_and_mark_nothing_occupied() -> Result<(), GridError> {
        let ranges = vec![f32::INFINITY; 3];
        let scan = CompactScan::new(-0.01, 0.01, 0.1, 30.0, &ranges, 0.0, 2.0);
        let grid = grid_of_repeated(&scan, Pose2::new(0.05, 0.05, 0.0), 5, 2.0)?;
        assert_eq!((grid.width(), grid.height()), (21, 1));
        let states: Vec<CellState> = (0..grid.width()).map(|c| grid.state(c, 0)).collect();
        assert!(states.iter().all(|&s| s == CellState::Free), "{states:?}");
        Ok(())
    }

    #[test]
    fn an_absurd_extent_is_refused() {
        let scan = CompactScan::new(0.0, 0.01, 0.1, 300.0, &[100.0], 0.0, 5.0);
        let scans = [
            (Pose2::new(0.0, 0.0, 0.0), &scan),
            (Pose2::new(1e6, 1e6, 0.0), &scan),
        ];
        assert!(matches!(
            OccupancyGrid::build(&GridConfig::default(), &scans),
            Err(GridError::TooLarge { .. })
        ));
    }
}
