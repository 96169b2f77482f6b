//! Submaps: the surface points of a stretch of keyframes, in the frame of the stretch's first
//! node, held rigid once the stretch ends (Cartographer's submaps, as points rather than a
//! probability grid: the front end's own local-map type, so a closure is refined by the same
//! aligner that registers every scan).
//!
//! Submaps overlap by half: every keyframe goes into the two newest, and a submap is finished
//! after twice [`SubmapConfig::keyframes`] of them. A scan anywhere on the path then has a
//! finished submap around it that it did not help build only from the middle of one.
//!
//! An open submap keeps its keyframes' scans. Finished, it keeps only its points thinned to
//! one per voxel and the free space its beams crossed, a bit per cell: a submap costs
//! memory by the area it covers. The search structures over it (the match grid and the
//! local map the aligner needs) are built when a scan is searched for in it, and the caller
//! keeps the few in use.

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::Vector2;
use scan_match::local_map::LocalMap;
use scan_match::points::SurfacePoint;
use slam_geom::Pose2;

use crate::branch_bound::MatchGrid;
use crate::compact_scan::CompactScan;
use crate::coverage::{Coverage, FreeSpace};
use crate::occupancy_grid::{GridConfig, GridError};
use crate::submap_grid::SubmapGrid;

/// How submaps are cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubmapConfig {
    /// A new submap starts every this many keyframes; each holds twice as many.
    pub keyframes: usize,
    /// Voxel the points are thinned to, metres (the front end's).
    pub voxel: f64,
    /// How each submap's occupancy is traced.
    pub grid: GridConfig,
}

/// A node's scan: its surface points (robot frame) for closures, its beams for the grid.
#[derive(Debug, Clone)]
pub struct NodeScan {
    pub points: Vec<SurfacePoint>,
    pub beams: CompactScan,
}

/// A keyframe as an open submap holds it, shared with the other submap it went into.
#[derive(Debug, Clone)]
struct Keyframe {
    /// The keyframe's pose in the submap frame.
    pose: Pose2,
    points: Arc<[SurfacePoint]>,
    beams: Arc<CompactScan>,
}

/// One submap.
#[derive(Debug)]
pub struct Submap {
    /// The node whose pose is the submap's frame.
    pub anchor: usize,
    /// The last node inserted.
    pub last_node: usize,
    /// The submap frame's pose in the front end's frame, when it was started.
    odom_from_submap: Pose2,
    voxel: f64,
    grid: GridConfig,
    /// While open: its keyframes.
    keyframes: Vec<Keyframe>,
    /// What a finished submap keeps.
    finished: Option<Finished>,
    /// Lowest and highest point, submap frame.
    lo: Vector2<f64>,
    hi: Vector2<f64>,
}

/// A finished submap's contents.
#[derive(Debug)]
struct Finished {
    /// The points thinned to one per voxel (the newest), submap frame.
    points: Vec<SurfacePoint>,
    free: FreeSpace,
    /// Its occupancy; `None` when no beam was left to trace.
    grid: Option<SubmapGrid>,
}

/// What a scan is searched for and registered against in one submap.
#[derive(Debug)]
pub struct SearchMaps {
    pub grid: MatchGrid,
    pub map: LocalMap,
}

impl SearchMaps {
    /// Memory held, bytes (the local map's about).
    pub fn bytes(&self) -> usize {
        self.grid.bytes() + self.map.bytes()
    }
}

impl Submap {
    fn new(anchor: usize, odom_from_submap: Pose2, config: &SubmapConfig) -> Self {
        Self {
            anchor,
            last_node: anchor,
            odom_from_submap,
            voxel: config.voxel,
            grid: config.grid,
            keyframes: Vec::new(),
            finished: None,
            lo: Vector2::repeat(f64::INFINITY),
            hi: Vector2::repeat(f64::NEG_INFINITY),
        }
    }

    /// Adds a keyframe at its front-end pose.
    fn insert(&mut self, node: usize, odom_from_robot: &Pose2, keyframe: &Keyframe) {
        let submap_from_robot = self.odom_from_submap.between(odom_from_robot);
        for p in keyframe.points.iter() {
            let q = submap_from_robot.transform(p.point);
            self.lo = self.lo.inf(&q);
            self.hi = self.hi.sup(&q);
        }
        self.keyframes.push(Keyframe {
            pose: submap_from_robot,
            ..keyframe.clone()
        });
        self.last_node = node;
    }

    /// Ends the submap: its points are thinned as the local map thins them, the newest
    /// point of each voxel kept, and its beams' free space is kept; the scans go.
    fn finish(&mut self) -> Result<(), GridError> {
        let mut voxels = HashMap::new();
        let mut coverage = Coverage::new(2.0 * self.voxel);
        for Keyframe { pose, points, .. } in &self.keyframes {
            let rotation = pose.rotation();
            for p in points.iter() {
                let q = pose.transform(p.point);
                coverage.add_beam(pose.position(), q);
                let voxel = (
                    (q.x / self.voxel).floor() as i32,
                    (q.y / self.voxel).floor() as i32,
                );
                let normal = rotation * p.normal;
                voxels.insert(voxel, SurfacePoint { point: q, normal });
            }
        }
        let grid = self.trace()?;
        self.keyframes = Vec::new();
        self.finished = Some(Finished {
            points: voxels.into_values().collect(),
            free: coverage.free_space(),
            grid,
        });
        Ok(())
    }

    /// The occupancy of an open submap's keyframes, traced.
    fn trace(&self) -> Result<Option<SubmapGrid>, GridError> {
        let scans: Vec<(Pose2, &CompactScan)> = self
            .keyframes
            .iter()
            .map(|k| (k.pose, k.beams.as_ref()))
            .collect();
        SubmapGrid::trace(&self.grid, &scans)
    }

    /// The submap's occupancy, submap frame: a finished one's as kept, an open one's traced
    /// now.
    pub fn occupancy(&self) -> Result<Option<std::borrow::Cow<'_, SubmapGrid>>, GridError> {
        Ok(match &self.finished {
            Some(finished) => finished.grid.as_ref().map(std::borrow::Cow::Borrowed),
            None => self.trace()?.map(std::borrow::Cow::Owned),
        })
    }

    /// Whether no more keyframes go in.
    pub fn is_finished(&self) -> bool {
        self.finished.is_some()
    }

    /// Where a finished submap's beams passed freely.
    pub fn free_space(&self) -> Option<&FreeSpace> {
        self.finished.as_ref().map(|f| &f.free)
    }

    /// The match grid and the local map over a finished submap's points.
    pub fn search_maps(&self, resolution: f64, max_window: f64) -> Option<SearchMaps> {
        let finished = self.finished.as_ref()?;
        let positions: Vec<Vector2<f64>> = finished.points.iter().map(|p| p.point).collect();
        let mut map = LocalMap::new(self.voxel, usize::MAX);
        map.insert(Pose2::IDENTITY, &finished.points);
        Some(SearchMaps {
            grid: MatchGrid::new(&positions, resolution, max_window),
            map,
        })
    }

    /// Whether `point` (submap frame) lies within `margin` of the submap's points' box.
    pub fn covers(&self, point: Vector2<f64>, margin: f64) -> bool {
        point.x >= self.lo.x - margin
            && point.y >= self.lo.y - margin
            && point.x <= self.hi.x + margin
            && point.y <= self.hi.y + margin
    }

    /// The centre of the submap's points' box, submap frame.
    pub fn centre(&self) -> Vector2<f64> {
        (self.lo + self.hi) / 2.0
    }
}

/// Every submap of a run, the newest two open.
#[derive(Debug)]
pub struct Submaps {
    config: SubmapConfig,
    all: Vec<Submap>,
    keyframes: usize,
}

impl Submaps {
    pub fn new(config: SubmapConfig) -> Self {
        Self {
            config,
            all: Vec::new(),
            keyframes: 0,
        }
    }

    /// Inserts keyframe `node` (front-end pose, its points and beams); returns the index of
    /// a submap it finished, if any.
    pub fn insert(
        &mut self,
        node: usize,
        odom_from_robot: &Pose2,
        points: Arc<[SurfacePoint]>,
        beams: CompactScan,
    ) -> Result<Option<usize>, GridError> {
        let per = self.config.keyframes.max(1);
        if self.keyframes.is_multiple_of(per) {
            self.all
                .push(Submap::new(node, *odom_from_robot, &self.config));
        }
        self.keyframes += 1;
        let keyframe = Keyframe {
            pose: Pose2::IDENTITY,
            points,
            beams: Arc::new(beams),
        };
        let mut finished = None;
        for (index, submap) in self.all.iter_mut().enumerate().rev().take(2) {
            if submap.is_finished() {
                continue;
            }
            submap.insert(node, odom_from_robot, &keyframe);
            if submap.keyframes.len() >= 2 * per {
                submap.finish()?;
                finished = Some(index);
            }
        }
        Ok(finished)
    }

    pub fn get(&self, index: usize) -> Option<&Submap> {
        self.all.get(index)
    }

    pub fn len(&self) -> usize {
        self.all.len()
    }

    pub fn is_empty(&self) -> bool {
        self.all.is_empty()
    }

    pub fn iter(&self) -> impl Iterator<Item = (usize, &Submap)> + '_ {
        self.all.iter().enumerate()
    }
}
