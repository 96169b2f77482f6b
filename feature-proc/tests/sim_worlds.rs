//! Ray-cast worlds with known corners, driven through with noisy scans: detected corners
//! must be real (precision) and the corners in view must be found (recall).

mod common;

use common::eval::{CornerScore, View, World, score_run};
use common::{Noise, hokuyo, input};
use feature_proc::{Extractor, FeatureConfig};

/// A hall with recessed walls and pillars: square ones on a grid, two turned, a hexagon.
fn hall() -> World {
    let mut world = World::new();
    // Outer wall counter-clockwise, with recesses 1.5 m wide and 0.5 m deep in the long walls.
    let mut outline = vec![[0.0, 0.0]];
    for x in [5.0, 13.0, 21.0] {
        outline.extend([[x, 0.0], [x, -0.5], [x + 1.5, -0.5], [x + 1.5, 0.0]]);
    }
    outline.extend([[30.0, 0.0], [30.0, 20.0]]);
    for x in [24.0, 14.0, 6.0] {
        outline.extend([[x, 20.0], [x, 20.5], [x - 1.5, 20.5], [x - 1.5, 20.0]]);
    }
    outline.push([0.0, 20.0]);
    world.add_polyline(&outline, true);
    for (i, x) in [6.0, 12.0, 18.0, 24.0].into_iter().enumerate() {
        for y in [6.0, 14.0] {
            let turn = if i == 1 && y == 14.0 { 0.5 } else { 0.0 };
            world.add_polyline(&square([x, y], 0.6, turn), true);
        }
    }
    world.add_polyline(&square([21.0, 10.0], 1.0, 0.3), true);
    let hexagon: Vec<[f64; 2]> = (0..6)
        .map(|k| {
            let a = f64::from(k) * std::f64::consts::FRAC_PI_3;
            [9.0 + 0.6 * a.cos(), 10.0 + 0.6 * a.sin()]
        })
        .collect();
    world.add_polyline(&hexagon, true);
    world
}

/// A corridor 40 m long and 2.4 m wide with door recesses (1 m wide, 0.4 m deep) on both
/// sides, staggered.
fn corridor() -> World {
    let mut world = World::new();
    let mut south = vec![[0.0, 0.0]];
    let mut north = vec![[40.0, 2.4]];
    for k in 0..9 {
        let x = 3.0 + 4.0 * f64::from(k);
        south.extend([[x, 0.0], [x, -0.4], [x + 1.0, -0.4], [x + 1.0, 0.0]]);
        let x = 39.0 - 4.0 * f64::from(k) - 2.0;
        north.extend([[x, 2.4], [x, 2.8], [x - 1.0, 2.8], [x - 1.0, 2.4]]);
    }
    south.extend([[40.0, 0.0], [40.0, 2.4]]);
    north.extend([[0.0, 2.4], [0.0, 0.0]]);
    south.extend(north);
    world.add_polyline(&south, true);
    world
}

/// A square of side `size` centred at `c`, turned by `turn`, counter-clockwise.
fn square(c: [f64; 2], size: f64, turn: f64) -> Vec<[f64; 2]> {
    let h = size / 2.0;
    let (s, co) = turn.sin_cos();
    [[-h, -h], [h, -h], [h, h], [-h, h]]
        .iter()
        .map(|p| [c[0] + co * p[0] - s * p[1], c[1] + s * p[0] + co * p[1]])
        .collect()
}

/// Poses every `step` metres along straight legs between `waypoints`, facing along them.
fn path(waypoints: &[[f64; 2]], step: f64) -> Vec<[f64; 3]> {
    let mut poses = Vec::new();
    for leg in waypoints.windows(2) {
        let (a, b) = (leg[0], leg[1]);
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        let yaw = (b[1] - a[1]).atan2(b[0] - a[0]);
        let mut s = 0.0;
        while s < length {
            let t = s / length;
            poses.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), yaw]);
            s += step;
        }
    }
    poses
}

/// Drives `poses` through `world` with range noise `sigma` and scores the corners: precision
/// within `tolerance` of any true corner, recall of the corners in view within 15 m.
fn drive(world: &World, poses: &[[f64; 3]], sigma: f64, tolerance: f64) -> CornerScore {
    let geometry = hokuyo();
    let config = FeatureConfig::default();
    let view = View::for_config(geometry, &config, 15.0);
    let mut noise = Noise::new(11, sigma);
    let scans: Vec<_> = poses
        .iter()
        .map(|&pose| (pose, noise.scan(world, pose, &geometry)))
        .collect();
    let runs = scans
        .iter()
        .map(|(pose, ranges)| (*pose, input(&geometry, ranges)));
    score_run(&mut Extractor::new(config), world, &view, tolerance, runs)
}

fn check(name: &str, world: &World, poses: &[[f64; 3]]) {
    for sigma in [0.01, 0.02] {
        let score = drive(world, poses, sigma, 0.05);
        eprintln!(
            "{name}, noise {sigma}: {} scans, {:.2} corners/scan, precision {:.3}, recall {:.3} ({score:?})",
            poses.len(),
            score.detected as f64 / poses.len() as f64,
            score.precision(),
            score.recall()
        );
        assert!(
            score.in_view > 10 * poses.len() / 4,
            "too few corners in view to judge"
        );
        assert!(
            score.precision() >= 0.9,
            "{name}: precision {}",
            score.precision()
        );
        assert!(score.recall() >= 0.8, "{name}: recall {}", score.recall());
    }
}

#[test]
fn corners_of_a_hall_with_pillars_are_real_and_found() {
    let waypoints = [
        [2.0, 3.0],
        [27.0, 3.5],
        [27.5, 17.0],
        [3.0, 16.5],
        [3.0, 9.5],
        [25.0, 10.5],
    ];
    check("hall", &hall(), &path(&waypoints, 0.25));
}

#[test]
fn corners_of_a_corridor_with_recesses_are_real_and_found() {
    let waypoints = [[1.0, 1.2], [39.0, 1.0], [38.0, 1.6], [1.5, 1.4]];
    check("corridor", &corridor(), &path(&waypoints, 0.25));
}
