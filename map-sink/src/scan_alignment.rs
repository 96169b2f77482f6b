//! One scan aligned to a map: the pose, near a guess, that brings the scan's returns
//! closest to the map's walls (Gauss-Newton, point to line, with a Cauchy loss so that what
//! the map does not hold pulls little), and how firmly the scan fixes it.
//!
//! Against walls the scan's own pass drew from farther along, the fit keeps only its motion
//! along the directions the walls fix firmly: along a corridor the fit's pull is then the
//! noise of a door frame seen at a glance, and a path refined pass after pass on such
//! pulls slides along the corridor. Those directions stay at the guess, with next to no
//! information, and the path's own steps decide them.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use slam_geom::{Pose2, wrap_angle};

use crate::wall_field::{WallDistance, WallField};

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
    /// A direction of `x, y, yaw` (yaw in metres at the returns' RMS range) whose
    /// information is below this share of the best-fixed direction's is left at the guess
    /// when the walls are the scan's own pass's (see [`WeakDirections::Keep`]).
    pub degeneracy_ratio: f64,
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
            degeneracy_ratio: 0.2,
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

/// How far a scan's alignment may move it along the directions its walls fix weakly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum WeakDirections {
    /// The walls were drawn on another visit: even a weak pull (along a corridor) is
    /// evidence the path does not have.
    Follow,
    /// The walls are the scan's own pass seen from farther along it: a weak pull there is
    /// the pass's own error read back at a glance, so those directions stay at the guess.
    Keep,
}

/// Aligns the returns `ends` (points in the sensor frame) to `walls` from `guess`. `None`
/// when the fit is not trusted: too few returns near the map, too far on average, or moved
/// too far.
pub(crate) fn align_scan(
    walls: &WallField,
    ends: &[[f64; 2]],
    guess: Pose2,
    config: &ScanAlignmentConfig,
    weak: WeakDirections,
) -> Option<ScanAlignment> {
    if ends.is_empty() {
        return None;
    }
    let reach = (ends.iter().map(|[x, y]| x * x + y * y).sum::<f64>() / ends.len() as f64).sqrt();
    let mut pose = guess;
    let mut hessian = None;
    for iteration in 0..config.iterations + config.coarse_iterations {
        let coarse = iteration < config.coarse_iterations;
        let (distance, scale) = if coarse {
            let widen = config.coarse_distance_m / config.inlier_distance_m;
            (config.coarse_distance_m, config.loss_scale_m * widen)
        } else {
            (config.inlier_distance_m, config.loss_scale_m)
        };
        let within = Reach {
            coarse,
            distance,
            scale,
        };
        let sin_cos = pose.yaw.sin_cos();
        let mut h = Matrix3::zeros();
        let mut g = Vector3::zeros();
        let mut inliers = 0;
        for &end in ends {
            let Some(pull) = Pull::of(walls, end, pose, sin_cos, &within) else {
                continue;
            };
            inliers += 1;
            h += pull.weight * pull.jacobian * pull.jacobian.transpose();
            g += pull.weight * pull.wall.residual * pull.jacobian;
        }
        if inliers < config.min_inliers {
            return None;
        }
        // A scan of one straight wall leaves its length free: the small diagonal keeps the
        // step finite there, and the information says the direction is not fixed.
        h += Matrix3::identity() * 1e-6;
        let step = h.cholesky()?.solve(&(-g));
        pose = Pose2::new(pose.x + step.x, pose.y + step.y, pose.yaw + step.z);
        hessian = Some(h);
        if step.amax() < 1e-4 && iteration >= config.coarse_iterations {
            break;
        }
    }
    // What the walls fix is judged at the fit's own scale, once it has converged; the
    // coarse steps may have leaned on walls farther off than the fit trusts.
    let hessian = hessian?;
    let (pose, information) = match weak {
        WeakDirections::Follow => (pose, hessian),
        WeakDirections::Keep => {
            let fixed = FixedDirections::of(&hessian, reach, config.degeneracy_ratio)?;
            (fixed.keep(guess, pose), fixed.information())
        }
    };
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

/// Which walls a return is pulled to in one step of a fit: those within `distance` (the far
/// reach of the field when `coarse`), with a Cauchy loss of scale `scale`.
struct Reach {
    coarse: bool,
    distance: f64,
    scale: f64,
}

/// One return's pull on a pose: the wall it is pulled to, the Jacobian of its residual in
/// `x, y, yaw`, and its weight under the loss.
struct Pull {
    wall: WallDistance,
    jacobian: Vector3<f64>,
    weight: f64,
}

impl Pull {
    /// The pull on `pose` (with `sin_cos`, its heading's sine and cosine, worked out once
    /// for all its returns) of the return `end` (sensor frame); `None` when no wall
    /// `within` reach faces it.
    fn of(
        walls: &WallField,
        end: [f64; 2],
        pose: Pose2,
        sin_cos: (f64, f64),
        within: &Reach,
    ) -> Option<Self> {
        let [lx, ly] = end;
        let (s, c) = sin_cos;
        let point = [pose.x + c * lx - s * ly, pose.y + s * lx + c * ly];
        let from = [pose.x, pose.y];
        let wall = if within.coarse {
            walls.far_distance(point, from)
        } else {
            walls.distance(point, from)
        }?;
        if wall.residual.abs() >= within.distance {
            return None;
        }
        let [gx, gy] = wall.gradient;
        let jacobian = Vector3::new(gx, gy, gx * (-s * lx - c * ly) + gy * (c * lx - s * ly));
        let weight = 1.0 / (1.0 + (wall.residual / within.scale).powi(2));
        Some(Self {
            wall,
            jacobian,
            weight,
        })
    }
}

/// The information the returns `ends` (sensor frame) at `pose` take from `walls`, by the
/// tag of the wall piece each is pulled to, in tag order: the fit's Hessian at `pose`
/// (without its small diagonal), each return's share given to whoever drew its wall.
pub(crate) fn information_by_tag(
    walls: &WallField,
    ends: &[[f64; 2]],
    pose: Pose2,
    config: &ScanAlignmentConfig,
) -> Vec<(u32, Matrix3<f64>)> {
    let within = Reach {
        coarse: false,
        distance: config.inlier_distance_m,
        scale: config.loss_scale_m,
    };
    let sin_cos = pose.yaw.sin_cos();
    let mut by_tag: Vec<(u32, Matrix3<f64>)> = Vec::new();
    for &end in ends {
        let Some(pull) = Pull::of(walls, end, pose, sin_cos, &within) else {
            continue;
        };
        let share = pull.weight * pull.jacobian * pull.jacobian.transpose();
        match by_tag.iter_mut().find(|(tag, _)| *tag == pull.wall.tag) {
            Some((_, information)) => *information += share,
            None => by_tag.push((pull.wall.tag, share)),
        }
    }
    by_tag.sort_unstable_by_key(|(tag, _)| *tag);
    by_tag
}

/// The directions of `x, y, yaw` a fit's Hessian fixes, found in a space where yaw is
/// measured in metres at the returns' range so that a turn and a shift compare.
struct FixedDirections {
    /// To the scaled space: `diag(1, 1, 1 / reach)`.
    to_scaled: Vector3<f64>,
    /// The fixed directions (unit, scaled space) with their information.
    fixed: Vec<(Vector3<f64>, f64)>,
}

impl FixedDirections {
    /// `None` when the Hessian fixes nothing.
    fn of(hessian: &Matrix3<f64>, reach: f64, degeneracy_ratio: f64) -> Option<Self> {
        let reach = if reach.is_finite() && reach > 0.1 {
            reach
        } else {
            1.0
        };
        let to_scaled = Vector3::new(1.0, 1.0, 1.0 / reach);
        let scale = Matrix3::from_diagonal(&to_scaled);
        let scaled = scale * hessian * scale;
        let eigen = SymmetricEigen::new(0.5 * (scaled + scaled.transpose()));
        let strongest = eigen.eigenvalues.max();
        let fixed: Vec<(Vector3<f64>, f64)> = (0..3)
            .filter(|&i| {
                let value = eigen.eigenvalues[i];
                value > 0.0 && value >= degeneracy_ratio * strongest
            })
            .map(|i| {
                (
                    eigen.eigenvectors.column(i).into_owned(),
                    eigen.eigenvalues[i],
                )
            })
            .collect();
        (!fixed.is_empty()).then_some(Self { to_scaled, fixed })
    }

    /// `to` moved back towards `from` along the directions that are not fixed.
    fn keep(&self, from: Pose2, to: Pose2) -> Pose2 {
        let moved = Vector3::new(to.x - from.x, to.y - from.y, wrap_angle(to.yaw - from.yaw))
            .component_div(&self.to_scaled);
        let kept: Vector3<f64> = self.fixed.iter().map(|(v, _)| v * v.dot(&moved)).sum();
        let kept = kept.component_mul(&self.to_scaled);
        Pose2::new(from.x + kept.x, from.y + kept.y, from.yaw + kept.z)
    }

    /// The information over `x, y, yaw`: the Hessian's along the fixed directions, none
    /// along the others.
    fn information(&self) -> Matrix3<f64> {
        let scaled: Matrix3<f64> = self
            .fixed
            .iter()
            .map(|(v, value)| v * v.transpose() * *value)
            .sum();
        let from_scaled = Matrix3::from_diagonal(&self.to_scaled.map(|s| 1.0 / s));
        let information = from_scaled * scaled * from_scaled;
        0.5 * (information + information.transpose())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_room::{room_returns, scan_of};
    use crate::wall_field::SeenReturn;
    use back_end::compact_scan::CompactScan;
    use back_end::occupancy_grid::{GridConfig, OccupancyGrid};

    fn room_walls() -> WallField {
        room_walls_drawn_by(|_| 0)
    }

    /// The room's walls, each return tagged by `tag` of where it ended.
    fn room_walls_drawn_by(tag: impl Fn([f64; 2]) -> u32) -> WallField {
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
        let tags: Vec<u32> = returns.iter().map(|&p| tag(p)).collect();
        let window = crate::wall_field::CellWindow::whole(&grid);
        WallField::within(&grid, window, &seen, &tags, 0.3, 1.0).expect("walls")
    }

    #[test]
    fn a_scan_taken_elsewhere_is_pulled_back_to_where_it_was_taken() {
        let walls = room_walls();
        let truth = Pose2::new(0.4, -0.3, 0.2);
        let returns = room_returns(truth);
        let guess = Pose2::new(0.5, -0.2, 0.15);
        let aligned = align_scan(
            &walls,
            &returns,
            guess,
            &ScanAlignmentConfig::default(),
            WeakDirections::Keep,
        )
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
        for weak in [WeakDirections::Keep, WeakDirections::Follow] {
            assert_eq!(
                align_scan(
                    &walls,
                    &returns,
                    guess,
                    &ScanAlignmentConfig::default(),
                    weak
                ),
                None
            );
        }
    }

    #[test]
    fn the_information_is_split_between_whoever_drew_the_walls_and_adds_up_to_the_fit() {
        // The room's walls with x < 1 drawn by 1, the rest by 2.
        let walls = room_walls_drawn_by(|p| 1 + u32::from(p[0] >= 1.0));
        let pose = Pose2::new(0.4, -0.3, 0.2);
        let ends = room_returns(pose);
        let by_tag = information_by_tag(&walls, &ends, pose, &ScanAlignmentConfig::default());
        assert_eq!(by_tag.iter().map(|(t, _)| *t).collect::<Vec<_>>(), [1, 2]);
        // The walls at x = -2 (drawn by 1) fix x; the wall at x = 4 (by 2) too.
        for (_, information) in &by_tag {
            assert!(information[(0, 0)] > 10.0, "{information}");
        }
        let aligned = align_scan(
            &walls,
            &ends,
            pose,
            &ScanAlignmentConfig::default(),
            WeakDirections::Follow,
        )
        .expect("a room fixes the pose");
        // At the fit, the shares add up to the information the fit gives.
        let split = information_by_tag(&walls, &ends, aligned.pose, &Default::default());
        let at_fit: Matrix3<f64> = split.iter().map(|(_, m)| m).sum();
        let difference = (at_fit - aligned.information).abs().max();
        assert!(
            difference < 1e-3 * aligned.information.abs().max(),
            "{difference}"
        );
    }

    #[test]
    fn a_direction_the_walls_hardly_fix_is_kept_at_the_guess_with_no_information() {
        // Along a corridor: x barely fixed, y and the heading firmly (returns 5 m out).
        let reach = 5.0;
        let hessian = Matrix3::from_diagonal(&Vector3::new(1e-3, 100.0, 100.0 * reach * reach));
        let fixed = FixedDirections::of(&hessian, reach, 0.2).expect("y and yaw are fixed");
        let guess = Pose2::new(1.0, 2.0, 0.1);
        let fit = Pose2::new(1.3, 2.05, 0.12);

        let kept = fixed.keep(guess, fit);
        assert!((kept.x - guess.x).abs() < 1e-12, "{kept:?}");
        assert!((kept.y - fit.y).abs() < 1e-12, "{kept:?}");
        assert!((kept.yaw - fit.yaw).abs() < 1e-12, "{kept:?}");
        let information = fixed.information();
        assert!(information[(0, 0)].abs() < 1e-12, "{information}");
        assert!((information[(1, 1)] - 100.0).abs() < 1e-9, "{information}");
        assert!((information[(2, 2)] - 2500.0).abs() < 1e-6, "{information}");

        // Fixed well enough in x, all of the fit is kept.
        let all = FixedDirections::of(&hessian, reach, 0.0).expect("fixed");
        let all_kept = all.keep(guess, fit);
        assert!(
            (all_kept.position() - fit.position()).norm() < 1e-12,
            "{all_kept:?}"
        );
        assert!((all_kept.yaw - fit.yaw).abs() < 1e-12, "{all_kept:?}");
    }
}
