//! One scan aligned to a map: the pose, near a guess, that brings the scan's returns
//! closest to the map's walls (Gauss-Newton, point to line, with a Cauchy loss so that what
//! the map does not hold pulls little), and how firmly the scan fixes it.

use nalgebra::{Matrix3, Vector3};
use slam_geom::Pose2;

use crate::wall_field::WallField;

/// How a scan is aligned and when the alignment is trusted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanAlignmentConfig {
    /// Gauss-Newton steps at most.
    pub iterations: usize,
    /// Returns farther than this from the map (metres) are not pulled on.
    pub inlier_distance_m: f64,
    /// Scale of the Cauchy loss, metres: a return this far off counts half.
    pub loss_scale_m: f64,
    /// The first steps pull on returns this far from the map (metres), with the loss
    /// widened as much, so that a scan a few degrees off finds its walls before the
    /// steps that only pull on returns within `inlier_distance_m`.
    pub coarse_distance_m: f64,
    /// Gauss-Newton steps at the coarse distance.
    pub coarse_iterations: usize,
    /// Returns the alignment needs near the map, at the least.
    pub min_inliers: usize,
    /// Share of the scan's returns that must end near the map.
    pub min_inlier_share: f64,
    /// Mean distance of the returns to the map (each capped at `inlier_distance_m`) above
    /// which the alignment is not trusted, metres.
    pub max_mean_distance_m: f64,
    /// An alignment that moves the guess farther than this is a wrong basin, metres.
    pub max_shift_m: f64,
}

impl Default for ScanAlignmentConfig {
    fn default() -> Self {
        Self {
            iterations: 10,
            inlier_distance_m: 0.3,
            loss_scale_m: 0.05,
            coarse_distance_m: 1.0,
            coarse_iterations: 5,
            min_inliers: 20,
            min_inlier_share: 0.7,
            max_mean_distance_m: 0.12,
            max_shift_m: 0.6,
        }
    }
}

/// A trusted alignment: the pose and the information (inverse covariance) the scan's fit
/// gives it, in `x, y, yaw`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanAlignment {
    pub pose: Pose2,
    pub information: Matrix3<f64>,
}

/// Aligns the returns `ends` (points in the sensor frame) to `walls` from `guess`. `None`
/// when the fit is not trusted: too few returns near the map, too far on average, or moved
/// too far.
pub(crate) fn align_scan(
    walls: &WallField,
    ends: &[[f64; 2]],
    guess: Pose2,
    config: &ScanAlignmentConfig,
) -> Option<ScanAlignment> {
    if ends.is_empty() {
        return None;
    }
    let mut pose = guess;
    let mut information = None;
    for iteration in 0..config.iterations + config.coarse_iterations {
        let coarse = iteration < config.coarse_iterations;
        let (distance, scale) = if coarse {
            let widen = config.coarse_distance_m / config.inlier_distance_m;
            (config.coarse_distance_m, config.loss_scale_m * widen)
        } else {
            (config.inlier_distance_m, config.loss_scale_m)
        };
        let (s, c) = pose.yaw.sin_cos();
        let mut h = Matrix3::zeros();
        let mut g = Vector3::zeros();
        let mut inliers = 0;
        for &[lx, ly] in ends {
            let point = [pose.x + c * lx - s * ly, pose.y + s * lx + c * ly];
            let from = [pose.x, pose.y];
            let wall = if coarse {
                walls.far_distance(point, from)
            } else {
                walls.distance(point, from)
            };
            let Some(wall) = wall else {
                continue;
            };
            if wall.residual.abs() >= distance {
                continue;
            }
            inliers += 1;
            let [gx, gy] = wall.gradient;
            let jacobian = Vector3::new(gx, gy, gx * (-s * lx - c * ly) + gy * (c * lx - s * ly));
            let weight = 1.0 / (1.0 + (wall.residual / scale).powi(2));
            h += weight * jacobian * jacobian.transpose();
            g += weight * wall.residual * jacobian;
        }
        if inliers < config.min_inliers {
            return None;
        }
        // A scan of one straight wall leaves its length free: the small diagonal keeps the
        // step finite there, and the information says the direction is not fixed.
        h += Matrix3::identity() * 1e-6;
        let step = h.cholesky()?.solve(&(-g));
        pose = Pose2::new(pose.x + step.x, pose.y + step.y, pose.yaw + step.z);
        information = Some(h);
        if step.amax() < 1e-4 && iteration >= config.coarse_iterations {
            break;
        }
    }
    let information = information?;
    let (s, c) = pose.yaw.sin_cos();
    let (mut near, mut total) = (0_usize, 0.0);
    for &[lx, ly] in ends {
        let d = walls
            .distance(
                [pose.x + c * lx - s * ly, pose.y + s * lx + c * ly],
                [pose.x, pose.y],
            )
            .map_or(config.inlier_distance_m, |w| w.residual.abs());
        near += usize::from(d < config.inlier_distance_m);
        total += d.min(config.inlier_distance_m);
    }
    let trusted = near as f64 >= config.min_inlier_share * ends.len() as f64
        && total / ends.len() as f64 <= config.max_mean_distance_m
        && (pose.position() - guess.position()).norm() <= config.max_shift_m;
    trusted.then_some(ScanAlignment { pose, information })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compact_scan::CompactScan;
    use crate::occupancy_grid::{GridConfig, OccupancyGrid};
    use crate::test_room::{room_returns, scan_of};
    use crate::wall_field::SeenReturn;

    fn room_walls() -> WallField {
        let returns = room_returns(Pose2::new(0.0, 0.0, 0.0));
        let scan = scan_of(&returns);
        let scans: Vec<(Pose2, &CompactScan)> =
            (0..3).map(|_| (Pose2::new(0.0, 0.0, 0.0), &scan)).collect();
        let grid = OccupancyGrid::build(&GridConfig::default(), &scans)
            .expect("the grid fits")
            .expect("beams");
        // The room seen from the origin: the sensor and world frames are one.
        let seen: Vec<SeenReturn> = returns
            .iter()
            .map(|&at| SeenReturn {
                at,
                from: [0.0, 0.0],
            })
            .collect();
        WallField::new(&grid, &seen, 0.3, 1.0).expect("walls")
    }

    #[test]
    fn a_scan_taken_elsewhere_is_pulled_back_to_where_it_was_taken() {
        let walls = room_walls();
        let truth = Pose2::new(0.4, -0.3, 0.2);
        let returns = room_returns(truth);
        let guess = Pose2::new(0.5, -0.2, 0.15);
        let aligned = align_scan(&walls, &returns, guess, &ScanAlignmentConfig::default())
            .expect("a room fixes the pose");
        assert!(
            (aligned.pose.position() - truth.position()).norm() < 0.02,
            "{aligned:?}"
        );
        assert!((aligned.pose.yaw - truth.yaw).abs() < 0.01, "{aligned:?}");
        assert!(aligned.information.symmetric_eigenvalues().min() > 0.0);
    }

    #[test]
    fn a_scan_far_from_the_map_is_not_trusted() {
        let walls = room_walls();
        // The room's returns, but seen from 1.5 m away: nothing lines up.
        let returns = room_returns(Pose2::new(0.0, 0.0, 0.0));
        let guess = Pose2::new(-1.2, 1.0, 1.0);
        assert_eq!(
            align_scan(&walls, &returns, guess, &ScanAlignmentConfig::default()),
            None
        );
    }
}
