//! The local map: the surface points of the last few keyframes in the front end's frame,
//! thinned to one point per voxel, with a grid for exact nearest-neighbour queries and a
//! lookup raster ([`crate::nearest_field`]) that answers the usual ones in one step.

use std::collections::VecDeque;

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::cell_hash::{CellMap, cell_key, floor_i32, pack};
use crate::nearest_field::{Lookup, NearestField, SlabPoint, same_sector};
use crate::points::SurfacePoint;

/// Cells of the neighbour grid are this many voxels wide: a query within the usual gates
/// (a few voxels) looks at one to 2 x 2 cells. A hash lookup costs more than the few extra
/// points a wider cell holds.
const GRID_CELL_VOXELS: f64 = 6.0;

/// Cells of the lookup raster are this many voxels wide: a point's map neighbour is
/// picked as the one nearest the query's cell centre, so the raster's choice differs from
/// the exact one only between points a voxel apart, which lie on one line.
const FIELD_CELL_VOXELS: f64 = 1.0;

/// Map points stamp raster cells this many voxels around them: the raster answers gates
/// up to this less half a cell (the correlative search's widest radius, 6 voxels, and
/// every settled registration gate); wider ones go to the grid.
const FIELD_REACH_VOXELS: f64 = 7.0;

/// Below this cosine between a scan normal and a map normal two points are not on the
/// same surface seen from the same side (60 degrees: any plausible turn between
/// scans, none of a wall's back face).
const MIN_NORMAL_COSINE: f64 = 0.5;

#[derive(Debug, Clone)]
struct Keyframe {
    id: u64,
    pose: Pose2,
    /// Grid cells its points went into, to take them out again.
    cells: Vec<u64>,
}

/// A map point with the voxel it stands for, the keyframe it came from and its place in
/// the slab (which the raster names it by).
#[derive(Debug, Clone, Copy)]
struct Entry {
    voxel: u64,
    keyframe: u64,
    slot: u32,
    point: SurfacePoint,
}

/// A map point found for a query.
#[derive(Debug, Clone, Copy)]
pub struct Neighbour {
    pub point: Vector2<f64>,
    pub normal: Vector2<f64>,
    pub distance_squared: f64,
}

/// Recent keyframes' points in one grid, one point per voxel (the newest keyframe's).
/// Updated in place: a keyframe's points go in and, when it is the oldest of too many,
/// come out again, at a cost proportional to one scan, not to the map.
#[derive(Debug, Clone)]
pub struct LocalMap {
    voxel: f64,
    cell: f64,
    max_keyframes: usize,
    next_id: u64,
    keyframes: VecDeque<Keyframe>,
    cells: CellMap<Vec<Entry>>,
    len: usize,
    /// Every map point by a stable id; dead ones wait in `free` for reuse.
    slab: Vec<SlabPoint>,
    free: Vec<u32>,
    field: NearestField,
}

impl LocalMap {
    pub fn new(voxel: f64, max_keyframes: usize) -> Self {
        Self {
            voxel,
            cell: GRID_CELL_VOXELS * voxel,
            max_keyframes,
            next_id: 0,
            keyframes: VecDeque::new(),
            cells: CellMap::default(),
            len: 0,
            slab: Vec::new(),
            free: Vec::new(),
            field: NearestField::new(FIELD_CELL_VOXELS * voxel, FIELD_REACH_VOXELS * voxel),
        }
    }

    /// A slab place for `point`, alive.
    fn allocate(&mut self, point: SurfacePoint) -> u32 {
        match self.free.pop() {
            Some(id) => {
                let slot = &mut self.slab[id as usize];
                slot.point = point;
                slot.alive = true;
                id
            }
            None => {
                self.slab.push(SlabPoint {
                    point,
                    generation: 0,
                    alive: true,
                });
                (self.slab.len() - 1) as u32
            }
        }
    }

    /// The point leaves the map: raster slots naming it become stale.
    fn kill(&mut self, id: u32) {
        if let Some(slot) = self.slab.get_mut(id as usize) {
            slot.alive = false;
            slot.generation = slot.generation.wrapping_add(1);
            self.free.push(id);
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Points in the map.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Pose of the newest keyframe.
    pub fn last_keyframe(&self) -> Option<Pose2> {
        self.keyframes.back().map(|k| k.pose)
    }

    /// Adds a scan's points (robot frame) seen from `pose`, then drops the oldest keyframe
    /// if there are too many. Where a voxel already has a point, the new one replaces it:
    /// the latest view of a surface was registered with the most context.
    pub fn insert(&mut self, pose: Pose2, scan: &[SurfacePoint]) {
        let id = self.next_id;
        self.next_id += 1;
        let rotation = pose.rotation();
        let mut cells = Vec::with_capacity(scan.len());
        for p in scan {
            let point = SurfacePoint {
                point: pose.transform(p.point),
                normal: rotation * p.normal,
            };
            let voxel = cell_key(point.point.x, point.point.y, self.voxel);
            let cell = cell_key(point.point.x, point.point.y, self.cell);
            let entries = self.cells.entry(cell).or_default();
            let existing = entries.iter_mut().find(|e| e.voxel == voxel);
            match existing {
                Some(existing) if same_sector(&existing.point.normal, &point.normal) => {
                    // The new point takes over the old one's slab place, and with it the
                    // raster cells that named it: they are at most a voxel off, the
                    // raster's resolution, and need no restamping.
                    existing.keyframe = id;
                    existing.point = point;
                    let slot = existing.slot;
                    if let Some(place) = self.slab.get_mut(slot as usize) {
                        place.point = point;
                    }
                    self.field.touch(point.point, id);
                }
                Some(existing) => {
                    // Another surface (the other wall of a corner): its raster cells are
                    // another sector's, so the old point dies and the new one is stamped.
                    let old = existing.slot;
                    let slot = self.allocate(point);
                    if let Some(existing) = self
                        .cells
                        .get_mut(&cell)
                        .and_then(|entries| entries.iter_mut().find(|e| e.voxel == voxel))
                    {
                        *existing = Entry {
                            voxel,
                            keyframe: id,
                            slot,
                            point,
                        };
                    }
                    self.kill(old);
                    self.field.stamp(&self.slab, slot, id);
                }
                None => {
                    let slot = self.allocate(point);
                    if let Some(entries) = self.cells.get_mut(&cell) {
                        entries.push(Entry {
                            voxel,
                            keyframe: id,
                            slot,
                            point,
                        });
                    }
                    self.len += 1;
                    self.field.stamp(&self.slab, slot, id);
                }
            }
            cells.push(cell);
        }
        self.keyframes.push_back(Keyframe { id, pose, cells });
        while self.keyframes.len() > self.max_keyframes {
            if let Some(old) = self.keyframes.pop_front() {
                self.remove(&old);
            }
        }
        if let Some(oldest) = self.keyframes.front() {
            self.field.evict_before(oldest.id);
        }
    }

    fn remove(&mut self, keyframe: &Keyframe) {
        let mut dead = Vec::new();
        for cell in &keyframe.cells {
            if let Some(entries) = self.cells.get_mut(cell) {
                let before = entries.len();
                entries.retain(|e| {
                    let stays = e.keyframe != keyframe.id;
                    if !stays {
                        dead.push(e.slot);
                    }
                    stays
                });
                self.len -= before - entries.len();
                if entries.is_empty() {
                    self.cells.remove(cell);
                }
            }
        }
        for id in dead {
            self.kill(id);
        }
    }

    /// The nearest map point to `query` within `radius` whose normal agrees with `normal`
    /// (the one nearest the query's raster cell centre where the raster reaches that far).
    #[inline]
    pub fn nearest(
        &self,
        query: Vector2<f64>,
        normal: Vector2<f64>,
        radius: f64,
    ) -> Option<Neighbour> {
        if radius <= self.field.max_gate() {
            match self
                .field
                .lookup(&self.slab, query, normal, radius, MIN_NORMAL_COSINE)
            {
                Lookup::Found(id, distance_squared) => {
                    let p = self.slab.get(id as usize)?.point;
                    return Some(Neighbour {
                        point: p.point,
                        normal: p.normal,
                        distance_squared,
                    });
                }
                Lookup::Nothing => return None,
                Lookup::Stale => {}
            }
        }
        self.nearest_exact(query, normal, radius)
    }

    /// Every point of the map, in no particular order.
    pub fn points(&self) -> impl Iterator<Item = &SurfacePoint> + '_ {
        self.cells
            .values()
            .flat_map(|entries| entries.iter().map(|e| &e.point))
    }

    /// Memory held, bytes, about: the raster, the points and their cell entries.
    pub fn bytes(&self) -> usize {
        self.field.bytes()
            + self.slab.len() * std::mem::size_of::<SlabPoint>()
            + self.len * std::mem::size_of::<Entry>()
    }

    /// Raster tiles allocated (for tests of its upkeep).
    pub fn field_tiles(&self) -> usize {
        self.field.tiles()
    }

    /// The nearest map point to `query` within `radius` whose normal agrees with `normal`,
    /// searched through the grid.
    pub fn nearest_exact(
        &self,
        query: Vector2<f64>,
        normal: Vector2<f64>,
        radius: f64,
    ) -> Option<Neighbour> {
        let r2 = radius * radius;
        let x0 = floor_i32((query.x - radius) / self.cell);
        let x1 = floor_i32((query.x + radius) / self.cell);
        let y0 = floor_i32((query.y - radius) / self.cell);
        let y1 = floor_i32((query.y + radius) / self.cell);
        let mut best: Option<Neighbour> = None;
        for ix in x0..=x1 {
            for iy in y0..=y1 {
                let Some(entries) = self.cells.get(&pack(ix, iy)) else {
                    continue;
                };
                for e in entries {
                    let p = &e.point;
                    let d2 = (p.point - query).norm_squared();
                    if d2 > r2 || best.is_some_and(|b| b.distance_squared <= d2) {
                        continue;
                    }
                    if p.normal.dot(&normal) < MIN_NORMAL_COSINE {
                        continue;
                    }
                    best = Some(Neighbour {
                        point: p.point,
                        normal: p.normal,
                        distance_squared: d2,
                    });
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall_point(x: f64) -> SurfacePoint {
        SurfacePoint {
            point: Vector2::new(x, 1.0),
            normal: Vector2::new(0.0, -1.0),
        }
    }

    #[test]
    fn finds_the_nearest_compatible_point_and_forgets_old_keyframes() {
        let mut map = LocalMap::new(0.05, 2);
        let scan: Vec<SurfacePoint> = (0..40)
            .map(|i| wall_point(f64::from(i) * 0.1 + 0.025))
            .collect();
        map.insert(Pose2::IDENTITY, &scan);
        let tiles = map.field_tiles();
        assert!(tiles > 0);
        let hit = map
            .nearest(Vector2::new(0.52, 0.9), Vector2::new(0.0, -1.0), 0.2)
            .unwrap();
        assert!((hit.point - Vector2::new(0.525, 1.0)).norm() < 1e-9);
        // The back face of the wall is not the same surface.
        assert!(
            map.nearest(Vector2::new(0.52, 1.1), Vector2::new(0.0, 1.0), 0.2)
                .is_none()
        );
        assert!(
            map.nearest(Vector2::new(0.52, 1.5), Vector2::new(0.0, -1.0), 0.2)
                .is_none()
        );
        map.insert(Pose2::new(10.0, 0.0, 0.0), &scan);
        map.insert(Pose2::new(20.0, 0.0, 0.0), &scan);
        assert!(
            map.nearest(Vector2::new(0.52, 0.9), Vector2::new(0.0, -1.0), 0.2)
                .is_none()
        );
        assert_eq!(map.len(), 80);
        // The raster's tiles around the first keyframe went with it.
        assert!(
            map.field_tiles() < 2 * tiles + tiles / 2,
            "{}",
            map.field_tiles()
        );
        assert_eq!(map.last_keyframe(), Some(Pose2::new(20.0, 0.0, 0.0)));
    }

    /// The walls of a 6 x 4 m room with a 1 m pillar (both faces of its walls), as points
    /// every `spacing` with normals into the room (out of the pillar).
    fn room_points(spacing: f64) -> Vec<SurfacePoint> {
        let mut points = Vec::new();
        let mut wall = |a: (f64, f64), b: (f64, f64), normal: (f64, f64)| {
            let length = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
            let n = (length / spacing) as usize;
            for i in 0..n {
                let t = (i as f64 + 0.5) / n as f64;
                points.push(SurfacePoint {
                    point: Vector2::new(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)),
                    normal: Vector2::new(normal.0, normal.1),
                });
            }
        };
        wall((-3.0, -2.0), (3.0, -2.0), (0.0, 1.0));
        wall((3.0, -2.0), (3.0, 2.0), (-1.0, 0.0));
        wall((3.0, 2.0), (-3.0, 2.0), (0.0, -1.0));
        wall((-3.0, 2.0), (-3.0, -2.0), (1.0, 0.0));
        wall((0.0, 0.0), (1.0, 0.0), (0.0, -1.0));
        wall((1.0, 0.0), (1.0, 1.0), (1.0, 0.0));
        wall((1.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        wall((0.0, 1.0), (0.0, 0.0), (-1.0, 0.0));
        points
    }

    #[test]
    fn the_raster_finds_the_exact_searchs_line_within_its_resolution() {
        let voxel = 0.05;
        let mut map = LocalMap::new(voxel, 2);
        let room = room_points(0.02);
        // Three views: the second replaces most of the first's voxels, the third pushes
        // the first out, so stale and reused slab places are both exercised.
        for shift in [0.0, 0.013, 0.031] {
            let pose = Pose2::new(shift, -0.5 * shift, 0.0);
            let seen: Vec<SurfacePoint> = room
                .iter()
                .map(|p| SurfacePoint {
                    point: pose.inverse().transform(p.point),
                    normal: p.normal,
                })
                .collect();
            map.insert(pose, &seen);
        }
        let gate = 0.2;
        let mut state = 12345_u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut compared, mut other_line) = (0, 0);
        for _ in 0..5000 {
            // Near a wall, facing roughly as it does: where registration asks.
            let near = room[(uniform() * room.len() as f64) as usize % room.len()];
            let query = near.point + Vector2::new(0.5 * uniform() - 0.25, 0.5 * uniform() - 0.25);
            let turn = 2.4 * uniform() - 1.2;
            let normal = Pose2::new(0.0, 0.0, turn).rotation() * near.normal;
            let exact = map.nearest_exact(query, normal, gate);
            let fast = map.nearest(query, normal, gate);
            match (exact, fast) {
                (Some(e), Some(f)) => {
                    compared += 1;
                    // Nearest to the query's cell centre rather than to the query, from a
                    // point up to a voxel from where it was stamped.
                    let slack = 3.0 * std::f64::consts::SQRT_2 * voxel;
                    assert!(
                        f.distance_squared.sqrt() <= e.distance_squared.sqrt() + slack,
                        "{query:?}: {f:?} vs {e:?}"
                    );
                    assert!(f.normal.dot(&normal) >= MIN_NORMAL_COSINE);
                    let residual = |n: &Neighbour| n.normal.dot(&(query - n.point));
                    if (residual(&f) - residual(&e)).abs() > 1e-3 {
                        other_line += 1;
                    }
                }
                (None, None) => {}
                (Some(e), None) => assert!(
                    e.distance_squared.sqrt() > gate - 0.1,
                    "{query:?} {normal:?} {e:?} {:?}",
                    map.field
                        .lookup(&map.slab, query, normal, gate, MIN_NORMAL_COSINE)
                ),
                (None, Some(f)) => assert!(f.distance_squared.sqrt() <= gate),
            }
        }
        assert!(compared > 1000, "{compared}");
        // Only near corners may the two pick different walls.
        assert!(other_line * 50 < compared, "{other_line} of {compared}");
        assert!(map.field_tiles() > 0);
    }
}
