//! A correlative search (Olson 2009, one resolution) for the start of registration when
//! the prior is too uncertain for Gauss-Newton to find the right basin: poses on a grid
//! over the prior's 3-sigma window are scored by how many scan points (a subsample) land
//! near a map surface facing the same way, and the best becomes the seed.

use slam_geom::{Pose2, wrap_angle};

use crate::local_map::LocalMap;
use crate::points::SurfacePoint;

/// Scan points scored per candidate: enough to tell poses apart, few enough that a
/// window of thousands of candidates costs well under a millisecond per hundred.
const SUBSAMPLE: usize = 48;
/// Yaw candidates at most (the step widens past this).
const MAX_YAW_STEPS: usize = 41;
/// Translation candidates per axis at most, each side of the seed.
const MAX_HALF_STEPS: i32 = 4;

/// The window to search: 3-sigma half-widths of the prior.
#[derive(Debug, Clone, Copy)]
pub struct Window {
    pub translation: f64,
    pub yaw: f64,
}

/// Fraction of (subsampled) scan points that find a compatible map point within
/// `radius` at `pose`, each weighted by closeness.
pub fn score_sample(map: &LocalMap, sample: &[SurfacePoint], pose: &Pose2, radius: f64) -> f64 {
    score_bounded(map, sample, pose, radius, f64::NEG_INFINITY)
}

/// [`score_sample`], abandoned (returning a lower bound) as soon as even a perfect fit of
/// the remaining points could not reach `to_beat`: most candidates of a window are far
/// off and are dropped after a fraction of their points.
fn score_bounded(
    map: &LocalMap,
    sample: &[SurfacePoint],
    pose: &Pose2,
    radius: f64,
    to_beat: f64,
) -> f64 {
    let rotation = pose.rotation();
    let translation = nalgebra::Vector2::new(pose.x, pose.y);
    let r2 = radius * radius;
    let n = sample.len().max(1) as f64;
    let mut total = 0.0;
    for (i, p) in sample.iter().enumerate() {
        let world = rotation * p.point + translation;
        if let Some(found) = map.nearest(world, rotation * p.normal, radius) {
            total += 1.0 - found.distance_squared / r2;
        }
        let remaining = (sample.len() - i - 1) as f64;
        if (total + remaining) / n < to_beat {
            return total / n;
        }
    }
    total / n
}

/// An even subsample of the scan for scoring.
pub fn subsample(scan: &[SurfacePoint]) -> Vec<SurfacePoint> {
    let stride = scan.len().div_ceil(SUBSAMPLE).max(1);
    scan.iter().step_by(stride).copied().collect()
}

/// What a candidate 3 sigmas of the prior away from the seed loses of its score (a
/// fraction of the points): the scan must fit clearly better to move the seed that far,
/// so a corridor or a repetitive room does not pull it along on noise (Olson's posterior,
/// with the scan's likelihood as a fraction).
const PRIOR_WEIGHT_AT_3_SIGMA: f64 = 0.1;

/// The best pose on the grid around `seed` and its score. `radius` is the scoring
/// distance and the translation step; the yaw step moves the scan's RMS point by it.
pub fn search(
    map: &LocalMap,
    scan: &[SurfacePoint],
    seed: &Pose2,
    window: Window,
    radius: f64,
) -> (Pose2, f64) {
    let sample = subsample(scan);
    search_sample(map, &sample, seed, window, radius)
}

/// [`search`] on an already subsampled scan.
pub fn search_sample(
    map: &LocalMap,
    sample: &[SurfacePoint],
    seed: &Pose2,
    window: Window,
    radius: f64,
) -> (Pose2, f64) {
    let (yaw_step, yaw_half_steps) = yaw_grid(sample, window.yaw, radius, MAX_YAW_STEPS);
    let half = ((window.translation / radius).round() as i32).clamp(0, MAX_HALF_STEPS);
    let step = if half > 0 {
        (window.translation / f64::from(half)).min(radius * 1.5)
    } else {
        radius
    };
    let sigma_t = (window.translation / 3.0).max(1e-9);
    let sigma_yaw = (window.yaw / 3.0).max(1e-9);
    let penalty = |dx: f64, dy: f64, dyaw: f64| {
        let d2 = (dx * dx + dy * dy) / (sigma_t * sigma_t) + dyaw * dyaw / (sigma_yaw * sigma_yaw);
        PRIOR_WEIGHT_AT_3_SIGMA * d2 / 9.0
    };
    let mut best = (*seed, score_sample(map, sample, seed, radius));
    let yaw_half = yaw_half_steps as i64;
    for k in -yaw_half..=yaw_half {
        let yaw = wrap_angle(seed.yaw + k as f64 * yaw_step);
        for i in -half..=half {
            for j in -half..=half {
                if k == 0 && i == 0 && j == 0 {
                    continue;
                }
                let (dx, dy, dyaw) = (
                    f64::from(i) * step,
                    f64::from(j) * step,
                    k as f64 * yaw_step,
                );
                let pose = Pose2::new(seed.x + dx, seed.y + dy, yaw);
                let cost = penalty(dx, dy, dyaw);
                let s = score_bounded(map, sample, &pose, radius, best.1 + cost) - cost;
                if s > best.1 {
                    best = (pose, s);
                }
            }
        }
    }
    best
}

/// The `keep` best poses of a wide grid around `seed` (no prior: after a gap in the data
/// the prior says little), each the best of its neighbourhood, best first. Translation
/// steps of `radius`, yaw steps that move the scan's RMS point by `radius`, at most
/// `max_yaw_steps` of them.
pub fn search_candidates(
    map: &LocalMap,
    sample: &[SurfacePoint],
    seed: &Pose2,
    window: Window,
    radius: f64,
    keep: usize,
    max_yaw_steps: usize,
) -> Vec<(Pose2, f64)> {
    let (yaw_step, yaw_half_steps) = yaw_grid(sample, window.yaw, radius, max_yaw_steps);
    let half = (window.translation / radius).round() as i32;
    // Two candidates closer than this in every coordinate share a basin: the weaker is
    // not kept.
    let near = |a: &Pose2, b: &Pose2| {
        (a.x - b.x).abs() <= 2.0 * radius
            && (a.y - b.y).abs() <= 2.0 * radius
            && wrap_angle(a.yaw - b.yaw).abs() <= 2.0 * yaw_step
    };
    let mut best: Vec<(Pose2, f64)> = Vec::with_capacity(keep + 1);
    let yaw_half = yaw_half_steps as i64;
    for k in -yaw_half..=yaw_half {
        let yaw = wrap_angle(seed.yaw + k as f64 * yaw_step);
        for i in -half..=half {
            for j in -half..=half {
                let pose = Pose2::new(
                    seed.x + f64::from(i) * radius,
                    seed.y + f64::from(j) * radius,
                    yaw,
                );
                let floor = if best.len() < keep {
                    0.0
                } else {
                    best.last().map_or(0.0, |b| b.1)
                };
                let s = score_bounded(map, sample, &pose, radius, floor);
                if s <= floor {
                    continue;
                }
                match best.iter().position(|b| near(&b.0, &pose)) {
                    Some(index) if best[index].1 >= s => continue,
                    Some(index) => {
                        best.remove(index);
                    }
                    None => {}
                }
                let at = best.partition_point(|b| b.1 >= s);
                best.insert(at, (pose, s));
                best.truncate(keep);
            }
        }
    }
    best
}

/// The yaw step and the steps each side of the seed that search `half_window` radians: a
/// step turns the scan's points by about `radius` at their RMS range, and no more than
/// `max_steps` are taken in all (the step then widens).
fn yaw_grid(
    sample: &[SurfacePoint],
    half_window: f64,
    radius: f64,
    max_steps: usize,
) -> (f64, usize) {
    let spread = (sample.iter().map(|p| p.point.norm_squared()).sum::<f64>()
        / sample.len().max(1) as f64)
        .sqrt()
        .max(1.0);
    let step = radius / spread;
    let half_steps = (half_window / step).ceil() as usize;
    if 2 * half_steps + 1 > max_steps {
        let half_steps = (max_steps / 2).max(1);
        (half_window / half_steps as f64, half_steps)
    } else {
        (step, half_steps)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;

    use super::*;

    #[test]
    fn the_wide_search_finds_a_half_turn() {
        // An L of two walls and a post: no symmetry a half turn could mistake.
        let mut map_points = Vec::new();
        for i in 0..80 {
            let t = f64::from(i) * 0.05;
            map_points.push(SurfacePoint {
                point: Vector2::new(t - 1.0, -1.0),
                normal: Vector2::new(0.0, 1.0),
            });
            if i < 50 {
                map_points.push(SurfacePoint {
                    point: Vector2::new(-1.0, t - 1.0),
                    normal: Vector2::new(1.0, 0.0),
                });
            }
        }
        for i in 0..8 {
            map_points.push(SurfacePoint {
                point: Vector2::new(1.5 + f64::from(i) * 0.05, 0.8),
                normal: Vector2::new(0.0, -1.0),
            });
        }
        let mut map = LocalMap::new(0.05, 5);
        map.insert(Pose2::IDENTITY, &map_points);
        let truth = Pose2::new(0.2, -0.1, 2.5);
        let scan: Vec<SurfacePoint> = map_points
            .iter()
            .map(|p| SurfacePoint {
                point: truth.inverse().transform(p.point),
                normal: truth.inverse().rotation() * p.normal,
            })
            .collect();
        let window = Window {
            translation: 0.6,
            yaw: std::f64::consts::PI,
        };
        let found = search_candidates(
            &map,
            &subsample(&scan),
            &Pose2::IDENTITY,
            window,
            0.3,
            4,
            181,
        );
        assert!(!found.is_empty() && found.len() <= 4);
        let (best, score) = found[0];
        assert!(score > 0.5, "{found:?}");
        assert!((best.x - truth.x).abs() < 0.31 && (best.y - truth.y).abs() < 0.31);
        assert!(wrap_angle(best.yaw - truth.yaw).abs() < 0.1, "{found:?}");
        assert!(found.windows(2).all(|w| w[0].1 >= w[1].1));
    }
}
