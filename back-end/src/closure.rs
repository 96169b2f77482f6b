//! A loop closure, found and checked by the scans: the scan is searched for over a window of
//! an old submap wide enough for the drift since ([`MatchGrid::search`]), the best pose is
//! registered point to line against the submap's points (the front end's aligner), and the
//! match is a closure only when the registered scan is explained by the submap: a share of
//! its points that find a surface facing their way within a few centimetres. The share means
//! the same on every scanner and every log; a raw sum would grow with the beams.
//!
//! A place that only looks like the old one (the same room shape next door) is refused by
//! the part of the scan that differs, and by an ambiguity check: a second pose, clearly
//! apart from the best, that explains the scan nearly as well means the scan cannot tell the
//! two places apart, and then it is not a closure.

use nalgebra::{Matrix3, Vector2};
use scan_match::points::SurfacePoint;
use scan_match::registration::{RegistrationParams, register};
use slam_geom::Pose2;

use crate::branch_bound::{MatchGrid, SearchWindow};
use crate::coverage::{FreeSpace, Seen};
use crate::submap::SearchMaps;

/// Information along a direction the closure leaves open: a standard deviation of 10 m (or
/// radians).
const OPEN_INFORMATION: f64 = 1e-2;

/// Scan points the grid search scores at most: enough to tell places apart.
const SEARCH_POINTS: usize = 200;

/// What a closure must reach.
#[derive(Debug, Clone, Copy)]
pub struct ClosureCheck {
    /// Of the scan's points the submap can speak for (explained, or in its free space),
    /// the share it must explain after registration.
    pub min_agreement: f64,
    /// Share of the scan's points the submap must explain at least: enough overlap to
    /// judge on.
    pub min_overlap: f64,
    /// The scan's points are explained within this distance, metres.
    pub radius: f64,
    /// Registration's settings (the front end's).
    pub registration: RegistrationParams,
}

/// A verified closure: where the scan is in the submap's frame, and how sure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closure {
    pub submap_from_robot: Pose2,
    /// Information over `(x, y, yaw)` of `submap_from_robot`, in the robot's frame.
    pub information: Matrix3<f64>,
    /// Share of the scan's points the submap explains.
    pub explained: f64,
    /// Share of those the submap can speak for that it explains.
    pub agreement: f64,
}

/// Why a candidate was not a closure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Refusal {
    /// The grid search found no pose explaining enough of the scan.
    NoMatch,
    /// Registered, the scan overlaps the submap too little.
    Unexplained(f64),
    /// Registered, too many of the scan's points lie where the submap saw free space.
    Contradicted(f64),
    /// Another pose, clearly apart, explains the scan nearly as well.
    Ambiguous,
    /// The registration leaves every direction open.
    Unconstrained,
}

/// Checks whether `scan` (robot frame) is seen in a submap (its search maps and free space)
/// within `window` of `seed` (`submap_from_robot` as the graph predicts it).
pub fn verify(
    maps: &SearchMaps,
    free: &FreeSpace,
    scan: &[SurfacePoint],
    seed: &Pose2,
    window: SearchWindow,
    check: &ClosureCheck,
) -> Result<Closure, Refusal> {
    let stride = scan.len().div_ceil(SEARCH_POINTS).max(1);
    let sample: Vec<SurfacePoint> = scan.iter().step_by(stride).copied().collect();
    let positions: Vec<Vector2<f64>> = sample.iter().map(|p| p.point).collect();
    let grid = &maps.grid;
    let found = grid
        .search(&positions, seed, window, check.min_overlap)
        .ok_or(Refusal::NoMatch)?;
    let gate = 2.0 * check.radius;
    let fit = register(&maps.map, scan, found.pose, gate, &check.registration);
    if fit.constraint.is_void() {
        return Err(Refusal::Unconstrained);
    }
    let (explained, agreement) = judge(maps, free, &sample, &fit.pose, check.radius);
    if explained < check.min_overlap {
        return Err(Refusal::Unexplained(explained));
    }
    if agreement < check.min_agreement {
        return Err(Refusal::Contradicted(agreement));
    }
    if ambiguous(grid, &positions, seed, window, &fit.pose, found.score) {
        return Err(Refusal::Ambiguous);
    }
    Ok(Closure {
        submap_from_robot: fit.pose,
        // A direction the scan leaves open (a corridor's length) is known to a few metres:
        // the graph's other edges decide it, and the information stays positive definite.
        information: fit.constraint.information(fit.variance, 0.0)
            + Matrix3::identity() * OPEN_INFORMATION,
        explained,
        agreement,
    })
}

/// The share of `sample` the submap explains at `pose` (a surface facing the same way within
/// `radius`), and the share of the points it can speak for that it explains.
fn judge(
    maps: &SearchMaps,
    free: &FreeSpace,
    sample: &[SurfacePoint],
    pose: &Pose2,
    radius: f64,
) -> (f64, f64) {
    let rotation = pose.rotation();
    let (mut explained, mut contradicted) = (0usize, 0usize);
    for p in sample {
        let point = pose.transform(p.point);
        if maps
            .map
            .nearest(point, rotation * p.normal, radius)
            .is_some()
        {
            explained += 1;
        } else if free.seen(point) == Seen::Free {
            contradicted += 1;
        }
    }
    let share = explained as f64 / sample.len().max(1) as f64;
    let agreement = explained as f64 / (explained + contradicted).max(1) as f64;
    (share, agreement)
}

/// Poses closer than this to the best are the same answer, metres...
const APART_M: f64 = 0.5;
/// ...or radians.
const APART_RAD: f64 = 0.2;
/// A second answer within this share of the best's score makes the match ambiguous.
const AMBIGUITY_SHARE: f64 = 0.9;

/// Whether the window holds a pose clearly apart from `best` that scores nearly as well:
/// searched in the window's parts that exclude the best's neighbourhood.
fn ambiguous(
    grid: &MatchGrid,
    positions: &[Vector2<f64>],
    seed: &Pose2,
    window: SearchWindow,
    best: &Pose2,
    best_score: f64,
) -> bool {
    let floor = AMBIGUITY_SHARE * best_score;
    // Four half-windows beside the best along x and y, each short of its neighbourhood.
    let offsets = [
        Vector2::new(1.0, 0.0),
        Vector2::new(-1.0, 0.0),
        Vector2::new(0.0, 1.0),
        Vector2::new(0.0, -1.0),
    ];
    let reach = window.translation + (best.position() - seed.position()).abs().max();
    if reach <= APART_M {
        return false;
    }
    let half = (reach - APART_M) / 2.0;
    offsets.iter().any(|d| {
        let centre = best.position() + d * (APART_M + half);
        let sub_seed = Pose2::new(centre.x, centre.y, best.yaw);
        let sub = SearchWindow {
            translation: half,
            yaw: window.yaw.max(APART_RAD),
        };
        grid.search(positions, &sub_seed, sub, floor).is_some()
    })
}
