//! Submaps: the surface points of a stretch of keyframes, in the frame of the stretch's first
//! node, held rigid once the stretch ends (Cartographer's submaps, as points rather than a
//! probability grid: the front end's own local-map type, so a closure is refined by the same
//! aligner that registers every scan).
//!
//! Submaps overlap by half: every keyframe goes into the two newest, and a submap is finished
//! after twice [`SubmapConfig::keyframes`] of them. A scan anywhere on the path then has a
//! finished submap around it that it did not help build only from the middle of one.
//!
//! The occupancy grid is cut the other way: each scan is owned by the submap that was newest
//! when it came, and traced, in that submap's frame, into that submap's grid once a newer
//! one starts ([`SubmapGrid`]). The submaps' grids then add up to every scan's evidence
//! once, wherever the graph lays them.
//!
//! An open submap keeps its keyframes' points. Finished, it keeps only its points thinned to
//! one per voxel, the free space its beams crossed (a bit per cell) and its grid: a submap
//! costs memory by the area it covers. The search structures over it (the match grid and the
//! local map the aligner needs) are built when a scan is searched for in it, and the caller
//! keeps the few in use.
//!
//! A finished submap that only repeats what older ones hold can be retired
//! ([`Submap::retire`], decided in [`crate::trim`]): it keeps its place in the list and its
//! nodes, which are the graph's, and drops everything else.

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

/// A keyframe as an open submap holds it, shared with the other submap it went into.
#[derive(Debug, Clone)]
struct Keyframe {
    /// The keyframe's pose in the submap frame.
    pose: Pose2,
    points: Arc<[SurfacePoint]>,
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
    grid_config: GridConfig,
    /// While open: its keyframes.
    keyframes: Vec<Keyframe>,
    /// Every keyframe's pose in the submap frame, nodes `anchor..=last_node` in order: where
    /// the submap lies follows from where the graph puts them (none once retired).
    poses: Vec<Pose2>,
    /// The keyframes inserted while it was the newest: the nodes its scans follow.
    owned_nodes: usize,
    /// While it is the newest: the scans it owns, at their poses in the submap frame.
    owned: Vec<(Pose2, CompactScan)>,
    /// Once a newer one started: its owned scans, traced.
    grid: Option<SubmapGrid>,
    sealed: bool,
    /// What a finished submap keeps.
    finished: Option<Finished>,
    /// Retired: finished, and nothing kept.
    retired: bool,
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
            grid_config: config.grid,
            keyframes: Vec::new(),
            poses: Vec::new(),
            owned_nodes: 0,
            owned: Vec::new(),
            grid: None,
            sealed: false,
            finished: None,
            retired: false,
            lo: Vector2::repeat(f64::INFINITY),
            hi: Vector2::repeat(f64::NEG_INFINITY),
        }
    }

    /// Adds a keyframe at its front-end pose.
    fn insert(&mut self, node: usize, odom_from_robot: &Pose2, keyframe: &Keyframe) {
        let submap_from_robot = self.odom_from_submap.between(odom_from_robot);
        if !self.sealed {
            self.owned_nodes += 1;
        }
        for p in keyframe.points.iter() {
            let q = submap_from_robot.transform(p.point);
            self.lo = self.lo.inf(&q);
            self.hi = self.hi.sup(&q);
        }
        self.keyframes.push(Keyframe {
            pose: submap_from_robot,
            ..keyframe.clone()
        });
        self.poses.push(submap_from_robot);
        self.last_node = node;
    }

    /// Takes a scan it owns, at its front-end pose.
    fn own(&mut self, odom_from_robot: &Pose2, beams: CompactScan) {
        self.owned
            .push((self.odom_from_submap.between(odom_from_robot), beams));
    }

    /// A newer submap started: the scans it owns are traced into its grid and go.
    fn seal(&mut self) -> Result<(), GridError> {
        self.grid = self.trace()?;
        self.owned = Vec::new();
        self.sealed = true;
        Ok(())
    }

    /// Ends the submap: its points are thinned as the local map thins them, the newest
    /// point of each voxel kept, and its beams' free space is kept; the keyframes go.
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
        self.keyframes = Vec::new();
        self.finished = Some(Finished {
            points: voxels.into_values().collect(),
            free: coverage.free_space(),
        });
        Ok(())
    }

    /// The occupancy of the scans it owns, traced.
    fn trace(&self) -> Result<Option<SubmapGrid>, GridError> {
        let scans: Vec<(Pose2, &CompactScan)> = self
            .owned
            .iter()
            .map(|(pose, beams)| (*pose, beams))
            .collect();
        SubmapGrid::trace(&self.grid_config, &scans)
    }

    /// The occupancy of the scans it owns, submap frame: a sealed one's as kept, the newest
    /// one's traced now.
    pub fn occupancy(&self) -> Result<Option<std::borrow::Cow<'_, SubmapGrid>>, GridError> {
        Ok(if self.sealed {
            self.grid.as_ref().map(std::borrow::Cow::Borrowed)
        } else {
            self.trace()?.map(std::borrow::Cow::Owned)
        })
    }

    /// A finished, kept submap's occupancy (of the scans it owns).
    pub fn kept_grid(&self) -> Option<&SubmapGrid> {
        self.finished.as_ref().and(self.grid.as_ref())
    }

    /// The submap's pose in the world that best fits where the graph puts the keyframes its
    /// scans follow (`world_from_node`, by node): the mean of their turns, then the
    /// translation that lays their positions on the graph's in the least-squares sense. A
    /// submap's keyframes are rigid in it; placed by its first one alone, the front end's
    /// drift along the submap would pile up at its far end.
    pub fn placed(&self, world_from_node: impl Fn(usize) -> Pose2) -> Pose2 {
        let pairs: Vec<(Pose2, Pose2)> = self
            .poses
            .iter()
            .take(self.owned_nodes.max(1))
            .enumerate()
            .map(|(k, pose)| (*pose, world_from_node(self.anchor + k)))
            .collect();
        Pose2::fit(&pairs).unwrap_or_else(|| world_from_node(self.anchor))
    }

    /// The submap's pose in the world that best fits `world_from_node` (node, its pose) for
    /// some of its keyframes, as [`Self::placed`] fits all; `None` without one of them.
    pub fn fitted(
        &self,
        world_from_node: impl IntoIterator<Item = (usize, Pose2)>,
    ) -> Option<Pose2> {
        let pairs: Vec<(Pose2, Pose2)> = world_from_node
            .into_iter()
            .filter_map(|(node, pose)| {
                let k = node.checked_sub(self.anchor)?;
                self.poses
                    .get(k)
                    .map(|submap_from_node| (*submap_from_node, pose))
            })
            .collect();
        Pose2::fit(&pairs)
    }

    /// Whether no more keyframes go in (retired too).
    pub fn is_finished(&self) -> bool {
        self.finished.is_some() || self.retired
    }

    /// Whether the submap was retired: it is neither searched nor laid out.
    pub fn is_retired(&self) -> bool {
        self.retired
    }

    /// Whether the submap is finished and kept: what closures are searched in and the grid
    /// is laid out from.
    pub fn is_kept(&self) -> bool {
        self.finished.is_some()
    }

    /// Drops a finished submap's contents: its points, free space, occupancy and keyframe
    /// poses. Its nodes stay in the graph; an open submap is left as it is.
    pub fn retire(&mut self) {
        if self.finished.take().is_some() {
            self.poses = Vec::new();
            self.grid = None;
            self.retired = true;
        }
    }

    /// Memory a finished submap's contents hold, bytes (an open one's scans are shared with
    /// its neighbour, and counted by neither).
    pub fn bytes(&self) -> usize {
        self.finished.as_ref().map_or(0, |f| {
            f.points.capacity() * std::mem::size_of::<SurfacePoint>() + f.free.bytes()
        }) + self.grid.as_ref().map_or(0, SubmapGrid::bytes)
            + self.poses.capacity() * std::mem::size_of::<Pose2>()
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
            if let Some(newest) = self.all.last_mut() {
                newest.seal()?;
            }
            self.all
                .push(Submap::new(node, *odom_from_robot, &self.config));
        }
        self.keyframes += 1;
        let keyframe = Keyframe {
            pose: Pose2::IDENTITY,
            points,
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
        self.own(odom_from_robot, beams);
        Ok(finished)
    }

    /// Gives a scan's beams (at its front-end pose) to the newest submap, whose grid they
    /// go into.
    pub fn own(&mut self, odom_from_robot: &Pose2, beams: CompactScan) {
        if let Some(newest) = self.all.last_mut() {
            newest.own(odom_from_robot, beams);
        }
    }

    pub fn get(&self, index: usize) -> Option<&Submap> {
        self.all.get(index)
    }

    /// Retires submap `index` if it is finished ([`Submap::retire`]).
    pub fn retire(&mut self, index: usize) {
        if let Some(submap) = self.all.get_mut(index) {
            submap.retire();
        }
    }

    /// The first node of the oldest open submap: no keyframe before it goes in anywhere.
    pub fn open_from(&self) -> Option<usize> {
        self.all
            .iter()
            .rev()
            .take(2)
            .filter(|s| !s.is_finished())
            .map(|s| s.anchor)
            .min()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_retired_submap_keeps_its_nodes_and_nothing_else() {
        let mut submaps = Submaps::new(SubmapConfig {
            keyframes: 2,
            voxel: 0.05,
            grid: GridConfig::default(),
        });
        let ranges = [2.0_f32; 31];
        let beams = CompactScan::new(-0.5, 1.0 / 30.0, 0.1, 10.0, &ranges, 0.05, 5.0);
        let points: Arc<[SurfacePoint]> = (0..31)
            .map(|i| SurfacePoint {
                point: Vector2::new(2.0, -0.5 + f64::from(i) / 30.0),
                normal: Vector2::new(-1.0, 0.0),
            })
            .collect();
        let mut finished = Vec::new();
        for node in 0..4 {
            let pose = Pose2::new(0.1 * node as f64, 0.0, 0.0);
            finished.extend(
                submaps
                    .insert(node, &pose, Arc::clone(&points), beams.clone())
                    .unwrap(),
            );
        }
        assert_eq!(finished, [0]);
        // Retiring an open submap does nothing.
        submaps.retire(1);
        assert!(!submaps.get(1).unwrap().is_finished());
        assert_eq!(submaps.open_from(), Some(2));
        let submap = submaps.get(0).unwrap();
        assert!(submap.is_kept() && submap.bytes() > 0);
        assert!(submap.occupancy().unwrap().is_some());
        submaps.retire(0);
        let submap = submaps.get(0).unwrap();
        assert!(submap.is_finished() && submap.is_retired() && !submap.is_kept());
        assert_eq!((submap.anchor, submap.last_node), (0, 3));
        assert_eq!(submap.bytes(), 0);
        assert!(submap.occupancy().unwrap().is_none());
        assert!(submap.free_space().is_none() && submap.kept_grid().is_none());
        assert!(submap.search_maps(0.05, 1.0).is_none());
    }

    #[test]
    fn a_submap_is_placed_where_the_graph_puts_its_keyframes() {
        let mut submaps = Submaps::new(SubmapConfig {
            keyframes: 4,
            voxel: 0.05,
            grid: GridConfig::default(),
        });
        let beams = CompactScan::new(0.0, 0.1, 0.1, 10.0, &[], 0.05, 5.0);
        // The front end's keyframes along a curve, starting at (2, 1).
        let front_end: Vec<Pose2> = (0..8)
            .map(|k| {
                Pose2::new(
                    2.0 + 0.5 * k as f64,
                    1.0 + 0.05 * (k * k) as f64,
                    0.1 * k as f64,
                )
            })
            .collect();
        for (node, pose) in front_end.iter().enumerate() {
            submaps
                .insert(node, pose, Vec::new().into(), beams.clone())
                .unwrap();
        }
        let submap = submaps.get(0).unwrap();
        // The graph moved the whole stretch rigidly: the submap moves with it.
        let moved = Pose2::new(-3.0, 4.0, 0.7);
        let world_from_node = |node: usize| moved.compose(&front_end[node]);
        let world_from_odom = moved;
        let expected = world_from_odom.compose(&front_end[0]);
        let placed = submap.placed(world_from_node);
        let error = expected.between(&placed);
        assert!(
            error.translation_norm() < 1e-9 && error.yaw.abs() < 1e-12,
            "{error:?}"
        );
        // The graph bent the stretch: the submap lies between its first and last keyframe's
        // corrections, not on the first's.
        let bent = |node: usize| Pose2::new(0.0, 0.02 * node as f64, 0.0).compose(&front_end[node]);
        let placed = submap.placed(bent);
        let shift = front_end[0].between(&placed);
        assert!(
            placed.y - front_end[0].y > 0.02 && placed.y - front_end[0].y < 0.12,
            "{shift:?}"
        );
    }
}
