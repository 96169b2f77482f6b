//! Where the walls of a traced grid are, finer than its cells: each occupied cell stands for
//! the mean of the returns that fell in it, with the direction of the wall through it, and
//! every cell near a wall knows which occupied cell is nearest. A point's distance to the
//! map is then its distance to that wall's line, as exact as the returns themselves rather
//! than rounded to a cell: aligning scans to cell centres would bend a path that is already
//! right to within a cell.

use std::collections::HashMap;

use crate::occupancy_grid::{CellState, OccupancyGrid};

/// A wall piece: the mean of the returns in one occupied cell, and the wall's normal there
/// when the neighbouring pieces line up (`None` at an isolated piece: a post, a leg).
#[derive(Debug, Clone, Copy, PartialEq)]
struct WallPiece {
    point: [f64; 2],
    normal: Option<[f64; 2]>,
}

/// The signed distance of a point to the nearest wall piece and its gradient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WallDistance {
    /// Along the wall's normal (signed), or straight to the piece where it has none.
    pub residual: f64,
    /// d residual / d point.
    pub gradient: [f64; 2],
}

/// The wall pieces of a grid and, for every cell within reach of one, the nearest.
#[derive(Debug, Clone)]
pub(crate) struct WallField {
    origin: [f64; 2],
    resolution: f64,
    width: usize,
    height: usize,
    /// Index into `pieces` of the nearest piece, `u32::MAX` beyond reach.
    nearest: Vec<u32>,
    pieces: Vec<WallPiece>,
}

/// Cells around a piece whose pieces decide its normal (a 5 x 5 block).
const NORMAL_RADIUS_CELLS: i64 = 2;
/// A normal needs this many pieces lined up with it, the piece itself included.
const MIN_NORMAL_PIECES: usize = 3;
/// The spread across the line must be this much smaller than along it for a wall.
const MAX_FLATNESS: f64 = 0.2;
impl WallField {
    /// The walls of `grid`, from the returns `ends` (world frame) that built it; cells
    /// farther than `reach_m` from every wall get none. `None` when no cell is occupied.
    pub fn new(grid: &OccupancyGrid, ends: &[[f64; 2]], reach_m: f64) -> Option<Self> {
        let (width, height) = (grid.width(), grid.height());
        let resolution = grid.resolution_m();
        let origin = grid.origin();
        let cell_of = |p: [f64; 2]| -> Option<usize> {
            let col = ((p[0] - origin[0]) / resolution).floor();
            let row = ((p[1] - origin[1]) / resolution).floor();
            (col >= 0.0 && row >= 0.0 && col < width as f64 && row < height as f64)
                .then(|| row as usize * width + col as usize)
        };
        let mut sums: HashMap<usize, ([f64; 2], f64)> = HashMap::new();
        for &p in ends {
            let Some(i) = cell_of(p) else { continue };
            if grid.state(i % width, i / width) != CellState::Occupied {
                continue;
            }
            let entry = sums.entry(i).or_insert(([0.0, 0.0], 0.0));
            entry.0[0] += p[0];
            entry.0[1] += p[1];
            entry.1 += 1.0;
        }
        if sums.is_empty() {
            return None;
        }
        let mut cells: Vec<usize> = sums.keys().copied().collect();
        cells.sort_unstable();
        let means: HashMap<usize, [f64; 2]> = sums
            .iter()
            .map(|(&i, &(sum, n))| (i, [sum[0] / n, sum[1] / n]))
            .collect();
        let pieces: Vec<WallPiece> = cells
            .iter()
            .map(|&i| {
                let point = means[&i];
                let (col, row) = ((i % width) as i64, (i / width) as i64);
                let mut around = Vec::new();
                for dr in -NORMAL_RADIUS_CELLS..=NORMAL_RADIUS_CELLS {
                    for dc in -NORMAL_RADIUS_CELLS..=NORMAL_RADIUS_CELLS {
                        let (c, r) = (col + dc, row + dr);
                        if c < 0 || r < 0 || c >= width as i64 || r >= height as i64 {
                            continue;
                        }
                        if let Some(m) = means.get(&(r as usize * width + c as usize)) {
                            around.push(*m);
                        }
                    }
                }
                WallPiece {
                    point,
                    normal: line_normal(&around),
                }
            })
            .collect();

        let reach = (reach_m / resolution).ceil() as i64;
        let mut nearest = vec![u32::MAX; width * height];
        let mut best = vec![f64::INFINITY; width * height];
        for (k, &i) in cells.iter().enumerate() {
            let (col, row) = ((i % width) as i64, (i / width) as i64);
            for dr in -reach..=reach {
                for dc in -reach..=reach {
                    let (c, r) = (col + dc, row + dr);
                    if c < 0 || r < 0 || c >= width as i64 || r >= height as i64 {
                        continue;
                    }
                    let d2 = (dc * dc + dr * dr) as f64;
                    if d2 > (reach * reach) as f64 {
                        continue;
                    }
                    let j = r as usize * width + c as usize;
                    if d2 < best[j] {
                        best[j] = d2;
                        nearest[j] = k as u32;
                    }
                }
            }
        }
        Some(Self {
            origin,
            resolution,
            width,
            height,
            nearest,
            pieces,
        })
    }

    /// The distance from `point` (world frame) to the wall nearest its cell; `None` beyond
    /// reach of every wall or off the grid.
    pub fn distance(&self, point: [f64; 2]) -> Option<WallDistance> {
        let col = ((point[0] - self.origin[0]) / self.resolution).floor();
        let row = ((point[1] - self.origin[1]) / self.resolution).floor();
        if !(col >= 0.0 && row >= 0.0 && col < self.width as f64 && row < self.height as f64) {
            return None;
        }
        let k = self.nearest[row as usize * self.width + col as usize];
        let piece = self.pieces.get(k as usize)?;
        let d = [point[0] - piece.point[0], point[1] - piece.point[1]];
        Some(match piece.normal {
            Some(n) => WallDistance {
                residual: n[0] * d[0] + n[1] * d[1],
                gradient: n,
            },
            None => {
                let norm = d[0].hypot(d[1]);
                let gradient = if norm > 1e-9 {
                    [d[0] / norm, d[1] / norm]
                } else {
                    [0.0, 0.0]
                };
                WallDistance {
                    residual: norm,
                    gradient,
                }
            }
        })
    }
}

/// The unit normal of the line through `points`, when they lie along one.
fn line_normal(points: &[[f64; 2]]) -> Option<[f64; 2]> {
    if points.len() < MIN_NORMAL_PIECES {
        return None;
    }
    let n = points.len() as f64;
    let mean = points
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p[0] - mean[0], p[1] - mean[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    // Eigenvalues of the scatter matrix: the line runs along the larger one's vector.
    let half_trace = (sxx + syy) / 2.0;
    let root = (((sxx - syy) / 2.0).powi(2) + sxy * sxy).sqrt();
    let (large, small) = (half_trace + root, half_trace - root);
    if large <= 0.0 || small > MAX_FLATNESS * MAX_FLATNESS * large {
        return None;
    }
    // The normal is the smaller eigenvalue's eigenvector.
    let normal = if sxy.abs() > 1e-12 {
        [sxy, small - sxx]
    } else if sxx <= syy {
        [1.0, 0.0]
    } else {
        [0.0, 1.0]
    };
    let norm = normal[0].hypot(normal[1]);
    Some([normal[0] / norm, normal[1] / norm])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compact_scan::CompactScan;
    use crate::occupancy_grid::GridConfig;
    use slam_geom::Pose2;

    /// A wall along x = 2.013 (off the cells' centres), seen from the origin, and the
    /// returns in the world frame.
    fn wall() -> (OccupancyGrid, Vec<[f64; 2]>) {
        let beams = 181;
        let increment = std::f64::consts::PI / 2.0 / (beams - 1) as f64;
        let angle_min = -std::f64::consts::PI / 4.0;
        let ranges: Vec<f32> = (0..beams)
            .map(|i| (2.013 / (angle_min + i as f64 * increment).cos()) as f32)
            .collect();
        let scan = CompactScan::new(angle_min, increment, 0.05, 30.0, &ranges, 0.0, 10.0);
        let pose = Pose2::new(0.0, 0.0, 0.0);
        let grid = OccupancyGrid::build(&GridConfig::default(), &[(pose, &scan)])
            .expect("fits")
            .expect("beams");
        let ends = ranges
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let a = angle_min + i as f64 * increment;
                [f64::from(*r) * a.cos(), f64::from(*r) * a.sin()]
            })
            .collect();
        (grid, ends)
    }

    #[test]
    fn the_distance_is_to_the_wall_itself_not_to_its_cells() {
        let (grid, ends) = wall();
        let field = WallField::new(&grid, &ends, 0.3).expect("a wall");
        for y in [-1.0, -0.33, 0.0, 0.52, 1.4] {
            let near = field.distance([1.9, y]).expect("within reach");
            assert!((near.residual.abs() - 0.113).abs() < 0.003, "{y}: {near:?}");
            assert!(near.gradient[0].abs() > 0.999, "{y}: {near:?}");
        }
    }

    #[test]
    fn nothing_is_near_beyond_reach_or_off_the_grid() {
        let (grid, ends) = wall();
        let field = WallField::new(&grid, &ends, 0.3).expect("a wall");
        assert_eq!(field.distance([1.0, 0.0]), None);
        assert_eq!(field.distance([100.0, 0.0]), None);
    }

    #[test]
    fn a_line_of_points_has_its_normal_and_a_blob_has_none() {
        let line: Vec<[f64; 2]> = (0..5).map(|i| [i as f64, 2.0 * i as f64]).collect();
        let n = line_normal(&line).expect("a line");
        assert!((n[0] * 1.0 + n[1] * 2.0).abs() < 1e-9, "{n:?}");
        let blob = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        assert_eq!(line_normal(&blob), None);
    }
}
