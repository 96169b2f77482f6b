//! Branch-and-bound correlative matching (Cartographer's fast correlative scan matcher, after
//! Olson's multi-resolution search): the exhaustive search over a window of poses gives the
//! same answer as trying every pose on the grid, at a small share of the cost.
//!
//! A submap's points are stamped into a grid whose cells hold how well a scan point landing
//! there is explained (1 on a surface, falling to 0 at [`EXPLAIN_RADIUS_CELLS`]). Level `h`
//! of the pyramid holds, per cell, the best value of the `2^h x 2^h` block of level 0 that
//! starts there, so a scan scored on level `h` at a translation bounds its score at every
//! translation of that block. The search scores the coarsest blocks, and descends only into
//! those whose bound beats the best exact score found so far.
//!
//! Scores are the mean over the scan's points, a share of the points explained: the same on
//! a scan of 180 beams and of 1081, on a log and in a simulated world.

use nalgebra::Vector2;
use slam_geom::{Pose2, wrap_angle};

/// Where a level-0 value falls to zero, in cells: a point that far from every surface is not
/// explained. Two cells: the voxels the points were thinned to, plus the ranges' noise.
pub const EXPLAIN_RADIUS_CELLS: f64 = 2.0;

/// The match grid of one submap: the explained-value pyramid over the submap's frame.
///
/// Every level has the same cells, so a point's cell is one index into all of them. They
/// reach `2^depth - 1` cells below the stamped area, where a block still covering it starts,
/// so a bound is never cut short at the edge.
#[derive(Debug, Clone)]
pub struct MatchGrid {
    resolution: f64,
    /// Submap-frame position of the stamped area's first cell's lower corner: cell (0, 0).
    origin: Vector2<f64>,
    /// Cells kept below cell (0, 0) on each axis.
    reach: i32,
    /// Cells kept on each axis, from `-reach`.
    width: i32,
    height: i32,
    /// `levels[h]`: the values of the blocks that start at each cell, values 0..=255,
    /// row-major.
    levels: Vec<Vec<u8>>,
}

/// A search window around a seed pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchWindow {
    /// Half-width in x and y, metres.
    pub translation: f64,
    /// Half-width in yaw, radians.
    pub yaw: f64,
}

/// The best pose found and its score (share of points explained, 0..1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridMatch {
    pub pose: Pose2,
    pub score: f64,
}

/// One candidate translation (in cells, from the seed) at one yaw of the search.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    yaw_index: usize,
    dx: i32,
    dy: i32,
    score: u32,
}

/// The scan at one yaw of a search, as cells of the grid at the seed's translation.
struct Footprint {
    /// Points that stay on the grid at every translation of the window: their cell's index.
    inside: Vec<i32>,
    /// Points that leave it at some: their cell, checked at each translation. Points off
    /// the grid at every translation score nothing and are left out.
    edge: Vec<(i32, i32)>,
}

impl MatchGrid {
    /// The pyramid over `points` (submap frame) at `resolution`, deep enough for windows up
    /// to `max_window` metres each way.
    pub fn new(points: &[Vector2<f64>], resolution: f64, max_window: f64) -> Self {
        let depth = depth_for(max_window / resolution);
        let reach = (1 << depth) - 1;
        let pad = EXPLAIN_RADIUS_CELLS.ceil() + 1.0;
        let (mut lo, mut hi) = (
            Vector2::repeat(f64::INFINITY),
            Vector2::repeat(f64::NEG_INFINITY),
        );
        for p in points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if points.is_empty() {
            lo = Vector2::zeros();
            hi = Vector2::zeros();
        }
        let origin = lo - Vector2::repeat(pad * resolution);
        let width = ((hi.x - lo.x) / resolution + 2.0 * pad).ceil() as i32 + 1 + reach;
        let height = ((hi.y - lo.y) / resolution + 2.0 * pad).ceil() as i32 + 1 + reach;
        let mut grid = Self {
            resolution,
            origin,
            reach,
            width,
            height,
            levels: Vec::with_capacity(depth + 1),
        };
        grid.levels.push(grid.stamp(points));
        for h in 1..=depth {
            let next = pooled(&grid.levels[h - 1], width as usize, 1 << (h - 1));
            grid.levels.push(next);
        }
        grid
    }

    /// Memory held by the pyramid, bytes.
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(Vec::len).sum()
    }

    /// The pose within `window` of `seed` where the most of `scan` (robot frame) is
    /// explained, if its score reaches `min_score`. Yaw steps move the points' RMS radius by
    /// a cell; translations are whole cells.
    pub fn search(
        &self,
        scan: &[Vector2<f64>],
        seed: &Pose2,
        window: SearchWindow,
        min_score: f64,
    ) -> Option<GridMatch> {
        if scan.is_empty() {
            return None;
        }
        let yaw_step = (self.resolution / yaw_lever(scan)).min(window.yaw.max(1e-9));
        let yaw_half = (window.yaw / yaw_step).floor() as i64;
        let half = (window.translation / self.resolution).ceil() as i32;
        let depth = (self.levels.len() - 1).min(depth_for(f64::from(half)));
        let yaws: Vec<f64> = (-yaw_half..=yaw_half)
            .map(|k| wrap_angle(seed.yaw + k as f64 * yaw_step))
            .collect();
        // Each yaw's points in cells, relative to the seed's translation.
        let rotated: Vec<Footprint> = yaws
            .iter()
            .map(|&yaw| self.footprint(scan, &Pose2::new(seed.x, seed.y, yaw), half))
            .collect();
        let total = scan.len() as u32 * 255;
        let floor = (min_score.clamp(0.0, 1.0) * f64::from(total)).ceil() as u32;
        let step = 1i32 << depth;
        let mut top = Vec::new();
        for (yaw_index, footprint) in rotated.iter().enumerate() {
            let mut dx = -half;
            while dx <= half {
                let mut dy = -half;
                while dy <= half {
                    let score = self.score(footprint, dx, dy, depth, floor);
                    if score >= floor {
                        top.push(Candidate {
                            yaw_index,
                            dx,
                            dy,
                            score,
                        });
                    }
                    dy += step;
                }
                dx += step;
            }
        }
        top.sort_unstable_by_key(|c| std::cmp::Reverse(c.score));
        let mut best: Option<Candidate> = None;
        let mut bound = floor;
        for candidate in top {
            self.descend(&rotated, candidate, depth, half, &mut best, &mut bound);
        }
        let best = best?;
        Some(GridMatch {
            pose: Pose2::new(
                seed.x + f64::from(best.dx) * self.resolution,
                seed.y + f64::from(best.dy) * self.resolution,
                yaws[best.yaw_index],
            ),
            score: f64::from(best.score) / f64::from(total),
        })
    }

    /// Depth-first through the blocks under `candidate` (scored at `level`), children best
    /// first, pruning every block whose bound does not beat `bound`.
    fn descend(
        &self,
        rotated: &[Footprint],
        candidate: Candidate,
        level: usize,
        half: i32,
        best: &mut Option<Candidate>,
        bound: &mut u32,
    ) {
        if candidate.score < *bound || (best.is_some() && candidate.score == *bound) {
            return;
        }
        if level == 0 {
            *bound = candidate.score;
            *best = Some(candidate);
            return;
        }
        let child = 1i32 << (level - 1);
        let mut children = [candidate; 4];
        let mut count = 0;
        for (ox, oy) in [(0, 0), (child, 0), (0, child), (child, child)] {
            let (dx, dy) = (candidate.dx + ox, candidate.dy + oy);
            if dx > half || dy > half {
                continue;
            }
            let score = self.score(&rotated[candidate.yaw_index], dx, dy, level - 1, *bound);
            children[count] = Candidate {
                dx,
                dy,
                score,
                ..candidate
            };
            count += 1;
        }
        // Stable: of children that score the same, the first stays first.
        children[..count].sort_by_key(|c| std::cmp::Reverse(c.score));
        for &c in &children[..count] {
            self.descend(rotated, c, level - 1, half, best, bound);
        }
    }

    /// The summed level-`level` values under the points shifted by `(dx, dy)` cells. A sum
    /// that can no longer reach `need`, even were every point left worth the most, is cut
    /// short: it is pruned whatever it would have come to.
    fn score(&self, footprint: &Footprint, dx: i32, dy: i32, level: usize, need: u32) -> u32 {
        let cells = &self.levels[level];
        let shift = dy * self.width + dx;
        let mut sum = 0;
        let mut left = 255 * (footprint.inside.len() + footprint.edge.len()) as u32;
        for chunk in footprint.inside.chunks(SCORE_CHUNK) {
            sum += chunk
                .iter()
                .map(|&index| u32::from(cells[(index + shift) as usize]))
                .sum::<u32>();
            left -= 255 * chunk.len() as u32;
            if sum + left < need {
                return sum;
            }
        }
        let (width, height) = (self.width as u32, self.height as u32);
        for &(x, y) in &footprint.edge {
            // Below zero wraps to beyond the width: one comparison per axis.
            let (x, y) = ((x + dx) as u32, (y + dy) as u32);
            if x < width && y < height {
                sum += u32::from(cells[(y * width + x) as usize]);
            }
        }
        sum
    }

    /// The kept cells `scan` falls in at `pose` (counted from `-reach`), sorted by whether
    /// they stay on the grid at every translation within `half` cells.
    fn footprint(&self, scan: &[Vector2<f64>], pose: &Pose2, half: i32) -> Footprint {
        let rotation = pose.rotation();
        let translation = Vector2::new(pose.x, pose.y);
        let mut footprint = Footprint {
            inside: Vec::with_capacity(scan.len()),
            edge: Vec::new(),
        };
        for p in scan {
            let q = (rotation * p + translation - self.origin) / self.resolution;
            let (x, y) = (floor_i32(q.x) + self.reach, floor_i32(q.y) + self.reach);
            // Whether a coordinate stays on the grid at every shift of the window, and
            // whether at any.
            let always = |c: i32, size: i32| c - half >= 0 && c + half < size;
            let ever = |c: i32, size: i32| c + half >= 0 && c - half < size;
            if always(x, self.width) && always(y, self.height) {
                footprint.inside.push(y * self.width + x);
            } else if ever(x, self.width) && ever(y, self.height) {
                footprint.edge.push((x, y));
            }
        }
        footprint
    }

    /// The level-0 score of `scan` at `pose`, a share of the points.
    pub fn score_at(&self, scan: &[Vector2<f64>], pose: &Pose2) -> f64 {
        if scan.is_empty() {
            return 0.0;
        }
        let footprint = self.footprint(scan, pose, 0);
        f64::from(self.score(&footprint, 0, 0, 0, 0)) / (255.0 * scan.len() as f64)
    }
}

/// `floor(v)` as an integer (saturating, as `as` does), without the library call that
/// `f64::floor` is on the baseline x86-64 target.
fn floor_i32(v: f64) -> i32 {
    let t = v as i32;
    if f64::from(t) > v { t - 1 } else { t }
}

/// Points scored between two checks of whether a score can still reach what it needs.
const SCORE_CHUNK: usize = 32;

/// The lever a turn acts on: the RMS distance of the points. A yaw step moves a point at this
/// distance by a cell; farther points move by more, and the registration after the search
/// takes up what the grid's steps leave.
fn yaw_lever(scan: &[Vector2<f64>]) -> f64 {
    let mean_square = scan.iter().map(|p| p.norm_squared()).sum::<f64>() / scan.len() as f64;
    mean_square.sqrt().max(1.0)
}

/// Deepest level: blocks of 32 cells. Coarser blocks bound so loosely that nearly every one
/// is searched anyway, and the pyramid's cost grows with the block.
const MAX_DEPTH: usize = 5;

/// Levels so that the coarsest block spans the window's half-width, at most [`MAX_DEPTH`].
fn depth_for(half_cells: f64) -> usize {
    let mut depth = 0;
    while ((1usize << depth) as f64) < half_cells && depth < MAX_DEPTH {
        depth += 1;
    }
    depth
}

/// Level `h` from level `h - 1` (`width` cells a row): the max over a block twice as wide,
/// each cell with the cell `half` (`2^(h-1)`) beyond it, in x then in y; zero off the grid.
fn pooled(below: &[u8], width: usize, half: usize) -> Vec<u8> {
    let mut rows = below.to_vec();
    for (out, row) in rows.chunks_exact_mut(width).zip(below.chunks_exact(width)) {
        let beyond = row.get(half..).unwrap_or_default();
        for (cell, &b) in out.iter_mut().zip(beyond) {
            *cell = (*cell).max(b);
        }
    }
    let mut cells = rows.clone();
    let beyond = rows.get(half * width..).unwrap_or_default();
    for (cell, &b) in cells.iter_mut().zip(beyond) {
        *cell = (*cell).max(b);
    }
    cells
}

impl MatchGrid {
    /// Level 0: each cell near a point holds `1 - (d / r)^2`, scaled to 255, at its best
    /// point.
    fn stamp(&self, points: &[Vector2<f64>]) -> Vec<u8> {
        let (width, height) = (self.width as usize, self.height as usize);
        let mut cells = vec![0u8; width * height];
        let radius = EXPLAIN_RADIUS_CELLS.ceil() as i64;
        let r2 = EXPLAIN_RADIUS_CELLS * EXPLAIN_RADIUS_CELLS;
        let reach = i64::from(self.reach);
        for p in points {
            let q = (p - self.origin) / self.resolution;
            let (cx, cy) = (q.x.floor() as i64, q.y.floor() as i64);
            for x in (cx - radius).max(0)..=(cx + radius).min(width as i64 - 1 - reach) {
                for y in (cy - radius).max(0)..=(cy + radius).min(height as i64 - 1 - reach) {
                    let d2 = (x as f64 + 0.5 - q.x).powi(2) + (y as f64 + 0.5 - q.y).powi(2);
                    if d2 >= r2 {
                        continue;
                    }
                    let value = (255.0 * (1.0 - d2 / r2)).round() as u8;
                    let cell = &mut cells[(y + reach) as usize * width + (x + reach) as usize];
                    *cell = (*cell).max(value);
                }
            }
        }
        cells
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points every 2 cm along the walls of an L-shaped room with a pillar.
    fn room() -> Vec<Vector2<f64>> {
        let mut points = Vec::new();
        let mut wall = |a: Vector2<f64>, b: Vector2<f64>| {
            let n = ((b - a).norm() / 0.02).ceil() as usize;
            for i in 0..=n {
                points.push(a + (b - a) * (i as f64 / n as f64));
            }
        };
        let corners = [
            (0.0, 0.0),
            (8.0, 0.0),
            (8.0, 3.0),
            (3.0, 3.0),
            (3.0, 7.0),
            (0.0, 7.0),
        ];
        for i in 0..corners.len() {
            let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
            wall(Vector2::new(a.0, a.1), Vector2::new(b.0, b.1));
        }
        wall(Vector2::new(1.0, 4.0), Vector2::new(1.4, 4.0));
        wall(Vector2::new(1.4, 4.0), Vector2::new(1.4, 4.4));
        points
    }

    /// The room as seen from `pose`: the points within 6 m, in the robot frame.
    fn seen_from(room: &[Vector2<f64>], pose: &Pose2) -> Vec<Vector2<f64>> {
        let robot_from_world = pose.inverse();
        room.iter()
            .map(|p| robot_from_world.transform(*p))
            .filter(|p| p.norm() < 6.0)
            .step_by(5)
            .collect()
    }

    #[test]
    fn finds_the_pose_two_metres_and_twenty_degrees_from_the_seed() {
        let room = room();
        let grid = MatchGrid::new(&room, 0.05, 3.0);
        let truth = Pose2::new(1.6, 1.4, 0.3);
        let scan = seen_from(&room, &truth);
        let seed = Pose2::new(truth.x - 1.5, truth.y + 1.2, truth.yaw - 0.35);
        let window = SearchWindow {
            translation: 2.0,
            yaw: 0.5,
        };
        let found = grid.search(&scan, &seed, window, 0.5).unwrap();
        assert!(
            (found.pose.position() - truth.position()).norm() < 0.05,
            "{found:?}"
        );
        assert!((found.pose.yaw - truth.yaw).abs() < 0.01, "{found:?}");
        assert!(found.score > 0.9, "{found:?}");
    }

    #[test]
    fn the_search_matches_trying_every_pose_on_its_grid() {
        let room = room();
        let grid = MatchGrid::new(&room, 0.05, 1.0);
        let truth = Pose2::new(5.0, 1.5, -0.2);
        let scan = seen_from(&room, &truth);
        let seed = Pose2::new(5.3, 1.2, -0.15);
        let window = SearchWindow {
            translation: 0.4,
            yaw: 0.08,
        };
        let found = grid.search(&scan, &seed, window, 0.0).unwrap();
        // Exhaustive: every yaw step and every cell of the window.
        let yaw_step = (0.05 / yaw_lever(&scan)).min(window.yaw);
        let yaw_half = (window.yaw / yaw_step).floor() as i64;
        let half = (window.translation / 0.05).ceil() as i32;
        let mut best = 0.0f64;
        for k in -yaw_half..=yaw_half {
            for dx in -half..=half {
                for dy in -half..=half {
                    let pose = Pose2::new(
                        seed.x + f64::from(dx) * 0.05,
                        seed.y + f64::from(dy) * 0.05,
                        seed.yaw + k as f64 * yaw_step,
                    );
                    best = best.max(grid.score_at(&scan, &pose));
                }
            }
        }
        assert!(
            (found.score - best).abs() < 1e-9,
            "{} vs {best}",
            found.score
        );
    }

    #[test]
    fn nothing_is_found_below_the_floor() {
        let room = room();
        let grid = MatchGrid::new(&room, 0.05, 1.0);
        // A scan of a different place: a long corridor 2 m wide.
        let scan: Vec<Vector2<f64>> = (0..200)
            .map(|i| {
                let x = -5.0 + 0.05 * f64::from(i);
                Vector2::new(x, if i % 2 == 0 { 1.0 } else { -1.0 })
            })
            .collect();
        let window = SearchWindow {
            translation: 1.0,
            yaw: 0.2,
        };
        assert!(
            grid.search(&scan, &Pose2::new(4.0, 1.5, 0.0), window, 0.7)
                .is_none()
        );
    }
}
