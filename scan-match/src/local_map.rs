//! The local map: the surface points of the last few keyframes in the front end's frame,
//! thinned to one point per voxel, with a grid for nearest-neighbour queries.

use std::collections::VecDeque;

use nalgebra::Vector2;
use slam_geom::Pose2;

use crate::cell_hash::{CellMap, CellSet, cell_key, pack};
use crate::points::SurfacePoint;

/// Cells of the neighbour grid are this many voxels wide: a query within the usual gates
/// (a few voxels) looks at 2 x 2 to 3 x 3 cells of a few points each.
const GRID_CELL_VOXELS: f64 = 4.0;

/// Below this cosine between a scan normal and a map normal two points are not on the
/// same surface seen from the same side (60 degrees: any plausible turn between
/// scans, none of a wall's back face).
const MIN_NORMAL_COSINE: f64 = 0.5;

#[derive(Debug, Clone)]
struct Keyframe {
    pose: Pose2,
    points: Vec<SurfacePoint>,
}

/// A map point found for a query.
#[derive(Debug, Clone, Copy)]
pub struct Neighbour {
    pub point: Vector2<f64>,
    pub normal: Vector2<f64>,
    pub distance_squared: f64,
}

/// Recent keyframes and the merged, thinned point set built from them.
#[derive(Debug, Clone)]
pub struct LocalMap {
    voxel: f64,
    cell: f64,
    max_keyframes: usize,
    keyframes: VecDeque<Keyframe>,
    /// Merged points, sorted by grid cell.
    points: Vec<SurfacePoint>,
    /// Grid cell -> range of `points`.
    cells: CellMap<(u32, u32)>,
}

impl LocalMap {
    pub fn new(voxel: f64, max_keyframes: usize) -> Self {
        Self {
            voxel,
            cell: GRID_CELL_VOXELS * voxel,
            max_keyframes,
            keyframes: VecDeque::new(),
            points: Vec::new(),
            cells: CellMap::default(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Points in the merged map.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Pose of the newest keyframe.
    pub fn last_keyframe(&self) -> Option<Pose2> {
        self.keyframes.back().map(|k| k.pose)
    }

    /// Adds a scan's points (robot frame) seen from `pose`, drops the oldest keyframe if
    /// there are too many, and rebuilds the merged set (a few thousand points: cheaper
    /// than keeping a removable index, and done only at keyframes).
    pub fn insert(&mut self, pose: Pose2, scan: &[SurfacePoint]) {
        let rotation = pose.rotation();
        let points = scan
            .iter()
            .map(|p| SurfacePoint {
                point: pose.transform(p.point),
                normal: rotation * p.normal,
            })
            .collect();
        self.keyframes.push_back(Keyframe { pose, points });
        while self.keyframes.len() > self.max_keyframes {
            self.keyframes.pop_front();
        }
        self.rebuild();
    }

    fn rebuild(&mut self) {
        // Newest first: where keyframes overlap, the latest view of a surface wins, since
        // it was registered with the most context.
        let mut taken = CellSet::default();
        let mut merged: Vec<(u64, SurfacePoint)> = Vec::new();
        for keyframe in self.keyframes.iter().rev() {
            for p in &keyframe.points {
                if taken.insert(cell_key(p.point.x, p.point.y, self.voxel)) {
                    merged.push((cell_key(p.point.x, p.point.y, self.cell), *p));
                }
            }
        }
        merged.sort_unstable_by_key(|(key, _)| *key);
        self.cells.clear();
        self.points.clear();
        let mut start = 0;
        while start < merged.len() {
            let key = merged[start].0;
            let mut end = start;
            while end < merged.len() && merged[end].0 == key {
                end += 1;
            }
            self.cells.insert(key, (start as u32, end as u32));
            start = end;
        }
        self.points.extend(merged.into_iter().map(|(_, p)| p));
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
                let Some(&(start, end)) = self.cells.get(&pack(ix, iy)) else {
                    continue;
                };
                for p in &self.points[start as usize..end as usize] {
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
        let scan: Vec<SurfacePoint> = (0..40).map(|i| wall_point(f64::from(i) * 0.05)).collect();
        map.insert(Pose2::IDENTITY, &scan);
        let hit = map
            .nearest(Vector2::new(0.52, 0.9), Vector2::new(0.0, -1.0), 0.2)
            .unwrap();
        assert!((hit.point - Vector2::new(0.5, 1.0)).norm() < 1e-9);
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
