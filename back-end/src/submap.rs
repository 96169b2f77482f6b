//! Submaps: the surface points of a stretch of keyframes, in the frame of the stretch's first
//! node, held rigid once the stretch ends (Cartographer's submaps, as points rather than a
//! probability grid: the front end's own local-map type, so a closure is refined by the same
//! aligner that registers every scan).
//!
//! Submaps overlap by half: every keyframe goes into the two newest, and a submap is finished
//! after twice [`SubmapConfig::keyframes`] of them. A scan anywhere on the path then has a
//! finished submap around it that it did not help build only from the middle of one.

use nalgebra::Vector2;
use scan_match::local_map::LocalMap;
use scan_match::points::SurfacePoint;
use slam_geom::Pose2;

use crate::branch_bound::MatchGrid;
use crate::coverage::Coverage;

/// How submaps are cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubmapConfig {
    /// A new submap starts every this many keyframes; each holds twice as many.
    pub keyframes: usize,
    /// Voxel the points are thinned to, metres (the front end's).
    pub voxel: f64,
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
    inserted: usize,
    finished: bool,
    map: LocalMap,
    coverage: Coverage,
    /// Lowest and highest point, submap frame.
    lo: Vector2<f64>,
    hi: Vector2<f64>,
}

impl Submap {
    fn new(anchor: usize, odom_from_submap: Pose2, voxel: f64) -> Self {
        Self {
            anchor,
            last_node: anchor,
            odom_from_submap,
            inserted: 0,
            finished: false,
            map: LocalMap::new(voxel, usize::MAX),
            coverage: Coverage::new(2.0 * voxel),
            lo: Vector2::repeat(f64::INFINITY),
            hi: Vector2::repeat(f64::NEG_INFINITY),
        }
    }

    /// Adds a keyframe's points (robot frame) at its front-end pose.
    fn insert(&mut self, node: usize, odom_from_robot: &Pose2, scan: &[SurfacePoint]) {
        let submap_from_robot = self.odom_from_submap.between(odom_from_robot);
        let origin = submap_from_robot.position();
        for p in scan {
            let q = submap_from_robot.transform(p.point);
            self.lo = self.lo.inf(&q);
            self.hi = self.hi.sup(&q);
            self.coverage.add_beam(origin, q);
        }
        self.map.insert(submap_from_robot, scan);
        self.last_node = node;
        self.inserted += 1;
    }

    /// Whether no more keyframes go in.
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// The points, for matching and registration.
    pub fn map(&self) -> &LocalMap {
        &self.map
    }

    /// Where the submap's beams went.
    pub fn coverage(&self) -> &Coverage {
        &self.coverage
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

    /// The match grid over the submap's points.
    pub fn match_grid(&self, resolution: f64, max_window: f64) -> MatchGrid {
        let points: Vec<Vector2<f64>> = self.map.points().map(|p| p.point).collect();
        MatchGrid::new(&points, resolution, max_window)
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

    /// Inserts keyframe `node` (front-end pose, robot-frame points); returns the index of
    /// a submap it finished, if any.
    pub fn insert(
        &mut self,
        node: usize,
        odom_from_robot: &Pose2,
        scan: &[SurfacePoint],
    ) -> Option<usize> {
        let per = self.config.keyframes.max(1);
        if self.keyframes.is_multiple_of(per) {
            self.all
                .push(Submap::new(node, *odom_from_robot, self.config.voxel));
        }
        self.keyframes += 1;
        let mut finished = None;
        for (index, submap) in self.all.iter_mut().enumerate().rev().take(2) {
            if submap.finished {
                continue;
            }
            submap.insert(node, odom_from_robot, scan);
            if submap.inserted >= 2 * per {
                submap.finished = true;
                finished = Some(index);
            }
        }
        finished
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
