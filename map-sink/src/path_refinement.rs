//! The final path refined against its own map.
//!
//! The filter's path is right from step to step, but where a loop closed late, or not at
//! all, a stretch of it comes back some decimetres and a few degrees off the part of the
//! map it revisits, and its scans draw a second wall beside the first. Each pass traces the
//! grid from the path, aligns every kept scan to the walls that the *other passes* drew
//! ([`align_scan`]; a scan's own pass is the path within `own_pass_m` of it, whose returns
//! would only hold it to its own second wall), and re-solves the path from its own steps
//! and those alignments ([`solve_pose_chain`]), each a link from the stretch of path that
//! drew the walls (see [`ScanTie`]), so a stretch and the walls the rest of the run saw
//! move towards each other while each step stays close to what the filter measured. A wall
//! piece is matched only by a return seen from its side: the far face of a wall that
//! another pass saw from the next room is not where this scan's return ended. The next
//! pass traces the grid again from the moved path.
//!
//! The last passes (`every_wall_passes`) align every scan to every wall, its own pass's
//! too: the grid the map is saved with, which a localizer on the saved map follows. After
//! the passes before them the walls are drawn once where the run saw them more than once,
//! and what is left between a scan and that grid is the path's own inconsistency along a
//! corridor, where scans that see the far end from afar and from nearby draw it apart;
//! aligned to the whole grid the saved path is where the saved grid puts its scans, and a
//! second such pass aligns them again to the grid the first one's path traces.
//!
//! Mapping on a saved map, its walls are one more pass, never a scan's own
//! ([`crate::prior_grid`]): the grid is traced on top of the saved one, and the scans that
//! see the saved walls again are aligned to them too, so the run's path holds to the map it
//! extends and a wall both saw is drawn once (office, a short run on a saved map: every
//! occupied cell within 0.1 m of a wall, 98.2 % without).

use std::collections::HashMap;

use nalgebra::Matrix3;
use rayon::prelude::*;
use slam_geom::{Pose2, StampedPose};

use crate::pose_chain::{PoseLink, PosePrior, solve_pose_chain};
use crate::prior_grid::saved_walls;
use crate::scan_alignment::{
    ScanAlignment, ScanAlignmentConfig, WeakDirections, align_scan, information_by_tag,
};
use crate::wall_field::{CellWindow, SeenReturn, WallField};
use back_end::compact_scan::{Beam, CompactScan};
use back_end::occupancy_grid::{GridConfig, GridError, OccupancyGrid};

/// How the final path is refined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathRefinementConfig {
    /// Passes of trace, align and solve; 0 leaves the path as the filter gave it.
    pub passes: usize,
    /// How many of the last passes align each scan to every wall, its own pass's too,
    /// rather than to the other passes': at most all but the first pass.
    pub every_wall_passes: usize,
    /// How far the filter's steps may bend: the variance of a step's translation along its
    /// direction of travel per metre it travelled, m^2/m ... Proportional to the motion, so
    /// that a path bends as much over a metre at any scan rate.
    pub step_along_variance_per_m: f64,
    /// ... and across it, m^2/m, in the passes to the other passes' walls: less, because
    /// scans fix a step across a corridor firmly, while along it they see little but door
    /// frames at a glance and the filter's steps there may be off by more, so that is
    /// where a loop closed late is taken out. The passes to every wall hold the steps as
    /// firmly across as along: they draw the path onto the grid it traces, across too.
    pub step_across_variance_per_m: f64,
    /// In the passes to every wall, how far a step may also bend per radian it turned,
    /// m^2/rad, in every direction: a scan taken mid-turn is the one the filter's step is
    /// least sure of (its fit can land a few centimetres off, and the next scan's takes it
    /// back), and there the grid every pass drew says better where it was. Not in the
    /// passes to the other passes' walls, where a step bent at a turn would bend the loop
    /// being closed.
    pub every_wall_step_xy_variance_per_rad: f64,
    /// The variance of a step's turn per metre travelled, rad^2/m.
    pub step_yaw_variance_per_m: f64,
    /// The variance of a step's turn per radian turned, rad^2/rad.
    pub step_yaw_variance_per_rad: f64,
    /// How far along the path a scan's own pass reaches, metres: a scan is aligned to the
    /// walls the scans farther than this along the path drew (and some of those up to half
    /// as far again), the other passes, not to the second wall its own pass drew beside
    /// theirs. 0 aligns it to every scan's walls.
    pub own_pass_m: f64,
    /// A scan of another pass is a revisit when the path from a block to it is at least
    /// this much longer than the straight line between them, metres: the robot went away
    /// and came back, rather than looking along the way it was going. A block whose other
    /// passes hold no revisit is aligned along the directions their walls fix firmly only.
    pub revisit_detour_m: f64,
    /// When a scan's alignment is trusted.
    pub alignment: ScanAlignmentConfig,
}

impl Default for PathRefinementConfig {
    fn default() -> Self {
        Self {
            passes: 8,
            every_wall_passes: 1,
            step_along_variance_per_m: 0.01,
            step_across_variance_per_m: 0.001,
            every_wall_step_xy_variance_per_rad: 0.2,
            step_yaw_variance_per_m: 0.002,
            step_yaw_variance_per_rad: 0.002,
            own_pass_m: 6.0,
            revisit_detour_m: 6.0,
            alignment: ScanAlignmentConfig::default(),
        }
    }
}

/// The information that holds the path's first pose where it is, in a pass whose ties do
/// not fix the run's frame: far above any step's or alignment's.
const HELD_START_INFORMATION: f64 = 1e9;

/// The smallest variance of a step (m^2, rad^2): a stopped robot's step is firm, but a
/// variance of zero would make the solve singular.
const MIN_STEP_VARIANCE: f64 = 1e-8;

/// What refining did, for the run's log.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RefinementReport {
    /// Scans aligned (and trusted) in each pass done, of `scans` on the path.
    pub aligned_per_pass: Vec<usize>,
    /// True when time ran out before every pass asked for was done: the path is the one
    /// after the passes in `aligned_per_pass`, the pass under way abandoned.
    pub cut_short: bool,
    pub scans: usize,
    /// The farthest any pose moved from the filter's path, metres.
    pub largest_move_m: f64,
}

/// Refines `path` against the grid its scans trace (`scans` by stamp; a scan the path does
/// not hold is left out), on top of `prior` (a saved map's grid, from
/// [`crate::prior_grid`], at `grid`'s resolution) when the run maps on one. Returns the
/// refined path, the same length and stamps, and what was done. A pass whose alignments
/// cannot fix the path leaves it as it was.
pub fn refine_path(
    path: &[StampedPose],
    scans: &[(u64, &CompactScan)],
    grid: &GridConfig,
    config: &PathRefinementConfig,
    prior: Option<&OccupancyGrid>,
) -> Result<(Vec<StampedPose>, RefinementReport), GridError> {
    refine_path_within(path, scans, grid, config, prior, &|| true)
}

/// [`refine_path`] for as long as `has_time` says there is time: it is asked before each
/// pass and between the blocks of a pass, and once it says no, the pass under way is
/// abandoned and the path after the passes done returned (the report says it was cut
/// short). Whether it is cut short depends on the clock; what each pass does does not.
pub fn refine_path_within(
    path: &[StampedPose],
    scans: &[(u64, &CompactScan)],
    grid: &GridConfig,
    config: &PathRefinementConfig,
    prior: Option<&OccupancyGrid>,
    has_time: &(dyn Fn() -> bool + Sync),
) -> Result<(Vec<StampedPose>, RefinementReport), GridError> {
    let saved = prior.map(saved_walls).unwrap_or_default();
    let index: HashMap<u64, usize> = path
        .iter()
        .enumerate()
        .map(|(i, p)| (p.stamp_ns, i))
        .collect();
    let on_path: Vec<(usize, &CompactScan, Vec<[f64; 2]>)> = scans
        .iter()
        .filter_map(|(stamp, scan)| Some((*index.get(stamp)?, *scan, returns(scan))))
        .collect();
    let filter_poses: Vec<Pose2> = path.iter().map(|p| p.pose).collect();
    let steps: Vec<Pose2> = filter_poses
        .windows(2)
        .map(|w| w[0].between(&w[1]))
        .collect();
    let mut report = RefinementReport {
        scans: on_path.len(),
        ..RefinementReport::default()
    };
    let mut poses = filter_poses.clone();
    let travelled = distance_travelled(&filter_poses, &on_path);
    let loop_step_information: Vec<Matrix3<f64>> = steps
        .iter()
        .map(|step| step_information(step, config, StepHold::to_other_passes(config)))
        .collect();
    let grid_step_information: Vec<Matrix3<f64>> = steps
        .iter()
        .map(|step| step_information(step, config, StepHold::to_every_wall(config)))
        .collect();
    // A pass whose alignments could not move the path leaves every later pass of its kind
    // the same path to align: only the other kind can still change it.
    let mut settled: Option<bool> = None;
    let first_to_every_wall = config.passes
        - config
            .every_wall_passes
            .min(config.passes.saturating_sub(1));
    for pass in 0..config.passes {
        let to_every_wall = config.own_pass_m <= 0.0 || pass >= first_to_every_wall;
        if settled == Some(to_every_wall) {
            continue;
        }
        if !has_time() {
            report.cut_short = true;
            break;
        }
        let traced: Vec<(Pose2, &CompactScan)> = on_path
            .iter()
            .map(|(i, scan, _)| (poses[*i], *scan))
            .collect();
        let Some(grid) = OccupancyGrid::build_on(grid, prior, &traced)? else {
            break;
        };
        let world_ends: Vec<Vec<SeenReturn>> = on_path
            .iter()
            .map(|(i, _, ends)| {
                let pose = poses[*i];
                let from = pose.position().into();
                ends.iter()
                    .map(|&[x, y]| SeenReturn {
                        at: pose.transform([x, y].into()).into(),
                        from,
                    })
                    .collect()
            })
            .collect();
        let pass_scans = PassScans {
            sensor_ends: on_path.iter().map(|(_, _, ends)| ends.as_slice()).collect(),
            world_ends,
            guesses: on_path.iter().map(|(i, _, _)| poses[*i]).collect(),
        };
        let alignments = if to_every_wall {
            align_to_every_wall(&grid, &pass_scans, &config.alignment, &saved, has_time)
        } else {
            align_to_other_passes(&grid, &pass_scans, &travelled, config, &saved, has_time)
        };
        let alignments = match alignments {
            Aligned::Scans(alignments) => alignments,
            Aligned::NoWalls => break,
            Aligned::OutOfTime => {
                report.cut_short = true;
                break;
            }
        };
        report
            .aligned_per_pass
            .push(alignments.iter().filter(|a| a.is_some()).count());
        let mut priors = Vec::new();
        let mut links = Vec::new();
        for (k, tie) in alignments.into_iter().enumerate() {
            let Some(tie) = tie else { continue };
            let index = on_path[k].0;
            if let Some(information) = tie.prior {
                priors.push(PosePrior {
                    index,
                    pose: tie.aligned,
                    information,
                });
            }
            for (anchor, information) in tie.links {
                let anchor_pose = pass_scans.guesses[anchor];
                links.push(PoseLink {
                    from: on_path[anchor].0,
                    to: index,
                    seen: anchor_pose.between(&tie.aligned),
                    information: in_frame_of(&anchor_pose, &information),
                });
            }
        }
        // Links say only where scans are seen from one another, not where the path lies:
        // unless a saved map's walls hold it, the pass holds its first pose where it is.
        if !links.is_empty() && (prior.is_none() || priors.is_empty()) {
            priors.push(PosePrior {
                index: 0,
                pose: poses[0],
                information: Matrix3::identity() * HELD_START_INFORMATION,
            });
        }
        let step_information = if to_every_wall {
            &grid_step_information
        } else {
            &loop_step_information
        };
        match solve_pose_chain(&poses, &steps, step_information, &priors, &links) {
            Some(solved) => poses = solved,
            None => settled = Some(to_every_wall),
        }
    }
    // The solve is free to move the whole path; the run's frame is where it started (the
    // origin, or `--initial-pose` on a saved map), so without a saved map's walls to hold it
    // the refined path is put back to start where the filter's did. A run that later maps
    // on this map then starts at the origin of the frame its walls and corners are in.
    if prior.is_none()
        && let (Some(start), Some(refined_start)) =
            (filter_poses.first().copied(), poses.first().copied())
        && start != refined_start
    {
        let back = start.compose(&refined_start.inverse());
        for pose in &mut poses {
            *pose = back.compose(pose);
        }
        // Exactly, not to within rounding.
        poses[0] = start;
    }
    report.largest_move_m = poses
        .iter()
        .zip(&filter_poses)
        .map(|(a, b)| (a.position() - b.position()).norm())
        .fold(0.0, f64::max);
    let refined = path
        .iter()
        .zip(poses)
        .map(|(p, pose)| StampedPose {
            stamp_ns: p.stamp_ns,
            pose,
        })
        .collect();
    Ok((refined, report))
}

/// For each scan on the path, how far the path has gone when it is taken, metres.
fn distance_travelled(
    poses: &[Pose2],
    on_path: &[(usize, &CompactScan, Vec<[f64; 2]>)],
) -> Vec<f64> {
    let mut travelled = Vec::with_capacity(poses.len());
    let mut length = 0.0;
    for (k, pose) in poses.iter().enumerate() {
        if k > 0 {
            length += (pose.position() - poses[k - 1].position()).norm();
        }
        travelled.push(length);
    }
    on_path.iter().map(|(i, _, _)| travelled[*i]).collect()
}

/// Side of the tiles the returns are indexed by, metres.
const TILE_M: f64 = 1.0;

/// The most returns a block's wall field is built from (before its own pass's are left
/// out), so that the cost of a pass grows with the path's length, not with the square of
/// the times it went round.
const MAX_OTHER_RETURNS: usize = 200_000;

/// What aligning a pass's scans came to.
enum Aligned {
    /// Each scan's alignment, `None` where it is not trusted.
    Scans(Vec<Option<ScanTie>>),
    /// The grid holds no wall to align to.
    NoWalls,
    /// `has_time` said no before the pass was done.
    OutOfTime,
}

/// How one scan's alignment ties the path: the pose it was aligned to, held by links from
/// the scans whose walls it was aligned to, each with the information those walls give it,
/// and by a prior for the information a saved map's walls give it (or, aligned to every
/// wall or along the fixed directions only, by a prior alone). The walls another stretch
/// of the path drew are where that stretch put them: a prior would hold the scan to them
/// as if that stretch were right, and move it with that stretch's error; a link holds it
/// where it is seen from that stretch, so that the two move until they agree.
#[derive(Debug, Clone, PartialEq)]
struct ScanTie {
    aligned: Pose2,
    prior: Option<Matrix3<f64>>,
    /// The scans (by index among those on the path) that anchor the links, each with the
    /// information the walls drawn around it give.
    links: Vec<(usize, Matrix3<f64>)>,
}

impl ScanTie {
    /// An alignment held as a prior alone.
    fn prior(alignment: ScanAlignment) -> Self {
        Self {
            aligned: alignment.pose,
            prior: Some(alignment.information),
            links: Vec::new(),
        }
    }
}

/// Scans aligned to every wall per parallel task; the stop clock is asked before each
/// task, so a pass is abandoned at most one task's work after time runs out.
const EVERY_WALL_SCANS_PER_TASK: usize = 32;

/// Aligns each scan (`sensor_ends` from `guesses`; `world_ends` the returns placed at the
/// guesses) to every wall, its own pass's too: one field of every return, which costs as
/// much as the returns, however often the robot went round.
fn align_to_every_wall(
    grid: &OccupancyGrid,
    scans: &PassScans<'_>,
    config: &ScanAlignmentConfig,
    saved: &[SeenReturn],
    has_time: &(dyn Fn() -> bool + Sync),
) -> Aligned {
    let every: Vec<SeenReturn> = scans
        .world_ends
        .iter()
        .flatten()
        .chain(saved)
        .copied()
        .collect();
    let Some(walls) = WallField::new(
        grid,
        &every,
        config.inlier_distance_m,
        config.coarse_distance_m,
    ) else {
        return Aligned::NoWalls;
    };
    let tasks: Option<Vec<Vec<Option<ScanTie>>>> = scans
        .sensor_ends
        .par_chunks(EVERY_WALL_SCANS_PER_TASK)
        .zip(scans.guesses.par_chunks(EVERY_WALL_SCANS_PER_TASK))
        .map(|(ends, guesses)| {
            if !has_time() {
                return None;
            }
            Some(
                ends.iter()
                    .zip(guesses)
                    .map(|(ends, guess)| {
                        align_scan(&walls, ends, *guess, config, WeakDirections::Follow)
                            .map(ScanTie::prior)
                    })
                    .collect(),
            )
        })
        .collect();
    match tasks {
        Some(tasks) => Aligned::Scans(tasks.concat()),
        None => Aligned::OutOfTime,
    }
}

/// Aligns each scan (`sensor_ends` from `guesses`; `world_ends` the returns placed at the
/// guesses) to the walls that the scans of other passes drew, block by block of the path;
/// out of time when `has_time` said no before a block.
fn align_to_other_passes(
    grid: &OccupancyGrid,
    scans: &PassScans<'_>,
    travelled: &[f64],
    refinement: &PathRefinementConfig,
    saved: &[SeenReturn],
    has_time: &(dyn Fn() -> bool + Sync),
) -> Aligned {
    let config = &refinement.alignment;
    let world_ends = &scans.world_ends;
    // Scan and return indices, as u32: the index holds every return of the run.
    let mut tiles: HashMap<(i64, i64), Vec<(u32, u32)>> = HashMap::new();
    for (k, ends) in world_ends.iter().enumerate() {
        for (j, &p) in ends.iter().enumerate() {
            tiles
                .entry(tile(p.at))
                .or_default()
                .push((k as u32, j as u32));
        }
    }
    for (j, p) in saved.iter().enumerate() {
        tiles.entry(tile(p.at)).or_default().push((SAVED, j as u32));
    }
    // Blocks of half a pass: a scan's own pass is its block and the two on either side,
    // every scan less than `own_pass_m` along the path from it and some a little farther.
    let block_m = refinement.own_pass_m / 2.0;
    let block_of: Vec<usize> = travelled
        .iter()
        .map(|t| (t / block_m).floor() as usize)
        .collect();
    let count = block_of.iter().max().map_or(0, |b| b + 1);
    let mut blocks: Vec<Vec<usize>> = vec![Vec::new(); count];
    for (k, &block) in block_of.iter().enumerate() {
        blocks[block].push(k);
    }
    let pass = OtherPasses {
        grid,
        scans,
        tiles: &tiles,
        blocks: &blocks,
        block_of: &block_of,
        travelled,
        revisit_detour_m: refinement.revisit_detour_m,
        saved,
        config,
    };
    // Each block's field and alignments depend on nothing another block computes: the
    // blocks go to all cores, their results are put together in order. A block that finds
    // no time left abandons the pass.
    let aligned: Option<Vec<BlockAlignments>> = blocks
        .par_iter()
        .enumerate()
        .map(|(block, members)| {
            if !has_time() {
                return None;
            }
            Some(pass.align_block(block, members))
        })
        .collect();
    let Some(aligned) = aligned else {
        return Aligned::OutOfTime;
    };
    let mut alignments = vec![None; world_ends.len()];
    for (k, alignment) in aligned.into_iter().flatten() {
        alignments[k] = alignment;
    }
    Aligned::Scans(alignments)
}

/// The kept scans of one pass, at the path's poses as the pass found them.
struct PassScans<'a> {
    /// Each scan's returns in its sensor frame ...
    sensor_ends: Vec<&'a [[f64; 2]]>,
    /// ... and placed at its pose, with where they were seen from.
    world_ends: Vec<Vec<SeenReturn>>,
    /// Each scan's pose.
    guesses: Vec<Pose2>,
}

/// The alignments of a block's scans, by scan.
type BlockAlignments = Vec<(usize, Option<ScanTie>)>;

/// One pass of the path over its grid, indexed for [`OtherPasses::align_block`].
struct OtherPasses<'a> {
    grid: &'a OccupancyGrid,
    scans: &'a PassScans<'a>,
    /// The scan and return indices of the returns in each tile.
    tiles: &'a HashMap<(i64, i64), Vec<(u32, u32)>>,
    /// The scans of each block, in order.
    blocks: &'a [Vec<usize>],
    block_of: &'a [usize],
    /// How far the path has gone at each scan, metres.
    travelled: &'a [f64],
    revisit_detour_m: f64,
    /// A saved map's walls, when the run maps on one: in the tiles as scan [`SAVED`].
    saved: &'a [SeenReturn],
    config: &'a ScanAlignmentConfig,
}

impl OtherPasses<'_> {
    /// The alignments of the scans `members` of `block` to the walls the other passes drew
    /// around them.
    fn align_block(&self, block: usize, members: &[usize]) -> BlockAlignments {
        let (config, world_ends) = (self.config, &self.scans.world_ends);
        if members.is_empty() {
            return Vec::new();
        }
        let pad = config.inlier_distance_m.max(config.coarse_distance_m) + config.max_shift_m;
        let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &k in members {
            let at: [f64; 2] = self.scans.guesses[k].position().into();
            for p in world_ends[k].iter().map(|seen| &seen.at).chain([&at]) {
                for d in 0..2 {
                    min[d] = min[d].min(p[d] - pad);
                    max[d] = max[d].max(p[d] + pad);
                }
            }
        }
        // Only the walls within reach of where the block's returns may move to can pull
        // on them: the tiles of those returns and the tiles within reach of them.
        let around = (pad / TILE_M).ceil() as i64;
        let mut hit: Vec<(i64, i64)> = members
            .iter()
            .flat_map(|&k| world_ends[k].iter().map(|seen| tile(seen.at)))
            .collect();
        hit.sort_unstable();
        hit.dedup();
        let mut near: Vec<(i64, i64)> = hit
            .iter()
            .flat_map(|&(tx, ty)| {
                (-around..=around)
                    .flat_map(move |dy| (-around..=around).map(move |dx| (tx + dx, ty + dy)))
            })
            .collect();
        // In order, so that each wall piece sums its returns in the same order every run.
        near.sort_unstable();
        near.dedup();
        // Where the robot went round the same rooms many times, each block would gather
        // every return of every other lap: past `MAX_OTHER_RETURNS` it takes an evenly
        // spread share of them, plenty for the mean of each wall piece.
        let candidates: usize = near
            .iter()
            .filter_map(|t| self.tiles.get(t))
            .map(Vec::len)
            .sum();
        let stride = candidates.div_ceil(MAX_OTHER_RETURNS).max(1);
        let mut others = Vec::new();
        // Who drew each of `others`: the block of its scan, or [`SAVED`].
        let mut drawers = Vec::new();
        // Whether the walls are another visit's (a saved map's are) or only this pass's
        // seen from farther along it.
        let mut revisited = false;
        let mut seen = vec![false; world_ends.len()];
        let mut seen_others: Vec<usize> = Vec::new();
        for t in &near {
            for &(k, j) in self.tiles.get(t).into_iter().flatten().step_by(stride) {
                if k == SAVED {
                    others.push(self.saved[j as usize]);
                    drawers.push(SAVED);
                    revisited = true;
                    continue;
                }
                let (k, j) = (k as usize, j as usize);
                if self.block_of[k].abs_diff(block) > 2 {
                    others.push(world_ends[k][j]);
                    drawers.push(self.block_of[k] as u32);
                    if !seen[k] {
                        seen[k] = true;
                        seen_others.push(k);
                    }
                }
            }
        }
        if !revisited {
            revisited = seen_others.iter().any(|&k| self.is_revisit(members, k));
        }
        let weak = if revisited {
            WeakDirections::Follow
        } else {
            WeakDirections::Keep
        };
        let Some(window) = CellWindow::around(self.grid, min, max) else {
            return Vec::new();
        };
        let Some(walls) = WallField::within(
            self.grid,
            window,
            &others,
            &drawers,
            config.inlier_distance_m,
            config.coarse_distance_m,
        ) else {
            return Vec::new();
        };
        members
            .iter()
            .map(|&k| {
                let (ends, guess) = (self.scans.sensor_ends[k], self.scans.guesses[k]);
                let aligned = align_scan(&walls, ends, guess, config, weak);
                let tie = aligned.map(|aligned| match weak {
                    WeakDirections::Follow => self.tie(&walls, ends, aligned),
                    WeakDirections::Keep => ScanTie::prior(aligned),
                });
                (k, tie)
            })
            .collect()
    }

    /// How the alignment `aligned` of a scan's returns `ends` to `walls` ties the path: by
    /// a link from the middle scan of each block that drew some of those walls, with the
    /// information its walls give, and by a prior for a saved map's.
    fn tie(&self, walls: &WallField, ends: &[[f64; 2]], aligned: ScanAlignment) -> ScanTie {
        let mut prior: Option<Matrix3<f64>> = None;
        let mut links = Vec::new();
        for (drawer, information) in information_by_tag(walls, ends, aligned.pose, self.config) {
            let anchor = (drawer != SAVED)
                .then(|| self.blocks.get(drawer as usize))
                .flatten()
                .and_then(|scans| scans.get(scans.len() / 2).copied());
            match anchor {
                Some(anchor) => links.push((anchor, information)),
                None => *prior.get_or_insert_with(Matrix3::zeros) += information,
            }
        }
        ScanTie {
            aligned: aligned.pose,
            prior,
            links,
        }
    }

    /// Whether scan `k` sees the block `members` on another visit: the path between them
    /// is longer than the straight line by the detour, from the block's middle scan.
    fn is_revisit(&self, members: &[usize], k: usize) -> bool {
        let middle = members[members.len() / 2];
        let along = (self.travelled[k] - self.travelled[middle]).abs();
        let straight =
            (self.scans.guesses[k].position() - self.scans.guesses[middle].position()).norm();
        along - straight >= self.revisit_detour_m
    }
}

/// `information` over a pose's world `x, y, yaw` as the information over the same pose
/// seen from `anchor`, in `anchor`'s frame, as a [`PoseLink`] holds it: its translation
/// turned by the anchor's heading.
fn in_frame_of(anchor: &Pose2, information: &Matrix3<f64>) -> Matrix3<f64> {
    // The link's error is `R^T (b - b*)` in translation and `b.yaw - b*.yaw` in turn: the
    // world error is this turned back by the anchor's frame Jacobian.
    let to_world = anchor.frame_jacobian();
    let turned = to_world.transpose() * information * to_world;
    0.5 * (turned + turned.transpose())
}

/// The 1 m tile `p` lies in.
fn tile(p: [f64; 2]) -> (i64, i64) {
    (
        (p[0] / TILE_M).floor() as i64,
        (p[1] / TILE_M).floor() as i64,
    )
}

/// The scan index the tiles give a saved map's walls: no scan's, never a scan's own pass.
const SAVED: u32 = u32::MAX;

/// How firmly a pass holds the translation of the filter's steps.
#[derive(Debug, Clone, Copy, PartialEq)]
struct StepHold {
    /// Variance along the direction of travel per metre travelled, m^2/m ...
    along_per_m: f64,
    /// ... across it, m^2/m ...
    across_per_m: f64,
    /// ... and in every direction per radian turned, m^2/rad.
    per_rad: f64,
}

impl StepHold {
    /// In the passes to the other passes' walls.
    fn to_other_passes(config: &PathRefinementConfig) -> Self {
        Self {
            along_per_m: config.step_along_variance_per_m,
            across_per_m: config.step_across_variance_per_m,
            per_rad: 0.0,
        }
    }

    /// In the passes to every wall.
    fn to_every_wall(config: &PathRefinementConfig) -> Self {
        Self {
            along_per_m: config.step_along_variance_per_m,
            across_per_m: config.step_along_variance_per_m,
            per_rad: config.every_wall_step_xy_variance_per_rad,
        }
    }
}

/// The information of one of the filter's steps, in the frame of the pose it starts from,
/// its translation held as `hold` says: its variances grow with the motion, from a floor
/// that keeps a stopped robot's steps firm but finite.
fn step_information(step: &Pose2, config: &PathRefinementConfig, hold: StepHold) -> Matrix3<f64> {
    let (metres, radians) = (step.translation_norm(), step.yaw.abs());
    let turning = hold.per_rad * radians;
    let along = 1.0 / (hold.along_per_m * metres + turning).max(MIN_STEP_VARIANCE);
    let across = 1.0 / (hold.across_per_m * metres + turning).max(MIN_STEP_VARIANCE);
    let yaw = (config.step_yaw_variance_per_m * metres
        + config.step_yaw_variance_per_rad * radians)
        .max(MIN_STEP_VARIANCE);
    // The direction of travel; a step in place (both variances at the floor) has none.
    let [ux, uy] = if metres > 0.0 {
        [step.x / metres, step.y / metres]
    } else {
        [1.0, 0.0]
    };
    // along * u u^T + across * (I - u u^T), in x and y.
    let (xx, yy, xy) = (
        along * ux * ux + across * uy * uy,
        along * uy * uy + across * ux * ux,
        (along - across) * ux * uy,
    );
    Matrix3::new(xx, xy, 0.0, xy, yy, 0.0, 0.0, 0.0, 1.0 / yaw)
}

/// The returns of a scan as points in the sensor frame.
fn returns(scan: &CompactScan) -> Vec<[f64; 2]> {
    scan.beams()
        .filter_map(|(bearing, beam)| match beam {
            Beam::Hit(range) => {
                let (s, c) = bearing.sin_cos();
                Some([range * c, range * s])
            }
            Beam::NoReturn => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_room::{room_returns, scan_of};
    use nalgebra::Vector3;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// [`refine_path_within`] with the default settings, the scans stamped by index.
    fn refine_by_default(
        path: &[StampedPose],
        scans: &[CompactScan],
        has_time: &(dyn Fn() -> bool + Sync),
    ) -> (Vec<StampedPose>, RefinementReport) {
        let (grid, config) = (GridConfig::default(), PathRefinementConfig::default());
        refine_path_within(path, &stamped(scans), &grid, &config, None, has_time).expect("fits")
    }

    /// The scans stamped with their index, as the refinement takes them.
    fn stamped(scans: &[CompactScan]) -> Vec<(u64, &CompactScan)> {
        scans
            .iter()
            .enumerate()
            .map(|(i, s)| (i as u64, s))
            .collect()
    }

    /// A lap of a circle in the room, `n` poses, facing along it.
    fn lap(n: usize) -> Vec<Pose2> {
        (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                Pose2::new(
                    1.0 + 0.8 * a.cos(),
                    0.8 * a.sin(),
                    a + std::f64::consts::FRAC_PI_2,
                )
            })
            .collect()
    }

    /// Five laps of the room, the last one the filter's open loop: it drifts off the first
    /// four until it ends `drift` off, on average more than `off_before`. Refined, the last
    /// lap must be pulled at least halfway back and the first four stay where they were.
    fn assert_last_lap_pulled(drift: Pose2, off_before: f64) {
        let (laps, per_lap) = (5, 40);
        let off_from = (laps - 1) * per_lap;
        let truth: Vec<Pose2> = (0..laps).flat_map(|_| lap(per_lap)).collect();
        let filter: Vec<StampedPose> = truth
            .iter()
            .enumerate()
            .map(|(i, pose)| StampedPose {
                stamp_ns: i as u64,
                pose: if i >= off_from {
                    let f = (i + 1 - off_from) as f64 / per_lap as f64;
                    Pose2::new(drift.x * f, drift.y * f, drift.yaw * f).compose(pose)
                } else {
                    *pose
                },
            })
            .collect();
        let scans: Vec<CompactScan> = truth.iter().map(|p| scan_of(&room_returns(*p))).collect();
        let by_stamp = stamped(&scans);

        let (refined, report) = refine_path(
            &filter,
            &by_stamp,
            &GridConfig::default(),
            &PathRefinementConfig::default(),
            None,
        )
        .expect("the grid fits");

        assert_eq!(refined.len(), filter.len());
        assert!(
            refined
                .iter()
                .zip(&filter)
                .all(|(a, b)| a.stamp_ns == b.stamp_ns)
        );
        assert_eq!(
            report.aligned_per_pass.len(),
            PathRefinementConfig::default().passes
        );
        // The run's frame is where it started: the refined path starts there too.
        let (start, refined_start) = (filter[0].pose, refined[0].pose);
        assert!((start.position() - refined_start.position()).norm() < 1e-9);
        assert!((start.yaw - refined_start.yaw).abs() < 1e-9);
        let off = |path: &[StampedPose]| {
            path[off_from..]
                .iter()
                .zip(&truth[off_from..])
                .map(|(p, t)| (p.pose.position() - t.position()).norm())
                .sum::<f64>()
                / per_lap as f64
        };
        let right = refined[..off_from]
            .iter()
            .zip(&truth[..off_from])
            .map(|(p, t)| (p.pose.position() - t.position()).norm())
            .fold(0.0, f64::max);
        let (before, after) = (off(&filter), off(&refined));
        assert!(before > off_before, "{before}");
        assert!(
            after < 0.5 * before,
            "last lap off by {after} m after, {before} m before"
        );
        assert!(
            right < 0.03,
            "the laps that were right moved up to {right} m"
        );
    }

    #[test]
    fn a_lap_that_came_back_off_is_pulled_towards_the_walls_the_others_saw() {
        assert_last_lap_pulled(Pose2::new(0.06, -0.04, 0.02), 0.03);
    }

    #[test]
    fn a_lap_that_came_back_degrees_off_its_own_second_walls_is_pulled_too() {
        // It ends 4.6 degrees off: a return 4 m away lands 0.3 m off the wall the other
        // laps drew, nearer the second wall the lap drew itself.
        assert_last_lap_pulled(Pose2::new(0.16, -0.12, 0.08), 0.08);
    }

    /// Three laps of the room, the last one drifting off: the filter's path, and the
    /// scans taken along the true one.
    fn drifting_laps() -> (Vec<StampedPose>, Vec<CompactScan>) {
        let truth: Vec<Pose2> = (0..3).flat_map(|_| lap(40)).collect();
        let path = truth
            .iter()
            .enumerate()
            .map(|(i, pose)| StampedPose {
                stamp_ns: i as u64,
                pose: if i >= 80 {
                    let f = (i - 79) as f64 / 40.0;
                    Pose2::new(0.06 * f, -0.04 * f, 0.02 * f).compose(pose)
                } else {
                    *pose
                },
            })
            .collect();
        let scans = truth.iter().map(|p| scan_of(&room_returns(*p))).collect();
        (path, scans)
    }

    #[test]
    fn with_no_time_the_path_is_left_as_it_was_and_said_cut_short() {
        let (path, scans) = drifting_laps();
        let (refined, report) = refine_by_default(&path, &scans, &|| false);
        assert_eq!(refined, path);
        assert!(report.cut_short);
        assert!(report.aligned_per_pass.is_empty());
    }

    /// Refines the drifting laps with `config` twice: once with all the time it needs, once
    /// with the clock saying no halfway through the second pass; the cut refinement must
    /// be the first pass's path, bit for bit.
    fn assert_cut_mid_second_pass_keeps_the_first(config: PathRefinementConfig) {
        let (path, scans) = drifting_laps();
        let grid = GridConfig::default();
        let refine = |has_time: &(dyn Fn() -> bool + Sync)| {
            refine_path_within(&path, &stamped(&scans), &grid, &config, None, has_time)
                .expect("fits")
        };
        // How often a whole refinement asks, and how often one pass does.
        let asked = AtomicUsize::new(0);
        let count = || {
            asked.fetch_add(1, Ordering::Relaxed);
            true
        };
        let (whole, report) = refine(&count);
        assert!(!report.cut_short);
        let asked = asked.load(Ordering::Relaxed);
        let per_pass = asked / config.passes;
        assert!(per_pass >= 3, "asked {asked} times");
        // Time runs out halfway through the second pass.
        // The tasks of a pass ask from all cores: which is told no first does not matter,
        // the pass is abandoned either way.
        let left = AtomicUsize::new(per_pass + per_pass / 2);
        let has_time = || {
            let before = left
                .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
                    Some(n.saturating_sub(1))
                })
                .unwrap_or(0);
            before > 1
        };
        let (cut, report) = refine(&has_time);
        assert!(report.cut_short);
        assert_eq!(report.aligned_per_pass.len(), 1);
        let one_pass = PathRefinementConfig {
            passes: 1,
            ..config
        };
        let (expected, _) =
            refine_path(&path, &stamped(&scans), &grid, &one_pass, None).expect("fits");
        assert_eq!(cut, expected, "the first pass's path, bit for bit");
        assert_ne!(cut, whole);
    }

    #[test]
    fn time_running_out_mid_pass_keeps_the_passes_done_as_they_were() {
        assert_cut_mid_second_pass_keeps_the_first(PathRefinementConfig::default());
    }

    #[test]
    fn a_pass_to_every_wall_asks_for_time_as_it_goes_too() {
        // Every pass aligns each scan to every wall: each must still be abandoned part way
        // once time runs out, not only before it starts.
        assert_cut_mid_second_pass_keeps_the_first(PathRefinementConfig {
            own_pass_m: 0.0,
            passes: 2,
            ..PathRefinementConfig::default()
        });
    }

    #[test]
    fn a_single_pass_off_a_saved_map_is_pulled_onto_its_walls() {
        // The saved map: the room as one lap at the true poses traced it.
        let truth = lap(40);
        let scans: Vec<CompactScan> = truth.iter().map(|p| scan_of(&room_returns(*p))).collect();
        let traced: Vec<(Pose2, &CompactScan)> = truth.iter().copied().zip(&scans).collect();
        // Cells of 6 cm: the room's walls lie a third of the way into a row of cells, not on
        // the cells' edges, where the returns would fall either side of the edge at random
        // and the wall come out as two rows that each hold half of it.
        let config = GridConfig {
            resolution_m: 0.06,
            ..GridConfig::default()
        };
        let saved = OccupancyGrid::build(&config, &traced)
            .expect("fits")
            .expect("cells");
        // This run: the same lap, the whole of it 7 cm and a degree off the saved frame.
        let offset = Pose2::new(0.06, -0.04, 0.02);
        let filter: Vec<StampedPose> = truth
            .iter()
            .enumerate()
            .map(|(i, pose)| StampedPose {
                stamp_ns: i as u64,
                pose: offset.compose(pose),
            })
            .collect();
        let by_stamp = stamped(&scans);
        let off = |path: &[StampedPose]| {
            path.iter()
                .zip(&truth)
                .map(|(p, t)| (p.pose.position() - t.position()).norm())
                .sum::<f64>()
                / truth.len() as f64
        };
        let refine = |prior| {
            refine_path(
                &filter,
                &by_stamp,
                &config,
                &PathRefinementConfig::default(),
                prior,
            )
            .expect("fits")
        };
        // One pass has no other pass to align to; its last passes align it to its own walls,
        // which it agrees with: alone, it stays where it was.
        let (alone, report) = refine(None);
        let done = report.aligned_per_pass.len();
        let every_wall = PathRefinementConfig::default().every_wall_passes;
        assert!(done > every_wall, "{report:?}");
        let (others, last) = report.aligned_per_pass.split_at(done - every_wall);
        assert!(others.iter().all(|&n| n == 0), "{report:?}");
        assert!(last.iter().all(|&n| n > 0), "{report:?}");
        let moved = alone
            .iter()
            .zip(&filter)
            .map(|(a, b)| (a.pose.position() - b.pose.position()).norm())
            .fold(0.0, f64::max);
        assert!(moved < 0.005, "moved up to {moved} m");
        let (on_saved, report) = refine(Some(&saved));
        assert!(report.aligned_per_pass.iter().all(|&n| n > 0), "{report:?}");
        // Pulled most of the way onto the saved walls.
        let (before, after) = (off(&filter), off(&on_saved));
        assert!(before > 0.06, "{before}");
        assert!(
            after < 0.3 * before,
            "{after} m off after, {before} m before"
        );
    }

    #[test]
    fn the_last_pass_pulls_a_pass_driven_once_onto_the_walls_it_drew() {
        // One lap of the room, driven once, the filter's path drifting off the truth from
        // its start until it ends 7 cm and a degree off: its scans draw each wall twice,
        // apart. No other pass sees the room, so only the last pass, aligning each scan to
        // every wall, can bring the lap's two ends together.
        let truth = lap(40);
        let drift = Pose2::new(0.06, -0.04, 0.02);
        let filter: Vec<StampedPose> = truth
            .iter()
            .enumerate()
            .map(|(i, pose)| {
                let f = i as f64 / (truth.len() - 1) as f64;
                StampedPose {
                    stamp_ns: i as u64,
                    pose: Pose2::new(drift.x * f, drift.y * f, drift.yaw * f).compose(pose),
                }
            })
            .collect();
        let scans: Vec<CompactScan> = truth.iter().map(|p| scan_of(&room_returns(*p))).collect();
        let by_stamp = stamped(&scans);
        // The lap's end against its start: the last pose's error, the first one's being none.
        let gap = |path: &[StampedPose]| {
            let (first, last) = (path[0].pose, path[path.len() - 1].pose);
            let seen = first.between(&last);
            let truly = truth[0].between(&truth[truth.len() - 1]);
            (seen.position() - truly.position()).norm()
        };
        let refine = |every_wall_passes| {
            let config = PathRefinementConfig {
                every_wall_passes,
                ..PathRefinementConfig::default()
            };
            refine_path(&filter, &by_stamp, &GridConfig::default(), &config, None)
                .expect("fits")
                .0
        };
        assert_eq!(refine(0), filter, "no other pass, nothing to align to");
        let before = gap(&filter);
        assert!(before > 0.06, "{before}");
        for every_wall_passes in [1, PathRefinementConfig::default().every_wall_passes] {
            let after = gap(&refine(every_wall_passes));
            assert!(
                after < 0.3 * before,
                "{every_wall_passes} passes to every wall: the lap's ends {after} m apart \
                 after, {before} m before"
            );
        }
    }

    #[test]
    fn no_passes_leave_the_path_as_it_was() {
        let path: Vec<StampedPose> = lap(20)
            .into_iter()
            .enumerate()
            .map(|(i, pose)| StampedPose {
                stamp_ns: i as u64,
                pose,
            })
            .collect();
        let scans: Vec<CompactScan> = path
            .iter()
            .map(|p| scan_of(&room_returns(p.pose)))
            .collect();
        let by_stamp = stamped(&scans);
        let config = PathRefinementConfig {
            passes: 0,
            ..PathRefinementConfig::default()
        };
        let (refined, report) =
            refine_path(&path, &by_stamp, &GridConfig::default(), &config, None).expect("fits");
        assert_eq!(refined, path);
        assert!(report.aligned_per_pass.is_empty());
        assert_eq!(report.largest_move_m, 0.0);
    }

    #[test]
    fn a_step_is_held_less_firmly_along_its_direction_of_travel_than_across_it() {
        let config = PathRefinementConfig::default();
        let (along, across) = (
            config.step_along_variance_per_m,
            config.step_across_variance_per_m,
        );
        // Half a metre at 30 degrees to the pose's heading, turning a little.
        let heading = 30f64.to_radians();
        let step = Pose2::new(0.5 * heading.cos(), 0.5 * heading.sin(), 0.05);
        let information = step_information(&step, &config, StepHold::to_other_passes(&config));
        let u = Vector3::new(heading.cos(), heading.sin(), 0.0);
        let v = Vector3::new(-heading.sin(), heading.cos(), 0.0);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b;
        assert!(close(u.dot(&(information * u)), 1.0 / (along * 0.5)));
        assert!(close(v.dot(&(information * v)), 1.0 / (across * 0.5)));
        assert!(close(u.dot(&(information * v)).abs() + 1.0, 1.0));
        let yaw = config.step_yaw_variance_per_m * 0.5 + config.step_yaw_variance_per_rad * 0.05;
        assert!(close(information[(2, 2)], 1.0 / yaw));
        assert_eq!(information, information.transpose());
        assert!(information.cholesky().is_some());

        // To every wall: as firmly across as along, the same in every direction, and looser
        // by the turn.
        let even = step_information(&step, &config, StepHold::to_every_wall(&config));
        let turning = config.every_wall_step_xy_variance_per_rad * 0.05;
        assert!(close(even[(0, 0)], 1.0 / (along * 0.5 + turning)));
        assert!(close(even[(0, 0)], even[(1, 1)]));
        assert!(even[(0, 1)].abs() <= 1e-9 * even[(0, 0)]);
        assert!(close(even[(2, 2)], information[(2, 2)]));
        // Turning in place, a step there is held by the turn alone.
        let in_place = step_information(
            &Pose2::new(0.0, 0.0, 0.3),
            &config,
            StepHold::to_every_wall(&config),
        );
        let by_turn = 1.0 / (config.every_wall_step_xy_variance_per_rad * 0.3);
        assert!(close(in_place[(0, 0)], by_turn) && close(in_place[(1, 1)], by_turn));

        // A stopped robot's step is firm in every direction, and finite.
        let stopped = step_information(&Pose2::IDENTITY, &config, StepHold::to_every_wall(&config));
        assert_eq!(stopped[(0, 0)], 1.0 / MIN_STEP_VARIANCE);
        assert_eq!(stopped[(1, 1)], 1.0 / MIN_STEP_VARIANCE);
        assert_eq!(stopped[(0, 1)], 0.0);
    }

    #[test]
    fn an_alignment_turned_into_its_anchor_frame_weighs_a_world_shift_as_the_fit_did() {
        // A fit that fixes world x firmly, y hardly, and the turn, with an x-turn coupling;
        // the anchor faces nearly along world y, where an unturned matrix would swap x and y.
        let world = Matrix3::new(400.0, 0.0, 30.0, 0.0, 2.0, 0.0, 30.0, 0.0, 900.0);
        let anchor = Pose2::new(3.0, -1.0, 1.4);
        let scan = Pose2::new(4.5, 2.0, -0.3);
        let information = in_frame_of(&anchor, &world);
        for shift in [
            Vector3::new(0.01, 0.0, 0.0),
            Vector3::new(0.0, 0.01, 0.0),
            Vector3::new(-0.004, 0.007, 0.003),
        ] {
            let shifted = Pose2::new(scan.x + shift.x, scan.y + shift.y, scan.yaw + shift.z);
            // The link's error as the chain solve computes it: the pose seen from the anchor.
            let (seen, seen_shifted) = (anchor.between(&scan), anchor.between(&shifted));
            let error = Vector3::new(
                seen_shifted.x - seen.x,
                seen_shifted.y - seen.y,
                seen_shifted.yaw - seen.yaw,
            );
            let by_link = error.dot(&(information * error));
            let by_fit = shift.dot(&(world * shift));
            assert!(
                (by_link - by_fit).abs() <= 1e-9 * by_fit,
                "{by_link} {by_fit}"
            );
        }
        assert_eq!(information, information.transpose());
    }
}
