//! Point-to-line registration of a scan against the local map (Censi's PL-ICP, with the
//! map's normals standing in for the segment between two map points): Gauss-Newton on
//! `n_map . (R p + t - q)`, a Cauchy loss, a correspondence gate that shrinks from the
//! prior's uncertainty to the sensor's noise as the fit settles (as KISS-ICP's adaptive
//! threshold does), and steps only along the directions the scan constrains.

use nalgebra::{Matrix3, Vector2, Vector3};
use slam_geom::{Pose2, wrap_angle};

use crate::constraint::Constraint;
use crate::local_map::LocalMap;
use crate::points::SurfacePoint;

/// Scans with at least twice this many points first iterate on a subsample of about
/// this many: enough to constrain three parameters robustly, a small share of a
/// 1081-beam scan's queries.
const COARSE_POINTS: usize = 128;

/// Residuals the robust spread is taken from at most.
const MEDIAN_SAMPLE: usize = 128;

/// Gauss-Newton iterations at most per scan (over both stages): a fit from a seed the
/// correlative search placed converges in a few; more means it oscillates.
pub const MAX_ITERATIONS: usize = 30;

/// The iteration stops once a step moves every point by less than this, metres: a tenth of
/// a scanner's range noise, below which further steps change nothing measurable.
pub const CONVERGENCE_M: f64 = 1e-3;

/// A direction (translation, or yaw scaled by the scan's spread) whose information is
/// below this fraction of the strongest direction's is degenerate: left to the prior. Small,
/// so that a door frame or two along a corridor, against hundreds of wall points, still
/// fixes its length.
pub const DEGENERACY_RATIO: f64 = 0.02;

/// The settings registration needs, taken from [`crate::FrontEndConfig`].
#[derive(Debug, Clone, Copy)]
pub struct RegistrationParams {
    pub range_sigma: f64,
    pub voxel: f64,
    /// Whether degenerate directions take damped steps (see [`Constraint::step`]): where
    /// the prior is only a velocity guess; an odometry prior decides them better.
    pub weak_steps: bool,
}

/// The outcome of registering one scan.
#[derive(Debug, Clone, Copy)]
pub struct Registration {
    /// The scan's pose in the map frame.
    pub pose: Pose2,
    pub constraint: Constraint,
    /// Residual variance of the fit (m^2), floored at the range noise.
    pub variance: f64,
    /// Scan points with a map neighbour inside the final gate and the loss's core.
    pub inliers: usize,
    pub iterations: usize,
}

/// Registers `scan` (robot frame) against `map` from `seed`; `gate` is the first
/// correspondence gate, from the prior's uncertainty.
pub fn register(
    map: &LocalMap,
    scan: &[SurfacePoint],
    seed: Pose2,
    gate: f64,
    params: &RegistrationParams,
) -> Registration {
    // A point's map neighbour is up to half a voxel along the wall plus the noise away;
    // the gate never shrinks below that.
    let min_gate = params.voxel + 3.0 * params.range_sigma;
    let mut gate = gate.max(min_gate);
    let length = (scan.iter().map(|p| p.point.norm_squared()).sum::<f64>()
        / scan.len().max(1) as f64)
        .sqrt();
    let mut pose = seed;
    let mut scale = gate / 2.0;
    let mut last = Accumulated::default();
    let mut iterations = 0;
    // Coarse to fine: the iterations that walk from the seed to the basin's bottom run on
    // an even subsample, the last few on every point, for the precision and the
    // covariance. Same minimum, a fraction of the queries on dense scans.
    let stride = scan.len() / COARSE_POINTS;
    let coarse: Vec<SurfacePoint> = if stride > 1 {
        scan.iter().step_by(stride).copied().collect()
    } else {
        Vec::new()
    };
    let stages: [&[SurfacePoint]; 2] = [&coarse, scan];
    for points in stages {
        if points.is_empty() {
            continue;
        }
        for _ in 0..MAX_ITERATIONS {
            iterations += 1;
            last = accumulate(map, points, &pose, gate, scale);
            let constraint = Constraint::new(&last.hessian, length, DEGENERACY_RATIO);
            if last.matched < 3 || constraint.is_void() {
                break;
            }
            let step = constraint.step(&last.gradient, params.weak_steps);
            pose = Pose2::new(
                pose.x + step.x,
                pose.y + step.y,
                wrap_angle(pose.yaw + step.z),
            );
            // The next gate and loss scale follow the residuals: wide while far off, down
            // to the noise once settled.
            let spread = last.robust_sigma().max(params.range_sigma);
            scale = (2.0 * spread).min(scale);
            gate = (params.voxel + 3.0 * spread).clamp(min_gate, gate);
            let moved = step.xy().norm() + step.z.abs() * length;
            if moved < CONVERGENCE_M {
                break;
            }
        }
    }
    // The covariance and the inliers of the pose returned, not of the one before the step.
    let final_terms = accumulate(map, scan, &pose, gate, scale);
    if final_terms.matched >= 3 {
        last = final_terms;
    }
    let variance = (last.weighted_squares / (last.weight - 3.0).max(1.0))
        .max(params.range_sigma * params.range_sigma);
    Registration {
        pose,
        constraint: Constraint::new(&last.hessian, length, DEGENERACY_RATIO),
        variance,
        inliers: last.inliers,
        iterations,
    }
}

#[derive(Debug, Clone, Default)]
struct Accumulated {
    hessian: Matrix3<f64>,
    gradient: Vector3<f64>,
    weight: f64,
    weighted_squares: f64,
    matched: usize,
    inliers: usize,
    /// Absolute residuals of the matched points, for a robust spread.
    residuals: Vec<f64>,
}

impl Accumulated {
    /// 1.4826 x the median absolute residual: the standard deviation of the inliers,
    /// whatever the outliers.
    fn robust_sigma(&mut self) -> f64 {
        if self.residuals.is_empty() {
            return f64::INFINITY;
        }
        // The median of an even subsample is as good a gate and costs a fraction.
        let stride = (self.residuals.len() / MEDIAN_SAMPLE).max(1);
        if stride > 1 {
            let kept = self.residuals.len().div_ceil(stride);
            for i in 1..kept {
                self.residuals[i] = self.residuals[i * stride];
            }
            self.residuals.truncate(kept);
        }
        let mid = self.residuals.len() / 2;
        let (_, median, _) = self.residuals.select_nth_unstable_by(mid, f64::total_cmp);
        1.4826 * *median
    }
}

fn accumulate(
    map: &LocalMap,
    scan: &[SurfacePoint],
    pose: &Pose2,
    gate: f64,
    scale: f64,
) -> Accumulated {
    let rotation = pose.rotation();
    let translation = Vector2::new(pose.x, pose.y);
    let mut acc = Accumulated {
        residuals: Vec::with_capacity(scan.len()),
        ..Accumulated::default()
    };
    let inverse_scale_sq = 1.0 / (scale * scale);
    for p in scan {
        let rotated = rotation * p.point;
        let world = rotated + translation;
        let Some(neighbour) = map.nearest(world, rotation * p.normal, gate) else {
            continue;
        };
        let n = neighbour.normal;
        let r = n.dot(&(world - neighbour.point));
        // d(R p)/d yaw is R p turned by 90 degrees.
        let j = Vector3::new(n.x, n.y, n.x * -rotated.y + n.y * rotated.x);
        let w = 1.0 / (1.0 + r * r * inverse_scale_sq);
        acc.hessian += (w * j) * j.transpose();
        acc.gradient += (w * r) * j;
        acc.weight += w;
        acc.weighted_squares += w * r * r;
        acc.matched += 1;
        if w >= 0.5 {
            acc.inliers += 1;
        }
        acc.residuals.push(r.abs());
    }
    acc
}
