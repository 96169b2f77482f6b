//! Global SLAM over the front end's output: every keyframe becomes a node of the pose graph
//! and goes into the submaps; each new node is checked against the finished submaps its
//! predicted pose lies in ([`crate::closure::verify`]), and a closure the scans confirm is
//! added to the graph. A closure that disagrees with the graph waits for a second to
//! confirm it; confirmed, both go in and the graph is solved at once: the next nodes'
//! searches start from its poses. A closure the graph already agrees with changes little
//! and waits for the next solve (or the last, at the end). A scan between keyframes
//! follows its keyframe rigidly, by the front end's motion since; its beams go into the
//! grid of the newest submap when the robot moved a cell or turned a little since the last
//! scan that did.
//!
//! The search window is as wide as the drift the front end can have built up since the graph
//! was last tied to an old place: a share of the path driven since the last closure (and a
//! floor for the front end's own noise), so a robot that keeps seeing its old map searches
//! narrow windows, cheaply, and one back from a long loop searches wide.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

use nalgebra::Matrix3;
use scan_match::points::SurfacePoint;
use slam_geom::{Pose2, ScanGeometry};

use crate::branch_bound::SearchWindow;
use crate::closure::{ClosureCheck, Refusal, verify};
use crate::compact_scan::CompactScan;
use crate::confirmation::{Confirmations, Tie};
use crate::global_grid;
use crate::occupancy_grid::{GridConfig, GridError, OccupancyGrid};
use crate::pose_graph::{PoseGraph, PoseGraphError};
use crate::submap::{SearchMaps, SubmapConfig, Submaps};
use crate::submap_grid::SubmapGrid;
use crate::trim::{Overlap, localized_all_along};

/// Memory the search maps of the submaps searched last may hold, bytes: those around the
/// robot are searched again and again, and a submap of a large hall costs megabytes.
const SEARCH_MAPS_BYTES: usize = 48 << 20;

/// Nodes between two searches in one submap: neighbouring nodes see the same, and a
/// closure every few nodes holds the path as well as one at each.
const ATTEMPT_GAP: usize = 3;

/// Submaps a node is checked against at most: those whose middle it is nearest.
const MAX_CANDIDATES: usize = 2;

/// A scan's beams go into the grid when the robot turned this much since the last scan
/// that did (or moved a cell): turning by it moves a wall 2.5 m away by a cell of 5 cm. A
/// scan from (nearly) the same viewpoint only adds certainty the log-odds clamp would cap,
/// so a robot standing still costs neither memory nor tracing.
pub const GRID_TURN_RAD: f64 = 0.02;

/// A scan's ranges and how its beams were cast.
#[derive(Debug, Clone, Copy)]
pub struct ScanRanges<'a> {
    pub geometry: &'a ScanGeometry,
    pub ranges: &'a [f32],
}

/// Why the back end could not go on.
#[derive(Debug, thiserror::Error)]
pub enum GlobalError {
    #[error(transparent)]
    PoseGraph(#[from] PoseGraphError),
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// The back end's settings.
#[derive(Debug, Clone, Copy)]
pub struct GlobalConfig {
    pub submaps: SubmapConfig,
    pub closure: ClosureCheck,
    /// Cells of the match grid, metres.
    pub resolution: f64,
    /// Smallest search window: the front end's own error over a submap, metres...
    pub min_window_m: f64,
    /// ...and radians.
    pub min_window_rad: f64,
    /// Drift of the front end per metre driven: the window's growth, metres per metre...
    pub drift_m_per_m: f64,
    /// ...and radians per metre.
    pub drift_rad_per_m: f64,
    /// A scan becomes a node once the robot moved this far from the last node, metres...
    pub node_distance_m: f64,
    /// ...or turned this much, radians.
    pub node_angle_rad: f64,
    /// Widest window, metres and radians.
    pub max_window_m: f64,
    pub max_window_rad: f64,
}

impl GlobalConfig {
    /// The defaults, with the front end's voxel, noise and registration.
    pub fn for_front_end(front_end: &scan_match::FrontEndConfig) -> Self {
        Self {
            submaps: SubmapConfig {
                keyframes: 20,
                voxel: front_end.voxel_size,
                grid: GridConfig::default(),
            },
            closure: ClosureCheck {
                min_agreement: 0.8,
                min_overlap: 0.4,
                radius: 2.0 * front_end.voxel_size,
                registration: scan_match::registration::RegistrationParams {
                    range_sigma: front_end.range_sigma,
                    voxel: front_end.voxel_size,
                    weak_steps: false,
                },
            },
            resolution: front_end.voxel_size,
            node_distance_m: front_end.keyframe_distance,
            node_angle_rad: front_end.keyframe_angle,
            min_window_m: 0.3,
            min_window_rad: 0.05,
            drift_m_per_m: 0.05,
            drift_rad_per_m: 0.005,
            max_window_m: 4.0,
            max_window_rad: 0.5,
        }
    }
}

impl GlobalConfig {
    /// How far, in metres and radians, the front end can have drifted over `path_m` of path
    /// (its own error over a submap at least).
    pub fn drift_over(&self, path_m: f64) -> (f64, f64) {
        (
            self.min_window_m + self.drift_m_per_m * path_m,
            self.min_window_rad + self.drift_rad_per_m * path_m,
        )
    }
}

/// One scan's place on the path: the node it follows and where it is from there.
#[derive(Debug, Clone, Copy)]
struct ScanPlace {
    stamp_ns: u64,
    node: usize,
    node_from_robot: Pose2,
}

/// Counts over a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GlobalStats {
    pub nodes: usize,
    pub submaps: usize,
    pub attempts: usize,
    pub closures: usize,
    /// Verified closures that moved the graph, held until another confirmed them (each
    /// counted once when held; confirmed ones count in `closures` too).
    pub held: usize,
    pub no_match: usize,
    pub unexplained: usize,
    pub contradicted: usize,
    pub ambiguous: usize,
    pub unconstrained: usize,
    pub optimizations: usize,
    pub grids_built: usize,
    /// Submaps retired because they repeated older ones ([`crate::trim`]).
    pub retired: usize,
}

/// The back end's state over a run.
pub struct GlobalSlam {
    config: GlobalConfig,
    graph: PoseGraph,
    submaps: Submaps,
    /// Search maps of the submaps searched last, the latest first.
    search_maps: VecDeque<(usize, SearchMaps)>,
    /// The most memory one submap's search maps took, bytes: room made before a build.
    largest_search_maps: usize,
    /// The node each submap was last searched for.
    last_attempt: Vec<Option<usize>>,
    scans: Vec<ScanPlace>,
    /// The front end's pose of the last node.
    odom_from_node: Pose2,
    /// The front end's pose of the last scan whose beams went into the grid.
    odom_from_traced: Option<Pose2>,
    /// The front end's motion since the last node, and its covariance in the node's frame.
    pending: Pose2,
    pending_covariance: Matrix3<f64>,
    /// Path driven, metres: in all, and at each node.
    travelled_m: f64,
    node_travelled_m: Vec<f64>,
    /// Per submap, the path driven when a closure last tied the robot to it.
    tied_at_m: Vec<f64>,
    /// The nodes a closure tied to an older submap (the submap, and where the node is in
    /// it), from the oldest open submap's first on: whether a submap was localized all
    /// along, and where, is judged on them when it finishes.
    tied_nodes: BTreeMap<usize, (usize, Pose2)>,
    /// Jumps waiting for confirmation.
    held: Confirmations,
    stats: GlobalStats,
}

impl GlobalSlam {
    pub fn new(config: GlobalConfig) -> Result<Self, PoseGraphError> {
        Ok(Self {
            config,
            graph: PoseGraph::new(Pose2::IDENTITY)?,
            submaps: Submaps::new(config.submaps),
            search_maps: VecDeque::new(),
            largest_search_maps: 0,
            last_attempt: Vec::new(),
            scans: Vec::new(),
            odom_from_node: Pose2::IDENTITY,
            odom_from_traced: None,
            pending: Pose2::IDENTITY,
            pending_covariance: Matrix3::zeros(),
            travelled_m: 0.0,
            node_travelled_m: Vec::new(),
            tied_at_m: Vec::new(),
            tied_nodes: BTreeMap::new(),
            held: Confirmations::default(),
            stats: GlobalStats::default(),
        })
    }

    /// Whether the scan at `odom_from_robot` (the front end's pose) is wanted, as a node or
    /// for the grid: [`Self::add_scan`] takes its ranges then, and only then needs them.
    pub fn wants_scan(&self, odom_from_robot: &Pose2) -> bool {
        self.wants_node(odom_from_robot) || self.wants_beams(odom_from_robot)
    }

    /// Whether the scan becomes a node, and so needs its points: the first scan, and any the
    /// robot reached by moving or turning enough since the last node (the front end's
    /// keyframe rule).
    fn wants_node(&self, odom_from_robot: &Pose2) -> bool {
        if self.scans.is_empty() {
            return true;
        }
        let moved = self.odom_from_node.between(odom_from_robot);
        moved.translation_norm() >= self.config.node_distance_m
            || moved.yaw.abs() >= self.config.node_angle_rad
    }

    /// Whether the scan's beams go into the grid ([`GRID_TURN_RAD`]).
    fn wants_beams(&self, odom_from_robot: &Pose2) -> bool {
        self.odom_from_traced.is_none_or(|last| {
            let moved = last.between(odom_from_robot);
            moved.translation_norm() >= self.config.submaps.grid.resolution_m
                || moved.yaw.abs() >= GRID_TURN_RAD
        })
    }

    /// A scan's beams, as the grids keep them.
    fn beams(&self, scan: &ScanRanges) -> CompactScan {
        let grid = &self.config.submaps.grid;
        let geometry = scan.geometry;
        CompactScan::new(
            geometry.angle_min,
            geometry.angle_increment,
            geometry.range_min,
            geometry.range_max,
            scan.ranges,
            grid.resolution_m,
            grid.no_return_reach_m,
        )
    }

    /// A node's points, the ones closures are judged on (the front end's, robot frame).
    fn points(&self, scan: &ScanRanges) -> Arc<[SurfacePoint]> {
        scan_match::points::extract(
            scan.geometry,
            scan.ranges,
            self.config.closure.registration.range_sigma,
            self.config.submaps.voxel,
        )
        .points
        .into()
    }

    /// Adds one scan: its front-end pose, the increment since the last scan and its
    /// covariance, and its ranges when [`Self::wants_scan`] (`None` for one it does not want,
    /// or one lost on the way: a node waits for the next).
    pub fn add_scan(
        &mut self,
        stamp_ns: u64,
        odom_from_robot: &Pose2,
        increment: &Pose2,
        increment_covariance: &Matrix3<f64>,
        scan: Option<ScanRanges>,
    ) -> Result<(), GlobalError> {
        let node_wanted = self.wants_node(odom_from_robot);
        let beams_wanted = self.wants_beams(odom_from_robot);
        let first = self.scans.is_empty();
        if first {
            // The first scan is node 0, the graph's origin.
            self.odom_from_node = *odom_from_robot;
            self.record(stamp_ns, 0, Pose2::IDENTITY);
        } else {
            // The pending motion grows by the increment: the old part's error swings the
            // increment's offset, the increment's own error is in the last scan's frame.
            let a = self.pending.mount_jacobian(increment);
            let b = self.pending.frame_jacobian();
            self.pending_covariance = a * self.pending_covariance * a.transpose()
                + b * increment_covariance * b.transpose();
            self.pending = self.pending.compose(increment);
            self.travelled_m += increment.translation_norm();
        }
        match scan {
            Some(scan) if first => {
                let points = self.points(&scan);
                self.insert(0, odom_from_robot, points, self.beams(&scan))?;
                self.odom_from_traced = Some(*odom_from_robot);
            }
            Some(scan) if node_wanted => {
                let node = self.add_node(stamp_ns, odom_from_robot)?;
                let points = self.points(&scan);
                self.insert(
                    node,
                    odom_from_robot,
                    Arc::clone(&points),
                    self.beams(&scan),
                )?;
                self.odom_from_traced = Some(*odom_from_robot);
                self.close_loops(node, &points)?;
            }
            scan => {
                if !first {
                    self.follow(stamp_ns);
                }
                if let Some(scan) = scan
                    && beams_wanted
                {
                    self.submaps.own(odom_from_robot, self.beams(&scan));
                    self.odom_from_traced = Some(*odom_from_robot);
                }
            }
        }
        Ok(())
    }

    /// A scan that is not a node follows the last node by the motion since.
    fn follow(&mut self, stamp_ns: u64) {
        let node = self.graph.node_count() - 1;
        self.record(stamp_ns, node, self.pending);
    }

    /// The graph's next node, where the front end's motion since the last one puts it.
    fn add_node(&mut self, stamp_ns: u64, odom_from_robot: &Pose2) -> Result<usize, GlobalError> {
        let information = information_of(&self.pending_covariance);
        let node = self.graph.add_node(self.pending, information)?;
        self.pending = Pose2::IDENTITY;
        self.pending_covariance = Matrix3::zeros();
        self.odom_from_node = *odom_from_robot;
        self.record(stamp_ns, node, Pose2::IDENTITY);
        Ok(node)
    }

    fn record(&mut self, stamp_ns: u64, node: usize, node_from_robot: Pose2) {
        self.scans.push(ScanPlace {
            stamp_ns,
            node,
            node_from_robot,
        });
    }

    fn insert(
        &mut self,
        node: usize,
        odom_from_robot: &Pose2,
        points: Arc<[SurfacePoint]>,
        beams: CompactScan,
    ) -> Result<(), GridError> {
        self.stats.nodes += 1;
        self.node_travelled_m.resize(node + 1, self.travelled_m);
        if let Some(finished) = self.submaps.insert(node, odom_from_robot, points, beams)? {
            self.trim(finished);
            if let Some(first) = self.submaps.open_from() {
                self.tied_nodes = self.tied_nodes.split_off(&first);
            }
        }
        self.stats.submaps = self.submaps.len();
        Ok(())
    }

    /// Retires submap `index`, just finished, if it repeats the map: its nodes were tied to
    /// older submaps all along, and those know its walls ([`crate::trim`]). It is laid
    /// over them where its closures put its nodes, not where the graph has them: closures
    /// the graph already agrees with wait for the next solve, and the front end's drift
    /// since the last would show as walls out of place.
    fn trim(&mut self, index: usize) {
        let Some(submap) = self.submaps.get(index) else {
            return;
        };
        let tied: Vec<(usize, usize, Pose2)> = self
            .tied_nodes
            .range(submap.anchor..=submap.last_node)
            .map(|(&node, &(older, seen))| (node, older, seen))
            .collect();
        let localized =
            localized_all_along(tied.iter().map(|t| t.0), submap.anchor, submap.last_node);
        let Some(grid) = submap.kept_grid().filter(|_| localized) else {
            return;
        };
        let world_from_node = |node: usize| self.graph.pose(node);
        let older: Vec<(usize, Pose2, &SubmapGrid)> = self
            .submaps
            .iter()
            .filter(|(i, _)| *i != index)
            .filter_map(|(i, s)| s.kept_grid().map(|g| (i, s.placed(world_from_node), g)))
            .collect();
        // Where each closure puts its node: the older submap as laid out, and the node
        // where the scan matched in it.
        let implied = tied.iter().filter_map(|&(node, of, seen)| {
            let at = older.iter().find(|o| o.0 == of)?;
            Some((node, at.1.compose(&seen)))
        });
        let Some(world_from_submap) = submap.fitted(implied) else {
            return;
        };
        let laid: Vec<(Pose2, &SubmapGrid)> = older.iter().map(|o| (o.1, o.2)).collect();
        let overlap = Overlap::of(grid, &world_from_submap, &laid);
        if overlap.repeats() {
            self.submaps.retire(index);
            self.search_maps.retain(|(i, _)| *i != index);
            self.stats.retired += 1;
        }
    }

    /// Searches the finished submaps the node may be in; adds what the scans confirm.
    fn close_loops(&mut self, node: usize, points: &[SurfacePoint]) -> Result<(), PoseGraphError> {
        let recent = 2 * self.config.submaps.keyframes;
        let graph = &self.graph;
        let world_from_node = graph.pose(node);
        let mut candidates: Vec<(f64, usize, Pose2, SearchWindow)> = self
            .submaps
            .iter()
            .filter(|(index, s)| {
                s.is_kept()
                    && s.last_node + recent < node
                    && self
                        .last_attempt
                        .get(*index)
                        .copied()
                        .flatten()
                        .is_none_or(|last| last + ATTEMPT_GAP <= node)
            })
            .filter_map(|(index, s)| {
                let seed = graph.pose(s.anchor).between(&world_from_node);
                let window = self.window(index, s.last_node);
                let off_centre = (seed.position() - s.centre()).norm();
                s.covers(seed.position(), window.translation)
                    .then_some((off_centre, index, seed, window))
            })
            .collect();
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
        candidates.truncate(MAX_CANDIDATES);
        let mut moved = false;
        for (_, index, seed, window) in candidates {
            self.stats.attempts += 1;
            if self.last_attempt.len() <= index {
                self.last_attempt.resize(index + 1, None);
            }
            self.last_attempt[index] = Some(node);
            self.cache_search_maps(index);
            let cached = self.search_maps.front().filter(|(i, _)| *i == index);
            let (Some(submap), Some((_, maps))) = (self.submaps.get(index), cached) else {
                continue;
            };
            let Some(free) = submap.free_space() else {
                continue;
            };
            let answer = verify(maps, free, points, &seed, window, &self.config.closure);
            match answer {
                Ok(closure) => {
                    let innovation = seed.between(&closure.submap_from_robot);
                    let tie = Tie {
                        node,
                        submap: index,
                        anchor: submap.anchor,
                        seen: closure.submap_from_robot,
                        information: closure.information,
                        at_m: self.travelled_m,
                    };
                    let agrees = innovation.translation_norm() <= 0.5 * self.config.min_window_m
                        && innovation.yaw.abs() <= 0.5 * self.config.min_window_rad;
                    if agrees {
                        // A closure the graph already agrees with can wait for the next
                        // solve.
                        self.add_closure(&tie)?;
                    } else {
                        moved |= self.offer_jump(tie)?;
                    }
                    // One closure ties the node; a second to the next submap adds little.
                    break;
                }
                Err(Refusal::NoMatch) => self.stats.no_match += 1,
                Err(Refusal::Unexplained(_)) => self.stats.unexplained += 1,
                Err(Refusal::Contradicted(_)) => self.stats.contradicted += 1,
                Err(Refusal::Ambiguous) => self.stats.ambiguous += 1,
                Err(Refusal::Unconstrained) => self.stats.unconstrained += 1,
            }
        }
        if moved {
            self.solve()?;
        }
        Ok(())
    }

    fn solve(&mut self) -> Result<(), PoseGraphError> {
        self.graph.optimize()?;
        self.stats.optimizations += 1;
        Ok(())
    }

    /// Adds a closure to the graph; the submap is tied to the robot from here.
    fn add_closure(&mut self, tie: &Tie) -> Result<(), PoseGraphError> {
        self.graph
            .add_closure(tie.anchor, tie.node, tie.seen, tie.information)?;
        self.stats.closures += 1;
        self.tied_nodes.insert(tie.node, (tie.submap, tie.seen));
        if self.tied_at_m.len() <= tie.submap {
            self.tied_at_m.resize(tie.submap + 1, f64::NAN);
        }
        self.tied_at_m[tie.submap] = self.travelled_m;
        Ok(())
    }

    /// A closure that would move the graph waits for another to confirm it; confirmed,
    /// they go in together and the graph must be solved at once (returns true).
    fn offer_jump(&mut self, tie: Tie) -> Result<bool, PoseGraphError> {
        let config = self.config;
        let confirmed = self
            .held
            .offer(tie, &self.graph, |apart_m| config.drift_over(apart_m));
        if confirmed.is_empty() {
            self.stats.held += 1;
            return Ok(false);
        }
        for tie in &confirmed {
            self.add_closure(tie)?;
        }
        Ok(true)
    }

    /// The search window for submap `index`: the drift the front end can have built up over
    /// the path since the graph last tied the robot to it (or since it was made).
    fn window(&self, index: usize, last_node: usize) -> SearchWindow {
        let c = &self.config;
        let tied = self
            .tied_at_m
            .get(index)
            .copied()
            .filter(|m| m.is_finite())
            .unwrap_or_else(|| self.node_travelled_m.get(last_node).copied().unwrap_or(0.0));
        let (metres, radians) = c.drift_over((self.travelled_m - tied).max(0.0));
        SearchWindow {
            translation: metres.min(c.max_window_m),
            yaw: radians.min(c.max_window_rad),
        }
    }

    /// Puts the search maps of submap `index` first in the cache, built on first use and
    /// kept while they are recent. Room for them is made before they are built, as much as
    /// the largest built so far takes: the cache then stays within its budget while they
    /// are built, and they take the memory the evicted maps freed, of the same shapes,
    /// before anything else is put there (built first, the cache would reach for new memory
    /// at every miss, and leave the evicted maps' as holes).
    fn cache_search_maps(&mut self, index: usize) {
        if let Some(at) = self.search_maps.iter().position(|(i, _)| *i == index) {
            if let Some(entry) = self.search_maps.remove(at) {
                self.search_maps.push_front(entry);
            }
            return;
        }
        let Some(submap) = self.submaps.get(index) else {
            return;
        };
        let room = SEARCH_MAPS_BYTES.saturating_sub(self.largest_search_maps);
        let mut kept = 0;
        let within = self
            .search_maps
            .iter()
            .take_while(|(_, maps)| {
                kept += maps.bytes();
                kept <= room
            })
            .count();
        self.search_maps.truncate(within);
        if let Some(maps) = submap.search_maps(self.config.resolution, self.config.max_window_m) {
            self.stats.grids_built += 1;
            self.largest_search_maps = self.largest_search_maps.max(maps.bytes());
            self.search_maps.push_front((index, maps));
        }
    }

    /// Solves the graph once more with everything in it.
    pub fn finish(&mut self) -> Result<(), PoseGraphError> {
        self.solve()
    }

    /// The occupancy grid of every submap at its pose on the graph as it stands; `None`
    /// before any beam.
    pub fn grid(&self) -> Result<Option<OccupancyGrid>, GridError> {
        let mut grids = Vec::with_capacity(self.submaps.len());
        for (_, submap) in self.submaps.iter() {
            if let Some(grid) = submap.occupancy()? {
                grids.push((submap.placed(|node| self.graph.pose(node)), grid));
            }
        }
        let laid: Vec<(Pose2, &dyn global_grid::Layer)> = grids
            .iter()
            .map(|(p, g)| (*p, g.as_ref() as &dyn global_grid::Layer))
            .collect();
        global_grid::render(&laid, self.config.submaps.grid.resolution_m)
    }

    /// Every scan's pose on the solved graph, with its stamp.
    pub fn path(&self) -> Vec<(u64, Pose2)> {
        self.scans
            .iter()
            .map(|s| {
                (
                    s.stamp_ns,
                    self.graph.pose(s.node).compose(&s.node_from_robot),
                )
            })
            .collect()
    }

    pub fn stats(&self) -> GlobalStats {
        self.stats
    }
}

/// The information of a step's covariance, with a floor on each variance so that a step
/// the front end reports as exact (a robot standing still) cannot make the graph singular.
fn information_of(covariance: &Matrix3<f64>) -> Matrix3<f64> {
    let floored = covariance + Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-8, 1e-8, 1e-10));
    let symmetric = 0.5 * (floored + floored.transpose());
    symmetric
        .try_inverse()
        .map(|m| 0.5 * (m + m.transpose()))
        .unwrap_or_else(|| Matrix3::identity() * 1e8)
}
