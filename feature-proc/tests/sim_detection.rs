//! Corner detection on the simulator's own worlds (lidar-sim), scored against their truth.

use feature_proc::{Extractor, FeatureConfig, ScanInput};
use lidar_sim::{RayCaster, SensorConfig, Simulation, VehicleConfig, World, visible_corners};

struct Score {
    detected: usize,
    correct: usize,
    in_view: usize,
    found: usize,
}

fn score_world(name: &str, frames: usize) -> Score {
    let world = World::builtin(name).unwrap();
    let caster = RayCaster::new(&world);
    let truth = world.true_corners();
    let sensor = SensorConfig::default();
    let mut sim = Simulation::new(world, sensor.clone(), VehicleConfig::default(), 11).unwrap();
    let mut extractor = Extractor::new(FeatureConfig::default());
    let mut score = Score {
        detected: 0,
        correct: 0,
        in_view: 0,
        found: 0,
    };
    // Every 10th frame: the scans are then far enough apart to count separately.
    for _ in 0..frames {
        let Some(frame) = sim.next_frame() else { break };
        if frame.seq % 10 != 0 {
            continue;
        }
        let pose = frame.pose;
        let features = extractor
            .extract(&ScanInput {
                geometry: sensor.scan_geometry(),
                ranges: &frame.ranges,
            })
            .unwrap();
        let (s, c) = pose.yaw.sin_cos();
        let world_corners: Vec<[f64; 2]> = features
            .corners
            .iter()
            .map(|k| [pose.x + c * k.x - s * k.y, pose.y + s * k.x + c * k.y])
            .collect();
        let near = |p: &[f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]) < 0.05;
        score.detected += world_corners.len();
        score.correct += world_corners
            .iter()
            .filter(|p| truth.iter().any(|t| near(p, [t.x, t.y])))
            .count();
        for index in visible_corners(&caster, &truth, [pose.x, pose.y], 15.0) {
            let t = truth[index];
            let bearing = (t.y - pose.y).atan2(t.x - pose.x) - pose.yaw;
            let bearing = (bearing + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            // Inside the 270-degree field of view, with margin for the walls' extent.
            if bearing.abs() > 2.2 {
                continue;
            }
            // Both walls must be seen over half a metre from the tip, enough points for a
            // line: a 0.2 m door reveal or a wall seen from behind is not a corner in view.
            let arm_seen = |arm: lidar_sim::Point2| {
                (1..=5).all(|k| {
                    let d = 0.1 * f64::from(k);
                    let p = [t.x + arm.x * d, t.y + arm.y * d];
                    let (dx, dy) = (p[0] - pose.x, p[1] - pose.y);
                    let range = dx.hypot(dy);
                    caster
                        .cast([pose.x, pose.y], dy.atan2(dx), range + 1.0)
                        .is_some_and(|hit| (hit - range).abs() < 0.02)
                })
            };
            if !t.arms().into_iter().all(arm_seen) {
                continue;
            }
            score.in_view += 1;
            if world_corners.iter().any(|p| near(p, [t.x, t.y])) {
                score.found += 1;
            }
        }
    }
    score
}

#[test]
fn simulated_worlds_corners_are_real_and_found() {
    for world in ["office", "hall"] {
        let s = score_world(world, 2000);
        let precision = s.correct as f64 / s.detected as f64;
        let recall = s.found as f64 / s.in_view as f64;
        eprintln!(
            "{world}: precision {precision:.3} ({}/{}), recall {recall:.3} ({}/{})",
            s.correct, s.detected, s.found, s.in_view
        );
        assert!(s.detected > 100, "{world}: only {} corners", s.detected);
        assert!(precision >= 0.9, "{world}: precision {precision}");
        assert!(recall >= 0.8, "{world}: recall {recall}");
    }
}
