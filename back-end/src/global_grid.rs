//! The run's occupancy grid: every submap's log-odds laid out at its solved pose and
//! added. Each scan belongs to one submap, so a cell's sum is the evidence of every scan
//! that saw it, as a trace of the whole path would weigh it (less what each submap's clamp
//! capped); a submap that the graph moved carries its walls with it. The sum is clamped as
//! the tracer clamps and thresholded as every grid is.
//!
//! The tracer weighs a pass through a cell that returns made likelier occupied as a
//! surface's ([`SURFACE_MISS_LOG_ODDS`]), but a submap knows only its own returns: one that
//! saw a wall only from along it, its beams grazing the wall's cells on their way further,
//! holds those cells as free as open floor. So where any layer says occupied, the layers
//! that say free count by the ratio of the two passes' weights: a wall stays a wall as it
//! does in one trace of every scan.
//!
//! Any grid that can say its log-odds at a point is a [`Layer`]: a saved map's grid laid
//! under a run's is added the same way.

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::occupancy_grid::{
    GridError, MAX_CELLS, MAX_LOG_ODDS, MIN_LOG_ODDS, MISS_LOG_ODDS, OccupancyGrid,
    SURFACE_MISS_LOG_ODDS,
};
use crate::submap_grid::SubmapGrid;

/// A grid of log-odds in a frame of its own.
pub trait Layer {
    /// Edge of a cell, metres.
    fn resolution(&self) -> f64;
    /// The stretches of cells it may know something of, row by row: the centre of each
    /// stretch's first cell (its frame) and how many cells run from there along +x.
    fn stretches(&self) -> Vec<(Vector2<f64>, usize)>;
    /// The log-odds at `out.len()` points (its frame) from `from` on by steps of `step`, 0
    /// where it knows nothing.
    fn sample_row(&self, from: Vector2<f64>, step: Vector2<f64>, out: &mut [f32]);
}

/// `v` rounded down, without the library call `f64::floor` is on a baseline x86-64 (this
/// runs for every cell of every layer).
pub(crate) fn floor(v: f64) -> i64 {
    let i = v as i64;
    i - i64::from((i as f64) > v)
}

impl Layer for SubmapGrid {
    fn resolution(&self) -> f64 {
        SubmapGrid::resolution(self)
    }

    fn stretches(&self) -> Vec<(Vector2<f64>, usize)> {
        SubmapGrid::stretches(self).collect()
    }

    fn sample_row(&self, from: Vector2<f64>, step: Vector2<f64>, out: &mut [f32]) {
        SubmapGrid::sample_row(self, from, step, out);
    }
}

impl Layer for OccupancyGrid {
    fn resolution(&self) -> f64 {
        self.resolution_m()
    }

    fn stretches(&self) -> Vec<(Vector2<f64>, usize)> {
        let [x, y] = self.origin();
        let res = self.resolution_m();
        (0..self.height())
            .map(|row| {
                let centre = Vector2::new(x + 0.5 * res, y + (row as f64 + 0.5) * res);
                (centre, self.width())
            })
            .collect()
    }

    fn sample_row(&self, from: Vector2<f64>, step: Vector2<f64>, out: &mut [f32]) {
        let [x0, y0] = self.origin();
        let res = self.resolution_m();
        let (x, y) = ((from.x - x0) / res, (from.y - y0) / res);
        let (dx, dy) = (step.x / res, step.y / res);
        for (k, value) in out.iter_mut().enumerate() {
            let k = k as f64;
            let (col, row) = (floor(x + k * dx), floor(y + k * dy));
            *value = match (usize::try_from(col), usize::try_from(row)) {
                (Ok(col), Ok(row)) if col < self.width() && row < self.height() => {
                    self.log_odds(col, row)
                }
                _ => 0.0,
            };
        }
    }
}

/// The world cells one layer may know, as a range of columns per world row from `lo_row`.
struct Footprint {
    lo_row: i64,
    cols: Vec<(i64, i64)>,
}

impl Footprint {
    /// Where `layer`'s stretches fall when laid at `pose` on cells of `resolution`: every
    /// world cell whose centre lies in one of their cells. A stretch is a rectangle one
    /// cell high, so each world row it reaches takes the span between the rectangle's
    /// edges at the row's centre line.
    fn of(layer: &dyn Layer, pose: &Pose2, resolution: f64) -> Self {
        let half = 0.5 * layer.resolution();
        let rectangles: Vec<[Vector2<f64>; 4]> = layer
            .stretches()
            .into_iter()
            .map(|(start, count)| {
                let end = start.x + (count as f64 - 1.0) * layer.resolution();
                [
                    (-half, -half),
                    (end - start.x + half, -half),
                    (end - start.x + half, half),
                    (-half, half),
                ]
                .map(|(dx, dy)| pose.transform(start + Vector2::new(dx, dy)))
            })
            .collect();
        let row_of = |y: f64| floor(y / resolution - 0.5);
        let ys = rectangles.iter().flatten().map(|c| c.y);
        let lo_row = ys.clone().map(row_of).min().unwrap_or(0);
        let hi_row = ys.map(|y| row_of(y) + 1).max().unwrap_or(-1);
        let rows = usize::try_from(hi_row - lo_row + 1).unwrap_or(0);
        let mut cols = vec![(i64::MAX, i64::MIN); rows];
        for corners in &rectangles {
            let (low, high) = corners
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), c| {
                    (l.min(c.y), h.max(c.y))
                });
            for row in row_of(low)..=row_of(high) + 1 {
                let centre_y = (row as f64 + 0.5) * resolution;
                let Some((x0, x1)) = span_at(corners, centre_y) else {
                    continue;
                };
                let first = -floor(-(x0 / resolution - 0.5));
                let last = floor(x1 / resolution - 0.5);
                if first <= last {
                    let range = &mut cols[(row - lo_row) as usize];
                    *range = (range.0.min(first), range.1.max(last));
                }
            }
        }
        Self { lo_row, cols }
    }

    /// The lowest and highest world cell, `None` for an empty layer.
    fn bounds(&self) -> Option<([i64; 2], [i64; 2])> {
        let known = self.cols.iter().filter(|c| c.0 <= c.1);
        let lo_col = known.clone().map(|c| c.0).min()?;
        let hi_col = known.map(|c| c.1).max()?;
        let hi_row = self.lo_row + self.cols.len() as i64 - 1;
        Some(([lo_col, self.lo_row], [hi_col, hi_row]))
    }
}

/// Where the line `y` crosses the convex polygon `corners`: the lowest and highest x.
fn span_at(corners: &[Vector2<f64>; 4], y: f64) -> Option<(f64, f64)> {
    let mut span: Option<(f64, f64)> = None;
    for (k, p) in corners.iter().enumerate() {
        let q = corners[(k + 1) % 4];
        if (p.y - y) * (q.y - y) > 0.0 || p.y == q.y {
            continue;
        }
        let x = p.x + (y - p.y) * (q.x - p.x) / (q.y - p.y);
        span = Some(span.map_or((x, x), |(l, h)| (l.min(x), h.max(x))));
    }
    span
}

/// Lays `layers` (each with its `world_from_layer`) out on a grid of `resolution` and adds
/// them: each world cell takes each layer's log-odds under its centre. `None` when none
/// knows a cell.
pub fn render(
    layers: &[(Pose2, &dyn Layer)],
    resolution: f64,
) -> Result<Option<OccupancyGrid>, GridError> {
    let footprints: Vec<Footprint> = layers
        .iter()
        .map(|(pose, layer)| Footprint::of(*layer, pose, resolution))
        .collect();
    let bounds: Vec<([i64; 2], [i64; 2])> =
        footprints.iter().filter_map(Footprint::bounds).collect();
    if bounds.is_empty() {
        return Ok(None);
    }
    let lo = [0, 1].map(|a| bounds.iter().map(|b| b.0[a]).min().unwrap_or(0));
    let hi = [0, 1].map(|a| bounds.iter().map(|b| b.1[a]).max().unwrap_or(0));
    let width = usize::try_from(hi[0] - lo[0] + 1).unwrap_or(usize::MAX);
    let height = usize::try_from(hi[1] - lo[1] + 1).unwrap_or(usize::MAX);
    if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
        return Err(GridError::TooLarge { width, height });
    }
    // Per world cell, the layers' evidence for occupied and for free, apart.
    let mut sum = vec![(0.0_f32, 0.0_f32); width * height];
    let mut samples = Vec::new();
    for ((pose, layer), footprint) in layers.iter().zip(&footprints) {
        let layer_from_world = pose.inverse();
        let step = layer_from_world.rotation() * Vector2::new(resolution, 0.0);
        for (k, &(x0, x1)) in footprint.cols.iter().enumerate() {
            if x0 > x1 {
                continue;
            }
            let y = footprint.lo_row + k as i64;
            let centre = Vector2::new(x0 as f64 + 0.5, y as f64 + 0.5) * resolution;
            samples.resize((x1 - x0 + 1) as usize, 0.0);
            layer.sample_row(layer_from_world.transform(centre), step, &mut samples);
            let first = (y - lo[1]) as usize * width + (x0 - lo[0]) as usize;
            for (cell, &l) in sum[first..first + samples.len()].iter_mut().zip(&samples) {
                if l > 0.0 {
                    cell.0 += l;
                } else {
                    cell.1 += l;
                }
            }
        }
    }
    let surface = SURFACE_MISS_LOG_ODDS / MISS_LOG_ODDS;
    let sum: Vec<f32> = sum
        .into_iter()
        .map(|(occupied, free)| match occupied > 0.0 {
            true => occupied + surface * free,
            false => free,
        })
        .collect();
    // The grid is cut to the cells some layer knows: a submap's box reaches as far as its
    // longest beam's end.
    let known = |i: usize| sum[i] != 0.0;
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
        .map(|i| sum[i].clamp(MIN_LOG_ODDS, MAX_LOG_ODDS))
        .collect();
    let min_index = [lo[0] + x0 as i64, lo[1] + y0 as i64];
    OccupancyGrid::from_log_odds(resolution, min_index, x1 - x0 + 1, log_odds).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compact_scan::CompactScan;
    use crate::occupancy_grid::{CellState, GridConfig};

    /// A scan of a wall 2 m ahead.
    fn wall_scan() -> CompactScan {
        let ranges: Vec<f32> = (0..91)
            .map(|i| {
                let bearing = -0.7 + 1.4 * f64::from(i) / 90.0;
                (2.0 / bearing.cos()) as f32
            })
            .collect();
        CompactScan::new(-0.7, 1.4 / 90.0, 0.1, 30.0, &ranges, 0.0, 5.0)
    }

    /// A submap of a wall 2 m ahead, seen from its origin three times (free space is free
    /// after three passes).
    fn wall_submap() -> SubmapGrid {
        let scan = wall_scan();
        SubmapGrid::trace(&GridConfig::default(), &[(Pose2::IDENTITY, &scan); 3])
            .unwrap()
            .unwrap()
    }

    fn state(grid: &OccupancyGrid, p: Vector2<f64>) -> CellState {
        let res = grid.resolution_m();
        let [x0, y0] = grid.origin();
        let col = ((p.x - x0) / res).floor();
        let row = ((p.y - y0) / res).floor();
        if col < 0.0 || row < 0.0 || col >= grid.width() as f64 || row >= grid.height() as f64 {
            return CellState::Unknown;
        }
        grid.state(col as usize, row as usize)
    }

    #[test]
    fn a_submap_moved_by_the_graph_moves_its_wall() {
        let submap = wall_submap();
        let at = Pose2::new(10.0, -3.0, std::f64::consts::FRAC_PI_2);
        let grid = render(&[(at, &submap as &dyn Layer)], 0.05)
            .unwrap()
            .unwrap();
        // The wall 2 m ahead of the submap's origin, which now faces +y.
        assert_eq!(
            state(&grid, Vector2::new(10.0, -1.0 + 0.01)),
            CellState::Occupied
        );
        assert_eq!(state(&grid, Vector2::new(10.0, -2.0)), CellState::Free);
        assert_eq!(render(&[], 0.05).unwrap().map(|g| g.width()), None);
    }

    #[test]
    fn submaps_laid_out_add_up_to_one_trace_of_all_their_scans() {
        let scan = wall_scan();
        let config = GridConfig::default();
        // One pass each from two submaps: neither alone makes the free space free.
        let first = SubmapGrid::trace(&config, &[(Pose2::IDENTITY, &scan)])
            .unwrap()
            .unwrap();
        let second = SubmapGrid::trace(&config, &[(Pose2::new(0.0, 0.2, 0.0), &scan); 2])
            .unwrap()
            .unwrap();
        let at = Pose2::new(1.0, 2.0, 0.0);
        let laid = render(&[(at, &first as &dyn Layer), (at, &second)], 0.05)
            .unwrap()
            .unwrap();
        let world = |p: Pose2| at.compose(&p);
        let whole = OccupancyGrid::build(
            &config,
            &[
                (world(Pose2::IDENTITY), &scan),
                (world(Pose2::new(0.0, 0.2, 0.0)), &scan),
                (world(Pose2::new(0.0, 0.2, 0.0)), &scan),
            ],
        )
        .unwrap()
        .unwrap();
        let res = whole.resolution_m();
        let [x0, y0] = whole.origin();
        let (mut known, mut same) = (0, 0);
        for row in 0..whole.height() {
            for col in 0..whole.width() {
                let expected = whole.state(col, row);
                if expected == CellState::Unknown {
                    continue;
                }
                let centre =
                    Vector2::new(x0 + (col as f64 + 0.5) * res, y0 + (row as f64 + 0.5) * res);
                known += 1;
                same += usize::from(state(&laid, centre) == expected);
            }
        }
        // A pass weighs less through a cell that returns made likely occupied, and each
        // submap knows only its own returns: a few cells by the wall differ, the rest agree.
        assert!(known > 500, "{known}");
        assert!(same as f64 >= 0.97 * known as f64, "{same} of {known}");
    }
}
