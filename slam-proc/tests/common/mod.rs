//! Synthetic corner worlds for the tests and the bench: true corners, a trajectory, and
//! the noisy corner observations a feature extractor would report along it.

#![allow(dead_code)] // each test binary uses a different part

pub mod recorded;

use std::f64::consts::{PI, TAU};

use nalgebra::{Matrix4, Vector2, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use slam_geom::wrap_angle;
use slam_proc::{MeasuredCorner, Pose2};

pub use slam_geom::TrueCorner;

/// How observations are generated.
#[derive(Debug, Clone, Copy)]
pub struct SensorModel {
    pub max_range: f64,
    pub half_fov: f64,
    pub miss_probability: f64,
    /// Expected spurious corners per scan.
    pub spurious_rate: f64,
    /// Position sigma `base + per_metre * range`.
    pub sigma_xy_base: f64,
    pub sigma_xy_per_metre: f64,
    pub sigma_angle: f64,
    /// A corner is seen only from about inside its wedge (both walls visible): the
    /// direction from the sensor to the tip within half the opening angle of the heading,
    /// plus `wedge_margin` (walls seen at grazing incidence still give a corner).
    pub wedge_visibility: bool,
    pub wedge_margin: f64,
}

impl Default for SensorModel {
    fn default() -> Self {
        Self {
            max_range: 15.0,
            half_fov: 135f64.to_radians(),
            miss_probability: 0.1,
            spurious_rate: 0.3,
            sigma_xy_base: 0.01,
            sigma_xy_per_metre: 0.001,
            sigma_angle: 1f64.to_radians(),
            wedge_visibility: true,
            wedge_margin: 20f64.to_radians(),
        }
    }
}

pub struct Run {
    pub corners: Vec<TrueCorner>,
    pub truth: Vec<Pose2>,
    pub stamps: Vec<u64>,
    pub scans: Vec<Vec<MeasuredCorner>>,
}

fn normal(rng: &mut impl Rng) -> f64 {
    rng.sample(StandardNormal)
}

/// Position and tangent direction at arc length `s` on a rounded square (straight sides of
/// `side`, quarter circles of radius `r`), starting mid-way along the bottom side going +x.
fn rounded_square(s: f64, side: f64, r: f64) -> (Vector2<f64>, f64) {
    let half = side / 2.0 + r;
    let perimeter = 4.0 * side + TAU * r;
    let mut s = s.rem_euclid(perimeter);
    // Start at the middle of the bottom side: first half a side, then arc, side, ...
    let pieces = [
        side / 2.0,
        PI / 2.0 * r,
        side,
        PI / 2.0 * r,
        side,
        PI / 2.0 * r,
        side,
        PI / 2.0 * r,
        side / 2.0,
    ];
    let mut position = Vector2::new(0.0, -half);
    let mut direction: f64 = 0.0;
    for (k, &length) in pieces.iter().enumerate() {
        let step = s.min(length);
        if k % 2 == 0 {
            position += Vector2::new(direction.cos(), direction.sin()) * step;
        } else {
            // Left turn along a circle of radius r.
            let centre = position + Vector2::new(-direction.sin(), direction.cos()) * r;
            let turned = direction + step / r;
            position = centre + Vector2::new(turned.sin(), -turned.cos()) * r;
            direction = turned;
        }
        s -= step;
        if s <= 0.0 {
            break;
        }
    }
    (position, wrap_angle(direction))
}

/// Random corners beside a path: `count` of them at 2-10 m from it, at least 1.5 m apart,
/// each facing the path to within 40 degrees (its walls open towards where the robot
/// drives, or it would never be seen: see `wedge_visibility`).
fn corners_along(
    rng: &mut impl Rng,
    count: usize,
    path: &dyn Fn(f64) -> (Vector2<f64>, f64),
    length: f64,
) -> Vec<TrueCorner> {
    let mut corners: Vec<TrueCorner> = Vec::new();
    while corners.len() < count {
        let (p, direction) = path(rng.random::<f64>() * length);
        let side = if rng.random::<bool>() { 1.0 } else { -1.0 };
        let offset = side * (2.0 + 8.0 * rng.random::<f64>());
        let q = p + Vector2::new(-direction.sin(), direction.cos()) * offset;
        if corners.iter().any(|c| (c.x - q.x).hypot(c.y - q.y) < 1.5) {
            continue;
        }
        let towards = (q.y - p.y).atan2(q.x - p.x);
        corners.push(TrueCorner {
            x: q.x,
            y: q.y,
            heading: wrap_angle(towards + (80.0 * rng.random::<f64>() - 40.0).to_radians()),
            angle: (50.0 + 80.0 * rng.random::<f64>()).to_radians(),
        });
    }
    corners
}

fn noisy(
    rng: &mut impl Rng,
    sensor: &SensorModel,
    x: f64,
    y: f64,
    heading: f64,
    angle: f64,
) -> MeasuredCorner {
    let range = x.hypot(y);
    let sxy = sensor.sigma_xy_base + sensor.sigma_xy_per_metre * range;
    let sa = sensor.sigma_angle;
    MeasuredCorner {
        x: x + sxy * normal(rng),
        y: y + sxy * normal(rng),
        heading: wrap_angle(heading + sa * normal(rng)),
        angle: (angle + sa * normal(rng)).clamp(0.01, PI - 0.01),
        covariance: Matrix4::from_diagonal(&Vector4::new(sxy * sxy, sxy * sxy, sa * sa, sa * sa)),
    }
}

/// What the sensor reports at `pose`: visible corners with noise, misses, spurious ones.
pub fn observe(
    rng: &mut impl Rng,
    sensor: &SensorModel,
    pose: &Pose2,
    corners: &[TrueCorner],
) -> Vec<MeasuredCorner> {
    let inverse = pose.inverse();
    let mut scan = Vec::new();
    for c in corners {
        let p = inverse.transform(Vector2::new(c.x, c.y));
        let range = p.norm();
        if !(0.5..=sensor.max_range).contains(&range) || p.y.atan2(p.x).abs() > sensor.half_fov {
            continue;
        }
        let towards_tip = p.y.atan2(p.x) + pose.yaw;
        if sensor.wedge_visibility
            && wrap_angle(towards_tip - c.heading).abs() > c.angle / 2.0 + sensor.wedge_margin
        {
            continue;
        }
        if rng.random::<f64>() < sensor.miss_probability {
            continue;
        }
        scan.push(noisy(
            rng,
            sensor,
            p.x,
            p.y,
            wrap_angle(c.heading - pose.yaw),
            c.angle,
        ));
    }
    if rng.random::<f64>() < sensor.spurious_rate {
        let range = 2.0 + (sensor.max_range - 2.0) * rng.random::<f64>();
        let bearing = sensor.half_fov * (2.0 * rng.random::<f64>() - 1.0);
        let heading = wrap_angle(rng.random::<f64>() * TAU);
        let angle = (50.0 + 80.0 * rng.random::<f64>()).to_radians();
        scan.push(noisy(
            rng,
            sensor,
            range * bearing.cos(),
            range * bearing.sin(),
            heading,
            angle,
        ));
    }
    // Extractors report corners in scan order, not in map order.
    scan.sort_by(|a, b| a.y.atan2(a.x).total_cmp(&b.y.atan2(b.x)));
    scan
}

/// A loop of about 99 m around a 26 m rounded square (0.08-0.12 m per scan at 40 Hz, the
/// yaw wobbling around the path direction), among `corner_count` corners, run a little past
/// the start so the loop closes. The path starts at the origin facing +x.
pub fn square_loop(seed: u64, corner_count: usize, sensor: &SensorModel) -> Run {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (side, radius) = (20.0, 3.0);
    let perimeter = 4.0 * side + TAU * radius;
    let origin = rounded_square(0.0, side, radius).0;
    let path = move |s: f64| {
        let (p, direction) = rounded_square(s, side, radius);
        (p - origin, direction)
    };
    let corners = corners_along(&mut rng, corner_count, &path, perimeter);
    let (mut truth, mut stamps, mut scans) = (Vec::new(), Vec::new(), Vec::new());
    let mut s = 0.0;
    let mut k = 0u64;
    while s < perimeter + 3.0 {
        let (p, direction) = path(s);
        let wobble = if k == 0 {
            0.0
        } else {
            0.06 * (k as f64 * TAU / 90.0).sin()
        };
        let pose = Pose2::new(p.x, p.y, wrap_angle(direction + wobble));
        scans.push(observe(&mut rng, sensor, &pose, &corners));
        truth.push(pose);
        stamps.push(k * 25_000_000);
        s += 0.1 + 0.02 * (k as f64 * TAU / 150.0).sin();
        k += 1;
    }
    Run {
        corners,
        truth,
        stamps,
        scans,
    }
}

/// The rigid transform (no scale) that best maps `estimate` positions onto `truth`, as
/// `evo_ape -a` aligns trajectories: slam-eval's, so the tests score as the pipeline does.
pub fn align(estimate: &[Pose2], truth: &[Pose2]) -> Pose2 {
    ate(estimate, truth).alignment.to_pose()
}

/// Absolute trajectory error (RMSE of positions, metres) after SE(2) alignment.
pub fn ate_rmse(estimate: &[Pose2], truth: &[Pose2]) -> f64 {
    ate(estimate, truth).rmse_m
}

fn ate(estimate: &[Pose2], truth: &[Pose2]) -> slam_eval::AteStats {
    let n = estimate.len().min(truth.len());
    let positions =
        |poses: &[Pose2]| -> Vec<[f64; 2]> { poses[..n].iter().map(|p| [p.x, p.y]).collect() };
    slam_eval::ate(&positions(estimate), &positions(truth)).expect("trajectories to score")
}
