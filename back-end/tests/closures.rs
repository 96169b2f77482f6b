//! Closures checked by the scans, on constructed worlds: a right closure after metres of
//! drift is found and placed; a room that only looks like the old one is refused.

mod common;
use common::geometry;

use back_end::GlobalConfig;
use back_end::branch_bound::SearchWindow;
use back_end::closure::{ClosureCheck, Refusal, verify};
use back_end::compact_scan::CompactScan;
use back_end::occupancy_grid::GridConfig;
use back_end::submap::{SubmapConfig, Submaps};
use lidar_sim::RayCaster;
use lidar_sim::geometry::Segment;
use scan_match::FrontEndConfig;
use scan_match::points::{SurfacePoint, extract};
use slam_geom::Pose2;

const VOXEL: f64 = 0.05;

/// The defaults the pipeline runs with.
fn check() -> ClosureCheck {
    GlobalConfig::for_front_end(&FrontEndConfig::default()).closure
}

/// A closed polygon's walls, with gaps where `doors` (pairs of indices of wall and span
/// along it, metres from its start) open.
fn walls(corners: &[(f64, f64)], doors: &[(usize, f64, f64)]) -> Vec<Segment> {
    let mut out = Vec::new();
    for i in 0..corners.len() {
        let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
        let length = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let at = |s: f64| {
            [
                a.0 + (b.0 - a.0) * s / length,
                a.1 + (b.1 - a.1) * s / length,
            ]
        };
        let mut start = 0.0;
        let mut gaps: Vec<(f64, f64)> = doors
            .iter()
            .filter(|d| d.0 == i)
            .map(|d| (d.1, d.2))
            .collect();
        gaps.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (from, to) in gaps {
            out.push(Segment::new(at(start), at(from)));
            start = to;
        }
        out.push(Segment::new(at(start), at(length)));
    }
    out
}

fn boxed(x: f64, y: f64, w: f64, h: f64) -> Vec<Segment> {
    walls(&[(x, y), (x + w, y), (x + w, y + h), (x, y + h)], &[])
}

fn ranges(caster: &RayCaster, pose: &Pose2) -> Vec<f32> {
    let geometry = geometry();
    (0..541)
        .map(|i| {
            let bearing = pose.yaw + geometry.bearing(i);
            caster
                .cast([pose.x, pose.y], bearing, geometry.range_max)
                .map_or(f32::NAN, |r| r as f32)
        })
        .collect()
}

fn scan(caster: &RayCaster, pose: &Pose2) -> Vec<SurfacePoint> {
    extract(&geometry(), &ranges(caster, pose), 0.01, VOXEL).points
}

/// A finished submap of `caster`'s world from poses along a line.
fn submap_along(caster: &RayCaster, from: Pose2, step: Pose2) -> Submaps {
    let grid = GridConfig::default();
    let mut submaps = Submaps::new(SubmapConfig {
        keyframes: 4,
        voxel: VOXEL,
        grid,
    });
    let g = geometry();
    let mut pose = from;
    for node in 0..8 {
        let ranges = ranges(caster, &pose);
        let beams = CompactScan::new(
            g.angle_min,
            g.angle_increment,
            g.range_min,
            g.range_max,
            &ranges,
            grid.resolution_m,
            grid.no_return_reach_m,
        );
        submaps
            .insert(node, &pose, scan(caster, &pose).into(), beams)
            .unwrap();
        pose = pose.compose(&step);
    }
    assert!(submaps.get(0).unwrap().is_finished());
    submaps
}

/// Two rooms of the same shape and size, 10 m apart: the same four corners, but the doors
/// in other walls, and a cabinet in one where the other has a row of desks.
fn look_alike_rooms() -> RayCaster {
    let mut segments = walls(
        &[(0.0, 0.0), (6.0, 0.0), (6.0, 5.0), (0.0, 5.0)],
        &[(2, 3.5, 4.5)],
    );
    segments.extend(boxed(4.5, 0.5, 1.0, 0.6));
    segments.extend(walls(
        &[(10.0, 0.0), (16.0, 0.0), (16.0, 5.0), (10.0, 5.0)],
        &[(1, 1.0, 2.0), (0, 1.0, 2.0)],
    ));
    segments.extend(boxed(10.6, 3.8, 1.6, 0.5));
    segments.extend(boxed(13.0, 3.8, 1.6, 0.5));
    RayCaster::from_segments(segments)
}

#[test]
fn a_closure_after_two_metres_of_drift_is_found_where_it_is() {
    let caster = look_alike_rooms();
    let submaps = submap_along(
        &caster,
        Pose2::new(1.0, 1.5, 0.2),
        Pose2::new(0.25, 0.0, 0.05),
    );
    let submap = submaps.get(0).unwrap();
    let maps = submap.search_maps(VOXEL, 2.5).unwrap();
    let free = submap.free_space().unwrap();
    // The robot is back, at `truth` in the submap's frame; the drifted path puts it 2 m off.
    let world_from_submap = Pose2::new(1.0, 1.5, 0.2);
    let world_from_robot = Pose2::new(3.0, 2.5, 1.2);
    let truth = world_from_submap.between(&world_from_robot);
    let seed = truth.compose(&Pose2::new(1.3, -1.4, 0.2));
    let window = SearchWindow {
        translation: 2.5,
        yaw: 0.3,
    };
    let closure = verify(
        &maps,
        free,
        &scan(&caster, &world_from_robot),
        &seed,
        window,
        &check(),
    )
    .unwrap();
    let error = truth.between(&closure.submap_from_robot);
    assert!(error.translation_norm() < 0.02, "{error:?}");
    assert!(error.yaw.abs() < 0.005, "{error:?}");
    assert!(closure.explained > 0.8, "{}", closure.explained);
    // The information is symmetric positive definite.
    let information = closure.information;
    assert!((information - information.transpose()).norm() < 1e-9 * information.norm());
    assert!(information.cholesky().is_some());
}

#[test]
fn a_room_that_only_looks_like_the_old_one_is_refused() {
    let caster = look_alike_rooms();
    let submaps = submap_along(
        &caster,
        Pose2::new(1.0, 1.5, 0.2),
        Pose2::new(0.25, 0.0, 0.05),
    );
    let submap = submaps.get(0).unwrap();
    let maps = submap.search_maps(VOXEL, 1.0).unwrap();
    let free = submap.free_space().unwrap();
    // The robot is in the second room; its corners say it is at the same place of the first.
    let world_from_submap = Pose2::new(1.0, 1.5, 0.2);
    let in_second_room = Pose2::new(13.0, 2.5, 1.2);
    let proposed = Pose2::new(3.0, 2.5, 1.2);
    let seed = world_from_submap.between(&proposed);
    let window = SearchWindow {
        translation: 1.0,
        yaw: 0.2,
    };
    let answer = verify(
        &maps,
        free,
        &scan(&caster, &in_second_room),
        &seed,
        window,
        &check(),
    );
    assert!(
        matches!(
            answer,
            Err(Refusal::NoMatch
                | Refusal::Unexplained(_)
                | Refusal::Contradicted(_)
                | Refusal::Ambiguous)
        ),
        "{answer:?}"
    );
    // The same scan from the first room is a closure.
    let answer = verify(
        &maps,
        free,
        &scan(&caster, &proposed),
        &seed,
        window,
        &check(),
    );
    assert!(answer.is_ok(), "{answer:?}");
}
