//! Where the walls of a traced grid are, finer than its cells: each occupied cell stands for
//! the mean of the returns that fell in it, with the direction of the wall through it, and
//! every cell near a wall knows which occupied cell is nearest. A point's distance to the
//! map is then its distance to that wall's line, as exact as the returns themselves rather
//! than rounded to a cell: aligning scans to cell centres would bend a path that is already
//! right to within a cell.

use back_end::occupancy_grid::{CellState, OccupancyGrid};

/// A return in the world frame and where the sensor was that saw it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SeenReturn {
    pub at: [f64; 2],
    pub from: [f64; 2],
}

/// A wall piece: the mean of the returns in one occupied cell, and the wall's normal there
/// when the neighbouring pieces line up (`None` at an isolated piece: a post, a leg),
/// turned towards the side its returns were seen from, and the tag most of its returns
/// carry.
#[derive(Debug, Clone, Copy, PartialEq)]
struct WallPiece {
    point: [f64; 2],
    normal: Option<[f64; 2]>,
    tag: u32,
}

/// What the returns that fell in one occupied cell add up to.
#[derive(Debug, Clone, Copy)]
struct CellSums {
    /// Row-major index of the cell in the field's window.
    cell: usize,
    returns: [f64; 2],
    /// The vectors from the returns back to the sensors that saw them.
    to_sensors: [f64; 2],
    count: f64,
    /// The tag most of the returns carry, if one does (a majority vote taken in one
    /// sweep): its candidate and the votes it holds.
    tag: u32,
    votes: u32,
}

/// The signed distance of a point to the nearest wall piece and its gradient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WallDistance {
    /// Along the wall's normal (signed), or straight to the piece where it has none.
    pub residual: f64,
    /// d residual / d point.
    pub gradient: [f64; 2],
    /// The tag most of that wall piece's returns carry (0 in a field built untagged).
    pub tag: u32,
}

/// A rectangle of a grid's cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CellWindow {
    col: usize,
    row: usize,
    width: usize,
    height: usize,
}

impl CellWindow {
    /// Every cell of `grid`.
    pub fn whole(grid: &OccupancyGrid) -> Self {
        Self {
            col: 0,
            row: 0,
            width: grid.width(),
            height: grid.height(),
        }
    }

    /// The cells of `grid` that overlap the world rectangle from `min` to `max`; `None`
    /// when it lies off the grid.
    pub fn around(grid: &OccupancyGrid, min: [f64; 2], max: [f64; 2]) -> Option<Self> {
        let origin = grid.origin();
        let resolution = grid.resolution_m();
        let cell = |v: f64, o: f64, size: usize| -> f64 {
            ((v - o) / resolution).floor().clamp(0.0, size as f64)
        };
        let (col, row) = (
            cell(min[0], origin[0], grid.width()),
            cell(min[1], origin[1], grid.height()),
        );
        let (end_col, end_row) = (
            cell(max[0], origin[0], grid.width() - 1) + 1.0,
            cell(max[1], origin[1], grid.height() - 1) + 1.0,
        );
        (end_col > col && end_row > row).then_some(Self {
            col: col as usize,
            row: row as usize,
            width: (end_col - col) as usize,
            height: (end_row - row) as usize,
        })
    }
}

/// The wall pieces of a grid and, for every cell within the far reach of one, the nearest
/// and how far it is.
#[derive(Debug, Clone)]
pub(crate) struct WallField {
    origin: [f64; 2],
    resolution: f64,
    nearest: NearestPieces,
    /// The reaches, as squared distances in cells.
    near_cells2: u32,
    far_cells2: u32,
    pieces: Vec<WallPiece>,
}

/// For every cell within reach of a wall piece, the nearest and its squared distance in
/// cells (between the cells' centres).
#[derive(Debug, Clone)]
struct NearestPieces {
    width: usize,
    height: usize,
    /// One more than the index of the nearest piece; 0 (a table zeroed when allocated,
    /// which costs nothing where it is never written) beyond reach.
    nearest: Vec<u32>,
    /// One more than the squared distance to it, 0 beyond reach.
    distance2: Vec<u32>,
}

impl NearestPieces {
    /// The table over a field `width` x `height` cells with pieces in `cells` (row-major
    /// indices into the field), `reach` cells out. The pieces' reach spreads outwards from
    /// them ring by ring, each cell passing its nearest piece on to its neighbours: a cell
    /// is visited a few times, rather than once for every piece within reach of it.
    fn new(width: usize, height: usize, cells: &[usize], reach: usize) -> Self {
        let mut nearest = vec![0_u32; width * height];
        let mut distance2 = vec![0_u32; width * height];
        let limit = (reach * reach) as u32;
        // Cells by the squared distance they were reached at.
        let mut rings: Vec<Vec<u32>> = vec![Vec::new(); limit as usize + 1];
        for (k, &i) in cells.iter().enumerate() {
            nearest[i] = k as u32 + 1;
            distance2[i] = 1;
            rings[0].push(i as u32);
        }
        for ring in 0..=limit {
            let mut next = 0;
            while next < rings[ring as usize].len() {
                let i = rings[ring as usize][next] as usize;
                next += 1;
                if distance2[i] != ring + 1 {
                    // Reached nearer since.
                    continue;
                }
                let piece = cells[nearest[i] as usize - 1];
                let (piece_col, piece_row) = ((piece % width) as i64, (piece / width) as i64);
                let (col, row) = ((i % width) as i64, (i / width) as i64);
                for (dc, dr) in NEIGHBOURS {
                    let (c, r) = (col + dc, row + dr);
                    if c < 0 || r < 0 || c >= width as i64 || r >= height as i64 {
                        continue;
                    }
                    let d2 = ((c - piece_col).pow(2) + (r - piece_row).pow(2)) as u32;
                    let j = r as usize * width + c as usize;
                    if d2 > limit || (distance2[j] != 0 && distance2[j] <= d2 + 1) {
                        continue;
                    }
                    nearest[j] = nearest[i];
                    distance2[j] = d2 + 1;
                    rings[d2.max(ring) as usize].push(j as u32);
                }
            }
        }
        Self {
            width,
            height,
            nearest,
            distance2,
        }
    }

    /// The index of the piece nearest the cell `col`, `row`, if it is within `reach2`
    /// (squared, in cells).
    fn nearest(&self, col: usize, row: usize, reach2: u32) -> Option<usize> {
        if col >= self.width || row >= self.height {
            return None;
        }
        let i = row * self.width + col;
        let (k, d2) = (self.nearest[i], self.distance2[i]);
        (k > 0 && d2 <= reach2 + 1).then(|| k as usize - 1)
    }
}

/// The eight cells around a cell.
const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Cells around a piece whose pieces decide its normal (a 5 x 5 block).
const NORMAL_RADIUS_CELLS: i64 = 2;
/// A normal needs this many pieces lined up with it, the piece itself included.
const MIN_NORMAL_PIECES: usize = 3;
/// The spread across the line must be this much smaller than along it for a wall (as
/// standard deviations). A wall seen at a slant or from afar is drawn two cells thick, and
/// its pieces' means lie in two rows: their spread across is over a third of the spread
/// along the 5 x 5 block, and such a wall still runs along a line. A corner's or a post's
/// pieces, spread alike both ways, have none.
const MAX_FLATNESS: f64 = 0.7;

impl WallField {
    /// The walls of `grid`, from the returns `ends` (world frame) that built it; cells
    /// farther than `reach_m` from every wall get none, and blocks of cells farther than
    /// `far_reach_m` none either. `None` when no cell is occupied.
    pub fn new(
        grid: &OccupancyGrid,
        ends: &[SeenReturn],
        reach_m: f64,
        far_reach_m: f64,
    ) -> Option<Self> {
        Self::within(
            grid,
            CellWindow::whole(grid),
            ends,
            &[],
            reach_m,
            far_reach_m,
        )
    }

    /// [`new`](Self::new) over the cells of `window` only, from the returns `ends` among
    /// those that built the grid: a wall piece is an occupied cell some of `ends` fell in.
    /// `tags`, one per return (or none), say who drew each: a distance names the tag most
    /// returns of its wall piece carry.
    pub fn within(
        grid: &OccupancyGrid,
        window: CellWindow,
        ends: &[SeenReturn],
        tags: &[u32],
        reach_m: f64,
        far_reach_m: f64,
    ) -> Option<Self> {
        let (width, height) = (window.width, window.height);
        let resolution = grid.resolution_m();
        let origin = [
            grid.origin()[0] + window.col as f64 * resolution,
            grid.origin()[1] + window.row as f64 * resolution,
        ];
        let cell_of = |p: [f64; 2]| -> Option<usize> {
            let col = ((p[0] - origin[0]) / resolution).floor();
            let row = ((p[1] - origin[1]) / resolution).floor();
            (col >= 0.0 && row >= 0.0 && col < width as f64 && row < height as f64)
                .then(|| row as usize * width + col as usize)
        };
        // Per occupied cell: the sum of its returns, of the vectors from them back to their
        // sensors (only the side they add up to matters), and their count. `slot` maps a
        // cell of the window to its sums (one more than their index; 0: none).
        let mut slot = vec![0_u32; width * height];
        let mut sums: Vec<CellSums> = Vec::new();
        for (k, seen) in ends.iter().enumerate() {
            let p = seen.at;
            let tag = tags.get(k).copied().unwrap_or(0);
            let Some(i) = cell_of(p) else { continue };
            if slot[i] == 0 {
                if grid.state(window.col + i % width, window.row + i / width) != CellState::Occupied
                {
                    continue;
                }
                sums.push(CellSums {
                    cell: i,
                    returns: [0.0, 0.0],
                    to_sensors: [0.0, 0.0],
                    count: 0.0,
                    tag,
                    votes: 0,
                });
                slot[i] = sums.len() as u32;
            }
            let entry = &mut sums[slot[i] as usize - 1];
            entry.returns[0] += p[0];
            entry.returns[1] += p[1];
            entry.to_sensors[0] += seen.from[0] - p[0];
            entry.to_sensors[1] += seen.from[1] - p[1];
            entry.count += 1.0;
            if entry.tag == tag {
                entry.votes += 1;
            } else if entry.votes == 0 {
                entry.tag = tag;
                entry.votes = 1;
            } else {
                entry.votes -= 1;
            }
        }
        if sums.is_empty() {
            return None;
        }
        // Pieces in the order of their cells, so that which of two equally near pieces a
        // cell takes does not depend on the order the returns came in.
        sums.sort_unstable_by_key(|c| c.cell);
        for (k, c) in sums.iter().enumerate() {
            slot[c.cell] = k as u32 + 1;
        }
        let means: Vec<[f64; 2]> = sums
            .iter()
            .map(|c| [c.returns[0] / c.count, c.returns[1] / c.count])
            .collect();
        let mut around = Vec::new();
        let pieces: Vec<WallPiece> = sums
            .iter()
            .zip(&means)
            .map(|(c, &point)| {
                let (col, row) = ((c.cell % width) as i64, (c.cell / width) as i64);
                around.clear();
                for dr in -NORMAL_RADIUS_CELLS..=NORMAL_RADIUS_CELLS {
                    for dc in -NORMAL_RADIUS_CELLS..=NORMAL_RADIUS_CELLS {
                        let (c, r) = (col + dc, row + dr);
                        if c < 0 || r < 0 || c >= width as i64 || r >= height as i64 {
                            continue;
                        }
                        if let Some(k) = slot[r as usize * width + c as usize].checked_sub(1) {
                            around.push(means[k as usize]);
                        }
                    }
                }
                let seen_from = c.to_sensors;
                let normal = line_normal(&around).map(|n| {
                    if n[0] * seen_from[0] + n[1] * seen_from[1] < 0.0 {
                        [-n[0], -n[1]]
                    } else {
                        n
                    }
                });
                WallPiece {
                    point,
                    normal,
                    tag: c.tag,
                }
            })
            .collect();
        let cells: Vec<usize> = sums.iter().map(|c| c.cell).collect();

        let cells2 = |reach_m: f64| (reach_m / resolution).ceil().powi(2) as u32;
        let (near_cells2, far_cells2) = (cells2(reach_m), cells2(far_reach_m.max(reach_m)));
        let reach = (far_cells2 as f64).sqrt().round() as usize;
        Some(Self {
            origin,
            resolution,
            nearest: NearestPieces::new(width, height, &cells, reach),
            near_cells2,
            far_cells2,
            pieces,
        })
    }

    /// The distance from `point` (world frame), a return seen from `from`, to the wall
    /// nearest its cell; `None` beyond reach of every wall, off the grid, or when that
    /// wall faces away from `from`: the far side of a wall that other scans saw from the
    /// other side is not where this one's return ended.
    pub fn distance(&self, point: [f64; 2], from: [f64; 2]) -> Option<WallDistance> {
        self.distance_by(self.near_cells2, point, from)
    }

    /// [`distance`](Self::distance) for a point up to the far reach from the walls: for the
    /// first steps of an alignment that starts farther off.
    pub fn far_distance(&self, point: [f64; 2], from: [f64; 2]) -> Option<WallDistance> {
        self.distance_by(self.far_cells2, point, from)
    }

    fn distance_by(&self, reach2: u32, point: [f64; 2], from: [f64; 2]) -> Option<WallDistance> {
        let col = ((point[0] - self.origin[0]) / self.resolution).floor();
        let row = ((point[1] - self.origin[1]) / self.resolution).floor();
        if col < 0.0 || row < 0.0 {
            return None;
        }
        let piece = &self.pieces[self.nearest.nearest(col as usize, row as usize, reach2)?];
        let d = [point[0] - piece.point[0], point[1] - piece.point[1]];
        if let Some(n) = piece.normal {
            let sensor = [from[0] - piece.point[0], from[1] - piece.point[1]];
            if n[0] * sensor[0] + n[1] * sensor[1] <= 0.0 {
                return None;
            }
        }
        Some(match piece.normal {
            Some(n) => WallDistance {
                residual: n[0] * d[0] + n[1] * d[1],
                gradient: n,
                tag: piece.tag,
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
                    tag: piece.tag,
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
    use back_end::compact_scan::CompactScan;
    use back_end::occupancy_grid::GridConfig;
    use slam_geom::Pose2;

    /// A wall along x = 2.013 (off the cells' centres), seen from the origin, and the
    /// returns in the world frame.
    fn wall() -> (OccupancyGrid, Vec<SeenReturn>) {
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
                SeenReturn {
                    at: [f64::from(*r) * a.cos(), f64::from(*r) * a.sin()],
                    from: [0.0, 0.0],
                }
            })
            .collect();
        (grid, ends)
    }

    #[test]
    fn the_distance_is_to_the_wall_itself_not_to_its_cells() {
        let (grid, ends) = wall();
        let field = WallField::new(&grid, &ends, 0.3, 1.0).expect("a wall");
        for y in [-1.0, -0.33, 0.0, 0.52, 1.4] {
            let near = field.distance([1.9, y], [0.5, 0.0]).expect("within reach");
            assert!((near.residual.abs() - 0.113).abs() < 0.003, "{y}: {near:?}");
            assert!(near.gradient[0].abs() > 0.999, "{y}: {near:?}");
        }
    }

    #[test]
    fn nothing_is_near_beyond_reach_or_off_the_grid() {
        let (grid, ends) = wall();
        let field = WallField::new(&grid, &ends, 0.3, 1.0).expect("a wall");
        assert_eq!(field.distance([1.0, 0.0], [0.0, 0.0]), None);
        assert_eq!(field.distance([100.0, 0.0], [0.0, 0.0]), None);
    }

    #[test]
    fn a_wall_is_only_where_returns_seen_from_its_own_side_end() {
        let (grid, ends) = wall();
        let field = WallField::new(&grid, &ends, 0.3, 1.0).expect("a wall");
        // Its face towards the origin, where its returns were seen from.
        let near = field.distance([1.95, 0.4], [1.0, 0.0]).expect("its face");
        assert!((near.residual - 0.063).abs() < 0.003, "{near:?}");
        // A sensor behind it sees its far side, which no return here drew.
        assert_eq!(field.distance([1.95, 0.4], [3.0, 0.0]), None);
    }

    #[test]
    fn a_window_holds_the_walls_of_the_whole_grid_within_it() {
        let (grid, ends) = wall();
        let whole = WallField::new(&grid, &ends, 0.3, 1.0).expect("a wall");
        let window = CellWindow::around(&grid, [1.5, -0.5], [2.5, 0.5]).expect("on the grid");
        let part = WallField::within(&grid, window, &ends, &[], 0.3, 1.0).expect("a wall in it");
        for y in [-0.4, 0.0, 0.33] {
            assert_eq!(
                part.distance([1.95, y], [0.0, 0.0]),
                whole.distance([1.95, y], [0.0, 0.0])
            );
        }
        assert!(whole.distance([1.95, 1.2], [0.0, 0.0]).is_some());
        assert_eq!(part.distance([1.95, 1.2], [0.0, 0.0]), None);
        assert_eq!(CellWindow::around(&grid, [50.0, 50.0], [51.0, 51.0]), None);
    }

    #[test]
    fn a_wall_piece_names_the_tag_most_of_its_returns_carry() {
        let (grid, ends) = wall();
        // The wall's lower half drawn by 7, its upper by 9, with a few of 8 in among each.
        let tags: Vec<u32> = ends
            .iter()
            .enumerate()
            .map(|(k, seen)| match (k % 5, seen.at[1] < 0.0) {
                (0, _) => 8,
                (_, true) => 7,
                (_, false) => 9,
            })
            .collect();
        let window = CellWindow::whole(&grid);
        let field = WallField::within(&grid, window, &ends, &tags, 0.3, 1.0).expect("a wall");
        let tag_at = |y: f64| field.distance([1.95, y], [0.0, 0.0]).expect("near").tag;
        assert_eq!(tag_at(-1.2), 7);
        assert_eq!(tag_at(-0.5), 7);
        assert_eq!(tag_at(0.5), 9);
        assert_eq!(tag_at(1.2), 9);
        // Untagged, every piece is 0.
        let untagged = WallField::new(&grid, &ends, 0.3, 1.0).expect("a wall");
        assert_eq!(
            untagged
                .distance([1.95, 0.5], [0.0, 0.0])
                .expect("near")
                .tag,
            0
        );
    }

    #[test]
    fn a_line_of_points_has_its_normal_and_a_blob_has_none() {
        let line: Vec<[f64; 2]> = (0..5).map(|i| [i as f64, 2.0 * i as f64]).collect();
        let n = line_normal(&line).expect("a line");
        assert!((n[0] * 1.0 + n[1] * 2.0).abs() < 1e-9, "{n:?}");
        let blob = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        assert_eq!(line_normal(&blob), None);
        // A wall drawn two cells thick (0.05 m) along x: the means of a 5 x 5 block's
        // pieces in two rows.
        let thick: Vec<[f64; 2]> = (0..10)
            .map(|i| [0.05 * (i / 2) as f64 + 0.01, 0.05 * (i % 2) as f64 + 0.02])
            .collect();
        let n = line_normal(&thick).expect("a thick wall");
        assert!(
            n[0].abs() < 1e-9 && (n[1].abs() - 1.0).abs() < 1e-9,
            "{n:?}"
        );
    }
}
