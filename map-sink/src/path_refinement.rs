//! The final path refined against its own map.
//!
//! The filter's path is right from step to step, but where a loop closed late, or not at
//! all, a stretch of it comes back some decimetres off the part of the map it revisits, and
//! its scans draw a second wall beside the first. Each pass traces the grid from the path,
//! aligns every kept scan to that grid ([`align_scan`]: where most passes agree, the grid's
//! walls are theirs), and re-solves the path from its own steps and those alignments
//! ([`solve_pose_chain`]), so a stretch moves towards the walls the rest of the run saw
//! while each step stays close to what the filter measured. A stretch is pulled where the
//! other passes outvote it: where its second wall lies in space their beams saw free, they
//! clear it, and within a cell a wall piece is the mean of all the returns in it, most of
//! them theirs. The next pass traces the grid again from the moved path.

use std::collections::HashMap;

use nalgebra::{Matrix3, Vector3};
use slam_geom::{Pose2, StampedPose};

use crate::compact_scan::{Beam, CompactScan};
use crate::occupancy_grid::{GridConfig, GridError, OccupancyGrid};
use crate::pose_chain::{PosePrior, solve_pose_chain};
use crate::scan_alignment::{ScanAlignmentConfig, align_scan};
use crate::wall_field::WallField;

/// How the final path is refined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathRefinementConfig {
    /// Passes of trace, align and solve; 0 leaves the path as the filter gave it.
    pub passes: usize,
    /// How far the filter's steps may bend: the variance of a step's x and y per metre it
    /// travelled, m^2/m. Proportional to the motion, so that a path bends as much over a
    /// metre at any scan rate.
    pub step_xy_variance_per_m: f64,
    /// The variance of a step's turn per metre travelled, rad^2/m.
    pub step_yaw_variance_per_m: f64,
    /// The variance of a step's turn per radian turned, rad^2/rad.
    pub step_yaw_variance_per_rad: f64,
    /// When a scan's alignment is trusted.
    pub alignment: ScanAlignmentConfig,
}

impl Default for PathRefinementConfig {
    fn default() -> Self {
        Self {
            passes: 3,
            step_xy_variance_per_m: 0.01,
            step_yaw_variance_per_m: 0.002,
            step_yaw_variance_per_rad: 0.002,
            alignment: ScanAlignmentConfig::default(),
        }
    }
}

/// The smallest variance of a step (m^2, rad^2): a stopped robot's step is firm, but a
/// variance of zero would make the solve singular.
const MIN_STEP_VARIANCE: f64 = 1e-8;

/// What refining did, for the run's log.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RefinementReport {
    /// Scans aligned (and trusted) in each pass, of `scans` on the path.
    pub aligned_per_pass: Vec<usize>,
    pub scans: usize,
    /// The farthest any pose moved from the filter's path, metres.
    pub largest_move_m: f64,
}

/// Refines `path` against the grid its scans trace (`scans` by stamp; a scan the path does
/// not hold is left out). Returns the refined path, the same length and stamps, and what
/// was done. A pass whose alignments cannot fix the path leaves it as it was.
pub fn refine_path(
    path: &[StampedPose],
    scans: &[(u64, &CompactScan)],
    grid: &GridConfig,
    config: &PathRefinementConfig,
) -> Result<(Vec<StampedPose>, RefinementReport), GridError> {
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
    let step_information: Vec<Matrix3<f64>> = steps
        .iter()
        .map(|step| step_information(step, config))
        .collect();
    for _ in 0..config.passes {
        let traced: Vec<(Pose2, &CompactScan)> = on_path
            .iter()
            .map(|(i, scan, _)| (poses[*i], *scan))
            .collect();
        let Some(grid) = OccupancyGrid::build(grid, &traced)? else {
            break;
        };
        let ends: Vec<[f64; 2]> = on_path
            .iter()
            .flat_map(|(i, _, ends)| {
                let pose = poses[*i];
                ends.iter()
                    .map(move |&[x, y]| pose.transform([x, y].into()).into())
            })
            .collect();
        let Some(walls) = WallField::new(&grid, &ends, config.alignment.inlier_distance_m) else {
            break;
        };
        let priors: Vec<PosePrior> = on_path
            .iter()
            .filter_map(|(i, _, ends)| {
                let aligned = align_scan(&walls, ends, poses[*i], &config.alignment)?;
                Some(PosePrior {
                    index: *i,
                    pose: aligned.pose,
                    information: aligned.information,
                })
            })
            .collect();
        report.aligned_per_pass.push(priors.len());
        match solve_pose_chain(&poses, &steps, &step_information, &priors) {
            Some(solved) => poses = solved,
            None => break,
        }
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

/// The information of one of the filter's steps: its variances grow with the motion, from
/// a floor that keeps a stopped robot's steps firm but finite.
fn step_information(step: &Pose2, config: &PathRefinementConfig) -> Matrix3<f64> {
    let (metres, radians) = (step.translation_norm(), step.yaw.abs());
    let xy = (config.step_xy_variance_per_m * metres).max(MIN_STEP_VARIANCE);
    let yaw = (config.step_yaw_variance_per_m * metres
        + config.step_yaw_variance_per_rad * radians)
        .max(MIN_STEP_VARIANCE);
    Matrix3::from_diagonal(&Vector3::new(1.0 / xy, 1.0 / xy, 1.0 / yaw))
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

    #[test]
    fn a_lap_that_came_back_off_is_pulled_towards_the_walls_the_others_saw() {
        let truth: Vec<Pose2> = (0..3).flat_map(|_| lap(40)).collect();
        // The third lap is the filter's open loop: right from step to step, but 3.6 cm and
        // 0.01 rad off the first two laps as a whole.
        let offset = Pose2::new(0.03, -0.02, 0.01);
        let filter: Vec<StampedPose> = truth
            .iter()
            .enumerate()
            .map(|(i, pose)| StampedPose {
                stamp_ns: i as u64,
                pose: if i >= 80 { offset.compose(pose) } else { *pose },
            })
            .collect();
        let scans: Vec<CompactScan> = truth.iter().map(|p| scan_of(&room_returns(*p))).collect();
        let by_stamp: Vec<(u64, &CompactScan)> = scans
            .iter()
            .enumerate()
            .map(|(i, s)| (i as u64, s))
            .collect();

        let (refined, report) = refine_path(
            &filter,
            &by_stamp,
            &GridConfig::default(),
            &PathRefinementConfig::default(),
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
        let off = |path: &[StampedPose]| {
            path[80..]
                .iter()
                .zip(&truth[80..])
                .map(|(p, t)| (p.pose.position() - t.position()).norm())
                .sum::<f64>()
                / 40.0
        };
        let before = off(&filter);
        let after = off(&refined);
        assert!(before > 0.03, "{before}");
        assert!(
            after < 0.6 * before,
            "third lap off by {after} m after, {before} m before"
        );
        // The laps that were right stay right.
        let first_two = refined[..80]
            .iter()
            .zip(&truth[..80])
            .map(|(p, t)| (p.pose.position() - t.position()).norm())
            .fold(0.0, f64::max);
        assert!(first_two < 0.03, "{first_two}");
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
        let by_stamp: Vec<(u64, &CompactScan)> = scans
            .iter()
            .enumerate()
            .map(|(i, s)| (i as u64, s))
            .collect();
        let config = PathRefinementConfig {
            passes: 0,
            ..PathRefinementConfig::default()
        };
        let (refined, report) =
            refine_path(&path, &by_stamp, &GridConfig::default(), &config).expect("fits");
        assert_eq!(refined, path);
        assert!(report.aligned_per_pass.is_empty());
        assert_eq!(report.largest_move_m, 0.0);
    }
}
