//! Exact ray casting against the wall segments through a uniform grid.
//!
//! Each segment is listed in every cell it touches (conservatively, with a small margin so
//! a segment on a cell border is in both cells). A ray walks the cells it crosses in order
//! (Amanatides-Woo DDA) and tests the segments listed there; it stops once its nearest hit
//! so far lies no farther than the exit of the current cell, because every segment that
//! could be hit earlier is listed in a cell already visited.

use crate::geometry::Segment;
use crate::{Point2, World};

/// Margin of a cell when listing segments, metres: covers the rounding of a ray that crosses
/// a cell corner or a segment lying on a cell border.
const CELL_MARGIN: f64 = 1e-7;

/// At most this many cells along either axis, to bound memory for huge sparse worlds.
const MAX_CELLS_PER_AXIS: f64 = 1024.0;

/// The walls of a world in a uniform grid, for fast exact ray casts.
#[derive(Debug, Clone)]
pub struct RayCaster {
    segments: Vec<Segment>,
    min: Point2,
    max: Point2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Cell `c` lists `items[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl RayCaster {
    /// Grids the walls of `world`.
    pub fn new(world: &World) -> RayCaster {
        RayCaster::from_segments(world.segments().map(|[a, b]| Segment::new(a, b)).collect())
    }

    /// Grids arbitrary segments; zero-length ones are dropped (a ray would hit them only
    /// by grazing a point).
    pub fn from_segments(mut segments: Vec<Segment>) -> RayCaster {
        segments.retain(|s| s.e != Point2::zeros());
        let ends = segments.iter().flat_map(|s| [s.a, s.a + s.e]);
        let (mut min, mut max) = (
            Point2::repeat(f64::INFINITY),
            Point2::repeat(f64::NEG_INFINITY),
        );
        for p in ends {
            min = min.inf(&p);
            max = max.sup(&p);
        }
        if segments.is_empty() {
            (min, max) = (Point2::zeros(), Point2::zeros());
        }
        min -= Point2::repeat(1e-6);
        max += Point2::repeat(1e-6);
        let size = max - min;
        // About one cell per segment keeps both the cells walked and the segments per cell
        // small; a world of long walls simply lists each wall in several cells.
        let cell = (size.x * size.y / segments.len().max(1) as f64)
            .sqrt()
            .max(size.max() / MAX_CELLS_PER_AXIS);
        let nx = ((size.x / cell).ceil() as usize).max(1);
        let ny = ((size.y / cell).ceil() as usize).max(1);

        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
        for (k, s) in segments.iter().enumerate() {
            let (lo, hi) = (s.a.inf(&(s.a + s.e)), s.a.sup(&(s.a + s.e)));
            let index =
                |v: f64, m: f64, n: usize| (((v - m) / cell).floor().max(0.0) as usize).min(n - 1);
            let (i0, i1) = (
                index(lo.x - CELL_MARGIN, min.x, nx),
                index(hi.x + CELL_MARGIN, min.x, nx),
            );
            let (j0, j1) = (
                index(lo.y - CELL_MARGIN, min.y, ny),
                index(hi.y + CELL_MARGIN, min.y, ny),
            );
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c0 =
                        min + Point2::new(i as f64, j as f64) * cell - Point2::repeat(CELL_MARGIN);
                    let c1 = c0 + Point2::repeat(cell + 2.0 * CELL_MARGIN);
                    // The segment's bounding box overlaps the cell; it misses the cell only
                    // if all four cell corners lie strictly on one side of its line.
                    let side = [c0, Point2::new(c1.x, c0.y), c1, Point2::new(c0.x, c1.y)]
                        .map(|p| crate::geometry::cross(s.e, p - s.a));
                    if !(side.iter().all(|&v| v > 0.0) || side.iter().all(|&v| v < 0.0)) {
                        lists[j * nx + i].push(k as u32);
                    }
                }
            }
        }
        let mut starts = Vec::with_capacity(lists.len() + 1);
        let mut items = Vec::new();
        starts.push(0);
        for list in lists {
            items.extend(list);
            starts.push(items.len() as u32);
        }
        RayCaster {
            segments,
            min,
            max,
            cell,
            nx,
            ny,
            starts,
            items,
        }
    }

    /// The wall segments.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Cells along x and y and the cell size, metres.
    pub fn grid(&self) -> (usize, usize, f64) {
        (self.nx, self.ny, self.cell)
    }

    /// Distance from `origin` along the bearing `angle` (world frame) to the first wall,
    /// if one lies within `max_range`.
    pub fn cast(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<f64> {
        let o = Point2::new(origin[0], origin[1]);
        if !(o.x.is_finite() && o.y.is_finite() && angle.is_finite()) || max_range.is_nan() {
            return None;
        }
        let (sin, cos) = angle.sin_cos();
        let d = Point2::new(cos, sin);
        // Clip the ray to the grid's box (slab test).
        let (mut t0, mut t1) = (0.0f64, max_range);
        for a in 0..2 {
            if d[a] == 0.0 {
                if o[a] < self.min[a] || o[a] > self.max[a] {
                    return None;
                }
            } else {
                let (ta, tb) = ((self.min[a] - o[a]) / d[a], (self.max[a] - o[a]) / d[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 > t1 {
            return None;
        }
        let p = o + t0 * d;
        let n = [self.nx as isize, self.ny as isize];
        let mut idx = [0isize; 2];
        let mut step = [0isize; 2];
        for a in 0..2 {
            idx[a] = (((p[a] - self.min[a]) / self.cell).floor() as isize).clamp(0, n[a] - 1);
            step[a] = if d[a] > 0.0 {
                1
            } else if d[a] < 0.0 {
                -1
            } else {
                0
            };
        }
        // Where the ray leaves the current cell across axis `a`, from the absolute cell
        // border (no accumulated rounding).
        let exit = |a: usize, i: isize| -> f64 {
            if step[a] == 0 {
                return f64::INFINITY;
            }
            let border = self.min[a] + (i + isize::from(step[a] > 0)) as f64 * self.cell;
            (border - o[a]) / d[a]
        };
        let mut best = f64::INFINITY;
        loop {
            let (tx, ty) = (exit(0, idx[0]), exit(1, idx[1]));
            let c = idx[1] as usize * self.nx + idx[0] as usize;
            for &k in &self.items[self.starts[c] as usize..self.starts[c + 1] as usize] {
                if let Some(t) = self.segments[k as usize].hit(o, d) {
                    best = best.min(t);
                }
            }
            let t_exit = tx.min(ty);
            if best <= t_exit || t_exit >= t1 {
                break;
            }
            let a = usize::from(tx >= ty);
            idx[a] += step[a];
            if idx[a] < 0 || idx[a] >= n[a] {
                break;
            }
        }
        (best <= max_range).then_some(best)
    }

    /// [`RayCaster::cast`] by testing every segment: the reference the grid is tested
    /// against.
    pub fn cast_brute_force(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<f64> {
        let o = Point2::new(origin[0], origin[1]);
        let (sin, cos) = angle.sin_cos();
        let d = Point2::new(cos, sin);
        self.segments
            .iter()
            .filter_map(|s| s.hit(o, d))
            .fold(None, |best: Option<f64>, t| {
                Some(best.map_or(t, |b| b.min(t)))
            })
            .filter(|&t| t <= max_range)
    }
}
