//! Memory by the area mapped, on a constructed building: a robot that drives a mapped loop
//! again retires the submaps it starts there, and keeps those of a wing it has not seen.

mod common;
use common::geometry;

use back_end::{GlobalConfig, GlobalSlam, GlobalStats, ScanRanges};
use lidar_sim::RayCaster;
use lidar_sim::geometry::Segment;
use nalgebra::Matrix3;
use scan_match::FrontEndConfig;
use slam_geom::Pose2;

/// The outline `corners` as walls.
fn polygon(corners: &[(f64, f64)]) -> Vec<Segment> {
    (0..corners.len())
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
            Segment::new([a.0, a.1], [b.0, b.1])
        })
        .collect()
}

fn boxed(x: f64, y: f64, w: f64, h: f64) -> Vec<Segment> {
    polygon(&[(x, y), (x + w, y), (x + w, y + h), (x, y + h)])
}

/// A loop corridor 3 m wide round a block of 18 x 10 m, cabinets and pillars along its
/// walls so that no stretch looks like another, and a door in its east wall to a wing: a
/// corridor east, then north for 16 m out of sight of the loop.
fn building() -> RayCaster {
    let mut walls = polygon(&[
        (0.0, 0.0),
        (24.0, 0.0),
        (24.0, 6.5),
        (30.0, 6.5),
        (30.0, 26.0),
        (27.0, 26.0),
        (27.0, 9.5),
        (24.0, 9.5),
        (24.0, 16.0),
        (0.0, 16.0),
    ]);
    walls.extend(boxed(3.0, 3.0, 18.0, 10.0));
    for (x, y, w, h) in [
        (5.0, 0.0, 0.6, 0.8),
        (11.3, 0.0, 1.2, 0.5),
        (17.0, 2.4, 0.5, 0.6),
        (23.3, 3.0, 0.7, 0.5),
        (21.0, 10.1, 0.4, 0.9),
        (23.5, 12.0, 0.5, 1.5),
        (8.0, 15.4, 0.9, 0.6),
        (15.5, 13.0, 0.6, 0.4),
        (0.0, 9.5, 0.5, 1.2),
        (2.5, 5.0, 0.5, 0.5),
        (29.4, 12.0, 0.6, 1.0),
        (27.0, 15.5, 0.5, 0.8),
        (29.5, 19.0, 0.5, 0.6),
        (27.0, 22.0, 0.7, 0.5),
        (28.0, 25.4, 1.0, 0.6),
    ] {
        walls.extend(boxed(x, y, w, h));
    }
    RayCaster::from_segments(walls)
}

/// The poses of a drive through `waypoints`: 0.1 m steps along each leg, turning on the
/// spot 0.1 rad a step at each corner.
fn drive(from: Pose2, waypoints: &[(f64, f64)]) -> Vec<Pose2> {
    let mut poses = Vec::new();
    let mut at = from;
    for &(x, y) in waypoints {
        let heading = (y - at.y).atan2(x - at.x);
        loop {
            let turn = slam_geom::wrap_angle(heading - at.yaw);
            if turn.abs() < 1e-9 {
                break;
            }
            at = Pose2::new(at.x, at.y, at.yaw + turn.clamp(-0.1, 0.1));
            poses.push(at);
        }
        let length = (x - at.x).hypot(y - at.y);
        let steps = (length / 0.1).ceil() as usize;
        let start = at;
        for k in 1..=steps {
            let s = k as f64 / steps as f64;
            at = Pose2::new(
                start.x + (x - start.x) * s,
                start.y + (y - start.y) * s,
                heading,
            );
            poses.push(at);
        }
    }
    poses
}

/// The loop's corners, driven anticlockwise from the start at (1.5, 1.5).
const LOOP: [(f64, f64); 5] = [
    (22.5, 1.5),
    (22.5, 14.5),
    (1.5, 14.5),
    (1.5, 1.5),
    (22.5, 1.5),
];

/// Feeds `poses` (the truth, which the front end here reports exactly) to `global`.
fn feed(global: &mut GlobalSlam, caster: &RayCaster, poses: &[Pose2], last: &mut Option<Pose2>) {
    let g = geometry();
    for pose in poses {
        let stamp_ns = global.path().len() as u64 * 100_000_000;
        let increment = last.map_or(Pose2::IDENTITY, |l| l.between(pose));
        let covariance = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-5, 1e-5, 1e-6));
        let ranges: Vec<f32> = (0..541)
            .map(|i| {
                caster
                    .cast([pose.x, pose.y], pose.yaw + g.bearing(i), g.range_max)
                    .map_or(f32::INFINITY, |r| r as f32)
            })
            .collect();
        let scan = global.wants_scan(pose).then_some(ScanRanges {
            geometry: &g,
            ranges: &ranges,
        });
        global
            .add_scan(stamp_ns, pose, &increment, &covariance, scan)
            .unwrap();
        *last = Some(*pose);
    }
}

fn kept(stats: &GlobalStats) -> usize {
    stats.submaps - stats.retired
}

#[test]
fn a_second_lap_retires_the_submaps_it_starts_and_new_ground_keeps_its_own() {
    let caster = building();
    let mut global =
        GlobalSlam::new(GlobalConfig::for_front_end(&FrontEndConfig::default())).unwrap();
    let start = Pose2::new(1.5, 1.5, 0.0);
    let mut last = None;
    let mut truth = vec![start];
    feed(&mut global, &caster, &[start], &mut last);
    // Three legs of the first lap: new ground all along, nothing retired.
    let new_ground = drive(start, &LOOP[..3]);
    feed(&mut global, &caster, &new_ground, &mut last);
    truth.extend(&new_ground);
    let first = global.stats();
    assert!(first.submaps > 6, "{first:?}");
    assert_eq!(first.retired, 0, "{first:?}");
    // The rest of the lap, and on along its first leg, where the loop closes.
    let closing = drive(*truth.last().unwrap(), &LOOP[3..]);
    feed(&mut global, &caster, &closing, &mut last);
    truth.extend(&closing);
    let once = global.stats();
    assert!(once.closures > 0, "{once:?}");
    assert!(kept(&once) > 8, "{once:?}");

    // The second lap: every submap it finishes lies on the first lap's.
    let again = drive(*truth.last().unwrap(), &LOOP[1..]);
    feed(&mut global, &caster, &again, &mut last);
    truth.extend(&again);
    let twice = global.stats();
    let started = twice.submaps - once.submaps;
    assert!(started > 8, "{once:?} {twice:?}");
    assert!(
        twice.retired >= started - 2,
        "{started} started, {} retired: {twice:?}",
        twice.retired - once.retired
    );
    assert!(kept(&twice) <= kept(&once) + 2, "{once:?} {twice:?}");

    // Into the wing through the east door and up its northern arm: new ground, whose
    // submaps are kept (those that finish on the loop's east side may go).
    let wing = drive(
        *truth.last().unwrap(),
        &[(22.5, 8.0), (28.5, 8.0), (28.5, 25.0)],
    );
    feed(&mut global, &caster, &wing, &mut last);
    truth.extend(&wing);
    let after = global.stats();
    assert!(kept(&after) >= kept(&twice) + 2, "{twice:?} {after:?}");

    // The path stays where the robot went.
    global.finish().unwrap();
    let path = global.path();
    assert_eq!(path.len(), truth.len());
    for ((_, pose), true_pose) in path.iter().zip(&truth) {
        let error = start.between(true_pose).between(pose);
        assert!(error.translation_norm() < 0.05, "{error:?}");
    }
}
