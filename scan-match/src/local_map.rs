//! The local map: the surface points of the last few keyframes in the front end's frame,
//! thinned to one point per voxel, with a grid for nearest-neighbour queries.

use std::collections::VecDeque;

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::cell_hash::{CellMap, cell_key, pack};
use crate::points::SurfacePoint;

/// Cells of the neighbour grid are this many voxels wide: a query within the usual gates
/// (a few voxels) looks at one to 2 x 2 cells. A hash lookup costs more than the few extra
/// points a wider cell holds (measured: 2, 4, 6 and 8 voxels; 6 was fastest on both logs).
const GRID_CELL_VOXELS: f64 = 6.0;

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

/// A map point with the voxel it stands for and the keyframe it came from.
#[derive(Debug, Clone, Copy)]
struct Entry {
    voxel: u64,
    keyframe: u64,
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
            let entry = Entry {
                voxel: cell_key(point.point.x, point.point.y, self.voxel),
                keyframe: id,
                point,
            };
            let cell = cell_key(point.point.x, point.point.y, self.cell);
            let entries = self.cells.entry(cell).or_default();
            match entries.iter_mut().find(|e| e.voxel == entry.voxel) {
                Some(existing) => *existing = entry,
                None => {
                    entries.push(entry);
                    self.len += 1;
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
    }

    fn remove(&mut self, keyframe: &Keyframe) {
        for cell in &keyframe.cells {
            if let Some(entries) = self.cells.get_mut(cell) {
                let before = entries.len();
                entries.retain(|e| e.keyframe != keyframe.id);
                self.len -= before - entries.len();
                if entries.is_empty() {
                    self.cells.remove(cell);
                }
            }
        }
    }

    /// The nearest map point to `query` within `radius` whose normal agrees with `normal`.
    pub fn nearest(
        &self,
        query: Vector2<f64>,
        normal: Vector2<f64>,
        radius: f64,
    ) -> Option<Neighbour> {
        let r2 = radius * radius;
        let x0 = ((query.x - radius) / self.cell).floor() as i32;
        let x1 = ((query.x + radius) / self.cell).floor() as i32;
        let y0 = ((query.y - radius) / self.cell).floor() as i32;
        let y1 = ((query.y + radius) / self.cell).floor() as i32;
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
        assert_eq!(map.last_keyframe(), Some(Pose2::new(20.0, 0.0, 0.0)));
    }
}
