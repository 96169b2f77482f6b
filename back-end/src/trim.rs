//! Which finished submaps repeat the map and can be retired: memory by the area mapped, not
//! by the length of the run (Cartographer's overlapping-submaps trimmer, turned round).
//!
//! A robot that drives the same building again keeps starting submaps where old ones lie.
//! Cartographer trims the old ones and keeps the newest; here the new one goes and the old
//! ones stay, because the old ones are what the robot was localized against: the closures of
//! the new submap's nodes tie it to them, and the graph keeps those nodes and closures
//! whatever happens to the submap. A submap is retired when it is finished and
//!
//! 1. its nodes were tied to older submaps by verified closures all along
//!    ([`localized_all_along`]): the robot knew where it was on the old map. The new
//!    submap is then laid over the old ones where its closures put its nodes, so that the
//!    comparison below is of the same walls, not of the front end's drift since the graph
//!    was last solved;
//! 2. older kept submaps know nearly every wall it saw ([`Overlap::new_walls`]): it maps
//!    no new area. Walls, not free space: where a submap's free space ends depends on where
//!    its beams happened to stop, while a new room or corridor always shows new walls;
//! 3. its walls agree with theirs: few stand where they saw free space
//!    ([`Overlap::changed`]). A place that changed (a cabinet moved, a door shut) keeps
//!    its new submap: a closure is judged against a submap's free space, and only a submap
//!    of the place as it is now lets the next pass close there.
//!
//! A single pass over new ground retires nothing: no closure ties a submap of it to an
//! older one. Driven again, a place keeps the submaps of its first pass (and of any pass
//! that found it changed): memory grows with the area, not with the laps.
//!
//! The alternative, not starting submaps while the robot is localized on old ones, has to
//! decide before the submap is seen; here the decision is made on what it saw, and an open
//! submap costs only its own forty scans until then.

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::occupancy_grid::CellState;
use crate::submap_grid::SubmapGrid;

/// Cells around a wall cell searched for an older submap's wall: two submaps of the same
/// wall place it a cell or two apart, by where their beams fell and how they were laid out.
const WALL_REACH_CELLS: i64 = 2;

/// Share of a submap's wall cells that may be new ground while it still repeats the map:
/// a wall's end seen from one step further on, a glimpse through a door that the other
/// passes did not have (a scanner that looks only ahead sees bits of every place on one
/// pass alone). A room or corridor the robot enters shows several times more, and its own
/// submaps, on ground no closure ties, are kept whatever they show. Kept for a few new
/// cells, a submap would also leave the place mapped by a patchwork of passes, and the
/// closures searched there would go to the odd submaps that saw a bit more.
const NEW_WALLS_SHARE: f64 = 0.05;

/// Share of a submap's wall cells that may stand in older free space while it still
/// repeats the map: a place that has not changed shows next to none, a cabinet moved
/// several times this.
const CHANGED_SHARE: f64 = 0.02;

/// A submap may go this share of its nodes without a closure, at either end or between
/// two, and still count as localized all along: closures are searched every few nodes, and
/// not every search finds one.
const UNTIED_SHARE: f64 = 0.25;

/// How a submap's walls (its occupied cells) compare with older submaps'.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Overlap {
    /// Its occupied cells.
    pub walls: usize,
    /// Of those, the ones no older submap has a wall near nor saw free: new ground.
    pub new_walls: usize,
    /// Of those, the ones an older submap saw free, with no older wall near: a change.
    pub changed: usize,
}

impl Overlap {
    /// Compares `grid`, laid out at `world_from_grid`, with `older`, each laid out at its
    /// own pose.
    pub fn of(grid: &SubmapGrid, world_from_grid: &Pose2, older: &[(Pose2, &SubmapGrid)]) -> Self {
        let from_world: Vec<(Pose2, &SubmapGrid)> = overlapping(grid, world_from_grid, older)
            .map(|(pose, g)| (pose.inverse(), g))
            .collect();
        let mut overlap = Self::default();
        for centre in grid.occupied_cells() {
            overlap.walls += 1;
            match seen_by(&from_world, world_from_grid.transform(centre)) {
                Seen::Wall => {}
                Seen::Free => overlap.changed += 1,
                Seen::Nothing => overlap.new_walls += 1,
            }
        }
        overlap
    }

    /// Whether the submap repeats the map: nearly all its walls known, and in their place.
    pub fn repeats(&self) -> bool {
        let walls = self.walls as f64;
        self.walls > 0
            && self.new_walls as f64 <= walls * NEW_WALLS_SHARE
            && self.changed as f64 <= walls * CHANGED_SHARE
    }
}

/// What older submaps say about a wall cell of the new one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Seen {
    /// A wall of theirs within reach.
    Wall,
    /// No wall within reach, and the cell itself free.
    Free,
    /// Neither.
    Nothing,
}

/// What `older` (each with its `grid_from_world`) say about the wall at `world`: a wall
/// within reach in any of them, else free if one saw the cell itself free.
fn seen_by(older: &[(Pose2, &SubmapGrid)], world: Vector2<f64>) -> Seen {
    let mut seen = Seen::Nothing;
    for (grid_from_world, grid) in older {
        let at = grid_from_world.transform(world);
        let cell = grid.resolution();
        for dx in -WALL_REACH_CELLS..=WALL_REACH_CELLS {
            for dy in -WALL_REACH_CELLS..=WALL_REACH_CELLS {
                let p = at + Vector2::new(dx as f64, dy as f64) * cell;
                if grid.state_at(p) == CellState::Occupied {
                    return Seen::Wall;
                }
            }
        }
        if grid.state_at(at) == CellState::Free {
            seen = Seen::Free;
        }
    }
    seen
}

/// The `older` grids whose box, laid out in the world, meets `grid`'s.
fn overlapping<'a>(
    grid: &SubmapGrid,
    world_from_grid: &Pose2,
    older: &'a [(Pose2, &'a SubmapGrid)],
) -> impl Iterator<Item = (Pose2, &'a SubmapGrid)> + 'a {
    let world_box = |pose: &Pose2, g: &SubmapGrid| {
        let corners = g.corners().map(|c| pose.transform(c));
        let lo = corners
            .iter()
            .fold(Vector2::repeat(f64::INFINITY), |a, c| a.inf(c));
        let hi = corners
            .iter()
            .fold(Vector2::repeat(f64::NEG_INFINITY), |a, c| a.sup(c));
        (lo, hi)
    };
    let (lo, hi) = world_box(world_from_grid, grid);
    older
        .iter()
        .filter(move |(pose, g)| {
            let (l, h) = world_box(pose, g);
            l.x <= hi.x && l.y <= hi.y && h.x >= lo.x && h.y >= lo.y
        })
        .copied()
}

/// Whether nodes `first..=last` were tied to the old map all along: no stretch of more
/// than [`UNTIED_SHARE`] of them, at either end or between, without a node of `tied`
/// (ascending; those outside the range are skipped).
pub fn localized_all_along(
    tied: impl IntoIterator<Item = usize>,
    first: usize,
    last: usize,
) -> bool {
    if last < first {
        return false;
    }
    let longest = ((last - first + 1) as f64 * UNTIED_SHARE).floor() as usize;
    let mut previous = None;
    for node in tied
        .into_iter()
        .skip_while(|&n| n < first)
        .take_while(|&n| n <= last)
    {
        let gap = previous.map_or(node - first, |p: usize| node.saturating_sub(p + 1));
        if gap > longest {
            return false;
        }
        previous = Some(node);
    }
    previous.is_some_and(|p| last - p <= longest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compact_scan::CompactScan;
    use crate::occupancy_grid::GridConfig;

    /// The range from `origin` along `bearing` to the first of `walls` (segments), if any
    /// within 20 m.
    fn cast(walls: &[[f64; 4]], origin: Vector2<f64>, bearing: f64) -> f32 {
        let d = Vector2::new(bearing.cos(), bearing.sin());
        let mut nearest = f64::INFINITY;
        for [x0, y0, x1, y1] in walls {
            let a = Vector2::new(*x0, *y0);
            let e = Vector2::new(x1 - x0, y1 - y0);
            let denom = d.x * e.y - d.y * e.x;
            if denom.abs() < 1e-12 {
                continue;
            }
            let w = a - origin;
            let t = (w.x * e.y - w.y * e.x) / denom;
            let s = (w.x * d.y - w.y * d.x) / denom;
            if t > 0.0 && (0.0..=1.0).contains(&s) {
                nearest = nearest.min(t);
            }
        }
        if nearest <= 20.0 {
            nearest as f32
        } else {
            f32::INFINITY
        }
    }

    /// The grid traced from scans of `walls` at `poses` (world frame), in the frame of the
    /// first pose, as a submap keeps it; and that first pose, where the submap lies.
    fn submap(walls: &[[f64; 4]], poses: &[Pose2]) -> (Pose2, SubmapGrid) {
        let config = GridConfig::default();
        let beams = 721;
        let increment = 2.0 * std::f64::consts::PI / beams as f64;
        let scans: Vec<(Pose2, CompactScan)> = poses
            .iter()
            .map(|pose| {
                let ranges: Vec<f32> = (0..beams)
                    .map(|i| cast(walls, pose.position(), pose.yaw + increment * i as f64))
                    .collect();
                let scan = CompactScan::new(
                    0.0,
                    increment,
                    0.1,
                    20.0,
                    &ranges,
                    config.resolution_m,
                    config.no_return_reach_m,
                );
                (poses[0].between(pose), scan)
            })
            .collect();
        let laid: Vec<(Pose2, &CompactScan)> = scans.iter().map(|(p, s)| (*p, s)).collect();
        let grid = SubmapGrid::trace(&config, &laid).unwrap().unwrap();
        (poses[0], grid)
    }

    /// A room of 8 x 6 m with a cabinet, and a door in its east wall to `beyond` (a room of
    /// 6 x 6 m east of it) when asked.
    fn building(cabinet_x: f64, door_open: bool) -> Vec<[f64; 4]> {
        let mut walls = vec![
            [0.0, 0.0, 8.0, 0.0],
            [8.0, 6.0, 0.0, 6.0],
            [0.0, 6.0, 0.0, 0.0],
            // The cabinet, 1 x 0.5 m against the north wall.
            [cabinet_x, 6.0, cabinet_x, 5.5],
            [cabinet_x, 5.5, cabinet_x + 1.0, 5.5],
            [cabinet_x + 1.0, 5.5, cabinet_x + 1.0, 6.0],
            // The room beyond.
            [8.0, 0.0, 14.0, 0.0],
            [14.0, 0.0, 14.0, 6.0],
            [14.0, 6.0, 8.0, 6.0],
        ];
        if door_open {
            walls.extend([[8.0, 0.0, 8.0, 2.0], [8.0, 4.0, 8.0, 6.0]]);
        } else {
            walls.push([8.0, 0.0, 8.0, 6.0]);
        }
        walls
    }

    /// Poses across the west room, `offset` from the first pass's.
    fn pass(offset: Pose2) -> Vec<Pose2> {
        (0..8)
            .map(|k| offset.compose(&Pose2::new(1.5 + 0.6 * k as f64, 3.0, 0.05 * k as f64)))
            .collect()
    }

    #[test]
    fn a_second_pass_over_the_same_room_repeats_the_map() {
        let walls = building(2.0, false);
        let (at, first) = submap(&walls, &pass(Pose2::IDENTITY));
        // The robot comes back along another line, and the graph lays the new submap a
        // couple of centimetres and a few hundredths of a radian off.
        let (again, second) = submap(&walls, &pass(Pose2::new(0.2, -0.4, 0.1)));
        let laid = again.compose(&Pose2::new(0.02, -0.01, 0.003));
        let overlap = Overlap::of(&second, &laid, &[(at, &first)]);
        assert!(overlap.walls > 200, "{overlap:?}");
        assert!(overlap.repeats(), "{overlap:?}");
        // Nothing older: all of it is new.
        let alone = Overlap::of(&second, &laid, &[]);
        assert_eq!(alone.new_walls, alone.walls);
        assert!(!alone.repeats());
    }

    #[test]
    fn a_room_seen_through_a_door_now_open_is_new_ground() {
        let (at, first) = submap(&building(2.0, false), &pass(Pose2::IDENTITY));
        let (again, second) = submap(&building(2.0, true), &pass(Pose2::IDENTITY));
        let overlap = Overlap::of(&second, &again, &[(at, &first)]);
        assert!(!overlap.repeats(), "{overlap:?}");
        assert!(
            overlap.new_walls as f64 > 2.0 * NEW_WALLS_SHARE * overlap.walls as f64,
            "{overlap:?}"
        );
    }

    #[test]
    fn a_moved_cabinet_is_a_change_the_map_keeps() {
        let (at, first) = submap(&building(2.0, false), &pass(Pose2::IDENTITY));
        let (again, second) = submap(&building(5.0, false), &pass(Pose2::IDENTITY));
        let overlap = Overlap::of(&second, &again, &[(at, &first)]);
        assert!(overlap.changed > 0, "{overlap:?}");
        assert!(!overlap.repeats(), "{overlap:?}");
    }

    #[test]
    fn localized_all_along_allows_gaps_of_a_quarter() {
        // Nodes 40..=79: at most 10 in a row without a closure.
        let every_third: Vec<usize> = (40..80).step_by(3).collect();
        assert!(localized_all_along(every_third.iter().copied(), 40, 79));
        // Closures outside the range do not count.
        assert!(!localized_all_along([10, 20, 90], 40, 79));
        // A gap at the start, between, or at the end.
        assert!(!localized_all_along((51..80).collect::<Vec<_>>(), 40, 79));
        assert!(localized_all_along((50..80).collect::<Vec<_>>(), 40, 79));
        assert!(!localized_all_along(
            [40, 45, 57, 60, 65, 70, 75, 79],
            40,
            79
        ));
        assert!(!localized_all_along((40..69).collect::<Vec<_>>(), 40, 79));
        assert!(!localized_all_along([], 40, 79));
    }
}
