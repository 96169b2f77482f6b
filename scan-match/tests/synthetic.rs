//! Registration, degeneracy and fusion on constructed scans with a known motion.

#[path = "support/world.rs"]
mod world;

use nalgebra::Matrix3;
use scan_match::{
    FrontEnd, FrontEndConfig, MatchFailure, MatchStatus, OdometryInput, OdometryRejection,
    OdometryRejections, OdometryStatus, ScanInput,
};
use slam_geom::{Pose2, wrap_angle};
use world::{HOKUYO, SICK, corridor, corridor_with_recess, raycast, room};

const PERIOD_NS: u64 = 100_000_000;

fn scan<'a>(
    stamp: u64,
    ranges: &'a [f32],
    geometry: slam_geom::ScanGeometry,
    odometry: Option<OdometryInput>,
) -> ScanInput<'a> {
    ScanInput {
        stamp_ns: stamp * PERIOD_NS,
        geometry,
        ranges,
        odometry,
    }
}

fn odometry(pose: Pose2, variance: f64) -> OdometryInput {
    OdometryInput {
        odom_from_robot: pose,
        covariance: Matrix3::from_diagonal(&nalgebra::Vector3::new(variance, variance, variance)),
    }
}

/// Every odometry status of scans `range` is a stale reading's rejection.
fn assert_stale(statuses: &[OdometryStatus], range: std::ops::Range<usize>) {
    for k in range {
        assert!(
            matches!(
                statuses[k],
                OdometryStatus::Rejected(OdometryRejection::Stale { .. })
            ),
            "{k}: {:?}",
            statuses[k]
        );
    }
}

fn assert_close(a: &Pose2, b: &Pose2, metres: f64, radians: f64) {
    assert!(
        (a.x - b.x).abs() < metres
            && (a.y - b.y).abs() < metres
            && wrap_angle(a.yaw - b.yaw).abs() < radians,
        "{a:?} vs {b:?}"
    );
}

#[test]
fn a_known_motion_in_a_room_is_recovered_within_millimetres() {
    for (geometry, beams) in [(SICK, 361), (HOKUYO, 1081)] {
        let walls = room();
        let start = Pose2::new(0.5, 0.2, 0.1);
        let motion = Pose2::new(0.12, -0.04, 0.06);
        let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
        let first = raycast(&walls, &start, &geometry, beams, 0.0);
        let out = front_end.process(&scan(0, &first, geometry, None)).unwrap();
        assert_eq!(out.status, MatchStatus::First);
        assert_eq!(out.odom_from_robot, Pose2::IDENTITY);
        // No odometry, zero velocity: the whole motion comes from the scan.
        let second = raycast(&walls, &start.compose(&motion), &geometry, beams, 0.0);
        let out = front_end
            .process(&scan(1, &second, geometry, None))
            .unwrap();
        assert_eq!(out.status, MatchStatus::Matched, "{out:?}");
        assert_eq!(out.odometry, OdometryStatus::Absent);
        assert_close(&out.increment, &motion, 0.003, 0.001);
        assert!(out.increment_covariance.cholesky().is_some());
        assert!(out.inliers > out.points / 2);
    }
}

#[test]
fn sensor_noise_costs_millimetres_not_centimetres() {
    let walls = room();
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let mut truth = Pose2::new(-1.0, 0.5, 0.0);
    let step = Pose2::new(0.08, 0.0, 0.02);
    for k in 0..20 {
        let ranges = raycast(&walls, &truth, &SICK, 361, 0.01);
        let out = front_end.process(&scan(k, &ranges, SICK, None)).unwrap();
        if k > 0 {
            assert_close(&out.increment, &step, 0.01, 0.004);
        }
        truth = truth.compose(&step);
    }
    // Twenty steps (1.6 m, 0.4 rad) drift by less than 3 cm against the local map.
    let end = front_end.pose();
    let expected = (0..19).fold(Pose2::IDENTITY, |p, _| p.compose(&step));
    assert_close(&end, &expected, 0.03, 0.01);
}

#[test]
fn a_corridor_leaves_its_length_to_the_odometry() {
    let walls = corridor();
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let start = Pose2::new(0.0, 0.1, 0.02);
    let motion = Pose2::new(0.40, 0.03, -0.02);
    // The odometry is 6 cm long, 2 cm sideways and 0.01 rad off, with a 5 cm, 0.05 rad sigma.
    let odometry_motion = Pose2::new(0.46, 0.05, -0.01);
    let a = raycast(&walls, &start, &SICK, 361, 0.0);
    front_end
        .process(&scan(0, &a, SICK, Some(odometry(Pose2::IDENTITY, 0.0))))
        .unwrap();
    let b = raycast(&walls, &start.compose(&motion), &SICK, 361, 0.0);
    let out = front_end
        .process(&scan(1, &b, SICK, Some(odometry(odometry_motion, 0.0025))))
        .unwrap();
    let MatchStatus::Degenerate { direction, count } = out.status else {
        panic!("not degenerate: {out:?}");
    };
    assert_eq!(count, 1);
    // Along the corridor, in the robot frame (turned by 0.02 rad from it).
    assert!(direction.x.abs() > 0.99, "{direction:?}");
    assert_eq!(out.odometry, OdometryStatus::Used);
    // Across and in yaw the scan corrects the odometry; along, the odometry stands. The
    // comparison is in the corridor's frame, where "along" is x.
    let before = start;
    let after = before.compose(&out.increment);
    let truth = start.compose(&motion);
    assert!((after.y - truth.y).abs() < 0.003, "{after:?} vs {truth:?}");
    assert!(wrap_angle(after.yaw - truth.yaw).abs() < 0.002);
    let odometry_after = before.compose(&odometry_motion);
    assert!(
        (after.x - odometry_after.x).abs() < 0.01,
        "{after:?} vs {odometry_after:?}"
    );
    // The covariance says so: along the corridor as uncertain as the odometry.
    assert!(out.increment_covariance[(0, 0)] > 0.5 * 0.0025);
    assert!(out.increment_covariance[(1, 1)] < 0.1 * 0.0025);
}

#[test]
fn odometry_outliers_are_rejected_and_counted_consistent_steps_used() {
    let walls = room();
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let step = Pose2::new(0.1, 0.0, 0.03);
    let mut truth = Pose2::new(0.0, 0.0, 0.0);
    let mut odo = Pose2::new(5.0, -2.0, 1.0);
    let variance_per_step = 1e-4;
    let mut k = 0;
    let feed = |front_end: &mut FrontEnd, truth: Pose2, reading: Pose2, k: &mut u64| {
        let ranges = raycast(&walls, &truth, &SICK, 361, 0.005);
        let out = front_end
            .process(&scan(
                *k,
                &ranges,
                SICK,
                Some(odometry(reading, variance_per_step * *k as f64)),
            ))
            .unwrap();
        *k += 1;
        out
    };
    for _ in 0..5 {
        let out = feed(&mut front_end, truth, odo, &mut k);
        assert!(matches!(
            out.odometry,
            OdometryStatus::Used | OdometryStatus::Started
        ));
        truth = truth.compose(&step);
        odo = odo.compose(&step);
    }
    assert_eq!(front_end.stats().odometry_rejected.total(), 0);
    // A jump of 1000 m: rejected, and the pose follows the scan.
    let jumped = odo.compose(&Pose2::new(1000.0, 0.0, 0.0));
    let before = front_end.pose();
    let out = feed(&mut front_end, truth, jumped, &mut k);
    assert_eq!(
        out.odometry,
        OdometryStatus::Rejected(OdometryRejection::Implausible)
    );
    assert_close(&out.increment, &step, 0.01, 0.005);
    assert_close(
        &before.compose(&out.increment),
        &front_end.pose(),
        1e-9,
        1e-9,
    );
    assert_eq!(front_end.stats().odometry_rejected.total(), 1);
    // The reading after it is a step back from the jump: rejected too; the one after
    // that is consistent again and used.
    truth = truth.compose(&step);
    odo = odo.compose(&step);
    let out = feed(&mut front_end, truth, odo.compose(&step), &mut k);
    assert!(matches!(out.odometry, OdometryStatus::Rejected(_)));
    truth = truth.compose(&step);
    odo = odo.compose(&step).compose(&step);
    let out = feed(&mut front_end, truth, odo, &mut k);
    assert_eq!(out.odometry, OdometryStatus::Used);
    // A value of 1e300 (implausible) and a NaN (not finite).
    for bad in [Pose2::new(1e300, 0.0, 0.0), Pose2::new(f64::NAN, 0.0, 0.0)] {
        truth = truth.compose(&step);
        odo = odo.compose(&step);
        let out = feed(&mut front_end, truth, bad, &mut k);
        assert!(
            matches!(out.odometry, OdometryStatus::Rejected(_)),
            "{out:?}"
        );
        assert_close(&out.increment, &step, 0.01, 0.005);
    }
    assert_eq!(front_end.stats().odometry_rejected.total(), 4);
    // The NaN did not replace the last finite reading (1e300): the next step is measured
    // from it, rejected again; from then on the steps are good.
    truth = truth.compose(&step);
    odo = odo.compose(&step);
    let out = feed(&mut front_end, truth, odo, &mut k);
    assert_eq!(
        out.odometry,
        OdometryStatus::Rejected(OdometryRejection::Implausible)
    );
    truth = truth.compose(&step);
    odo = odo.compose(&step);
    let out = feed(&mut front_end, truth, odo, &mut k);
    assert_eq!(out.odometry, OdometryStatus::Used);
    // A step 15 cm sideways of the wheels' pace (the mean over their last 0.2 s, 0.15 s
    // before this step's middle: 10 m/s^2): stale.
    truth = truth.compose(&step);
    odo = odo.compose(&step);
    let out = feed(
        &mut front_end,
        truth,
        odo.compose(&Pose2::new(0.0, 0.15, 0.0)),
        &mut k,
    );
    assert!(
        matches!(
            out.odometry,
            OdometryStatus::Rejected(OdometryRejection::Stale { acceleration })
                if (acceleration - 10.0).abs() < 0.5
        ),
        "{out:?}"
    );
    assert_close(&out.increment, &step, 0.01, 0.005);
    assert_eq!(out.wheel_increment, None, "a stale step is no odometer");
    // The next reading is on course again: measured from the last one believed, used.
    truth = truth.compose(&step);
    odo = odo.compose(&step);
    let out = feed(&mut front_end, truth, odo, &mut k);
    assert_eq!(out.odometry, OdometryStatus::Used);
    assert_close(&out.increment, &step, 0.01, 0.005);
    let wheels = out.wheel_increment.expect("the wheels' step, used");
    assert_close(&wheels, &step, 0.01, 0.005);
    // A step at the pace but turned 0.15 rad too far (15 sigma): the match overrules it.
    truth = truth.compose(&step);
    odo = odo.compose(&step);
    let out = feed(
        &mut front_end,
        truth,
        odo.compose(&Pose2::new(0.0, 0.0, 0.15)),
        &mut k,
    );
    assert!(
        matches!(
            out.odometry,
            OdometryStatus::Rejected(OdometryRejection::Inconsistent { .. })
        ),
        "{out:?}"
    );
    assert_close(&out.increment, &step, 0.01, 0.005);
    // The overruled step is still the wheels' word, for whoever weighs both.
    let wheels = out.wheel_increment.expect("the wheels' step, overruled");
    assert_close(
        &wheels,
        &step.compose(&Pose2::new(0.0, 0.0, 0.15)),
        1e-9,
        1e-9,
    );
    let stats = front_end.stats();
    assert_eq!(
        stats.odometry_rejected,
        OdometryRejections {
            not_finite: 1,
            implausible: 4,
            inconsistent: 1,
            stale: 1,
        }
    );
    assert_eq!(stats.odometry_rejected.total(), 7);
    assert_eq!(stats.failed_matches, 0);
    assert!(stats.odometry_used >= 5);
}

#[test]
fn without_odometry_or_points_the_motion_is_constant_velocity() {
    let walls = room();
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let step = Pose2::new(0.1, 0.02, 0.01);
    let mut truth = Pose2::IDENTITY;
    for k in 0..6 {
        let ranges = raycast(&walls, &truth, &SICK, 361, 0.0);
        front_end.process(&scan(k, &ranges, SICK, None)).unwrap();
        truth = truth.compose(&step);
    }
    let blind = vec![f32::NAN; 361];
    let before = front_end.pose();
    let out = front_end.process(&scan(6, &blind, SICK, None)).unwrap();
    assert_eq!(out.status, MatchStatus::Failed(MatchFailure::TooFewPoints));
    assert_eq!(out.points, 0);
    assert_close(&out.increment, &step, 0.003, 0.001);
    assert_close(&before.compose(&step), &out.odom_from_robot, 0.003, 0.001);
    assert_eq!(front_end.stats().failed_matches, 1);
}

// Three seconds of scans that see nothing (a sensor blinded), without odometry, while the
// robot drives on: the front end carries it on at its speed for a second and then holds it, each step's covariance its own; the stretch is counted,
// and the first scan that sees again is found by a wide search against the map.
#[test]
fn a_stretch_of_scans_that_do_not_register_stays_bounded_and_is_recovered() {
    let walls = room();
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let step = Pose2::new(0.05, 0.0, 0.01);
    let mut truth = Pose2::new(0.5, 0.2, 0.1);
    let start = truth;
    let mut k = 0;
    for _ in 0..8 {
        let ranges = raycast(&walls, &truth, &SICK, 361, 0.005);
        front_end.process(&scan(k, &ranges, SICK, None)).unwrap();
        truth = truth.compose(&step);
        k += 1;
    }
    let blind = vec![f32::NAN; 361];
    let before = front_end.pose();
    let mut covariances = Vec::new();
    for _ in 0..30 {
        let out = front_end.process(&scan(k, &blind, SICK, None)).unwrap();
        assert_eq!(out.status, MatchStatus::Failed(MatchFailure::TooFewPoints));
        covariances.push(out.increment_covariance[(0, 0)]);
        truth = truth.compose(&step);
        k += 1;
    }
    // Carried on for a second (ten scans of 5 cm), then held.
    let drifted = before.between(&front_end.pose());
    assert!(
        (drifted.x - 0.5).abs() < 0.03,
        "{drifted:?} after three blind seconds"
    );
    // Each step's covariance is its own, not the stretch's so far.
    assert!(
        covariances
            .iter()
            .all(|&c| (c - covariances[0]).abs() < 1e-9),
        "{covariances:?}"
    );
    let stats = front_end.stats();
    assert_eq!(stats.failed_matches, 30);
    assert_eq!(stats.longest_unregistered, 30);
    let searched = stats.wide_searches;
    // The robot is a metre beyond where it was held: further than a regular step's window
    // reaches, within the stretch's.
    let ranges = raycast(&walls, &truth, &SICK, 361, 0.005);
    let out = front_end.process(&scan(k, &ranges, SICK, None)).unwrap();
    assert!(!matches!(out.status, MatchStatus::Failed(_)), "{out:?}");
    let stats = front_end.stats();
    assert!(stats.wide_searches > searched, "{stats:?}");
    assert!(stats.recovered >= 1, "{stats:?}");
    assert_close(&front_end.pose(), &start.between(&truth), 0.03, 0.01);
}

#[test]
fn a_turn_during_a_gap_in_the_data_is_recovered_without_odometry() {
    for (geometry, beams) in [(SICK, 361), (HOKUYO, 1081)] {
        let walls = room();
        let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
        let step = Pose2::new(0.05, 0.0, 0.02);
        let mut truth = Pose2::new(0.5, 0.2, 0.1);
        for k in 0..5 {
            let ranges = raycast(&walls, &truth, &geometry, beams, 0.005);
            front_end
                .process(&scan(k, &ranges, geometry, None))
                .unwrap();
            truth = truth.compose(&step);
        }
        // Three seconds without scans, in which the robot turned far beyond the search
        // window of a regular step and moved a little.
        let turn = Pose2::new(0.25, -0.1, -1.4);
        let before = front_end.pose();
        truth = truth.compose(&turn);
        let ranges = raycast(&walls, &truth, &geometry, beams, 0.005);
        let out = front_end
            .process(&scan(4 + 30, &ranges, geometry, None))
            .unwrap();
        assert!(
            matches!(out.status, MatchStatus::Matched),
            "{beams} beams: {out:?}"
        );
        assert_close(
            &before.between(&out.odom_from_robot),
            &step.compose(&turn),
            0.02,
            0.01,
        );
        // And the matching goes on from there.
        truth = truth.compose(&step);
        let ranges = raycast(&walls, &truth, &geometry, beams, 0.005);
        let out = front_end
            .process(&scan(4 + 31, &ranges, geometry, None))
            .unwrap();
        assert_eq!(out.status, MatchStatus::Matched, "{out:?}");
        assert_close(&out.increment, &step, 0.01, 0.005);
    }
}

#[test]
fn without_odometry_a_corridors_weak_evidence_says_when_the_robot_moves_and_stops() {
    // A corridor whose only feature along its length is a shallow recess: the scan says
    // little about the motion along it, but not nothing. Its sides are 25 cm: a face not
    // much longer than the 20 cm of wall a normal is fitted over gives no normal at all.
    let walls = corridor_with_recess(2.0, 2.6, 0.25);
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let step = Pose2::new(0.1, 0.0, 0.0);
    let mut truth = Pose2::IDENTITY;
    let mut degenerate = 0;
    for k in 0..40 {
        let ranges = raycast(&walls, &truth, &SICK, 361, 0.005);
        let out = front_end.process(&scan(k, &ranges, SICK, None)).unwrap();
        if matches!(out.status, MatchStatus::Degenerate { .. }) {
            degenerate += 1;
        }
        if k < 10 {
            truth = truth.compose(&step);
        }
    }
    // Out of the recess's view the corridor leaves its length open.
    assert!(degenerate > 0, "{degenerate}");
    // A metre driven from standing (the velocity guess says: standing), then thirty scans
    // standing still (the velocity guess says: 3 m on).
    let drift = front_end.pose().x - truth.x;
    assert!(drift.abs() < 0.5, "{:?} vs {truth:?}", front_end.pose());
}

#[test]
fn without_odometry_a_recess_that_comes_into_view_teaches_the_motion_along_a_corridor() {
    // The first scan sees two bare walls; a recess 8 m ahead comes into view only after a
    // few metres. The velocity guess starts at standing, and standing is all the bare
    // walls can confirm: the front end learns the robot moves only if the recess reaches
    // its map, although it has not (by its own estimate) moved a keyframe's distance.
    let walls = corridor_with_recess(8.0, 9.2, 0.4);
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let mut estimates = Vec::new();
    for k in 0..=100u64 {
        let truth = Pose2::new(0.1 * k as f64, 0.0, 0.0);
        let ranges = raycast(&walls, &truth, &SICK, 361, 0.005);
        estimates.push(front_end.process(&scan(k, &ranges, SICK, None)).unwrap());
    }
    // The advance the front end measured from 6 m to 9 m, with the recess in view.
    let advance = estimates[90].odom_from_robot.x - estimates[60].odom_from_robot.x;
    assert!((advance - 3.0).abs() < 0.3, "advanced {advance} m of 3 m");
}

/// The true poses of a drive along the room, 8 cm and 0.005 rad a scan.
fn drive_through_room(scans: usize) -> Vec<Pose2> {
    let step = Pose2::new(0.08, 0.0, 0.005);
    std::iter::successors(Some(Pose2::new(-3.0, -2.0, 0.0)), |p| {
        Some(p.compose(&step))
    })
    .take(scans)
    .collect()
}

#[test]
fn wheels_that_freeze_and_catch_up_are_measured_from_before_they_froze() {
    let walls = room();
    let truth = drive_through_room(14);
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let mut statuses = Vec::new();
    for (k, pose) in truth.iter().enumerate() {
        // The wheels report nothing new for scans 5 to 8, then the whole motion at once.
        let reported = if (5..=8).contains(&k) { 4 } else { k };
        let wheels = odometry(truth[0].between(&truth[reported]), 1e-4 * reported as f64);
        let ranges = raycast(&walls, pose, &SICK, 361, 0.0);
        let out = front_end
            .process(&scan(k as u64, &ranges, SICK, Some(wheels)))
            .unwrap();
        if k > 0 {
            assert_close(&out.increment, &truth[k - 1].between(pose), 0.01, 0.005);
        }
        statuses.push(out.odometry);
    }
    // Standing still at 0.8 m/s breaks the wheels' pace: stale.
    assert_stale(&statuses, 5..9);
    // The catch-up agrees with the scans since scan 4: believed, not rejected as a jump.
    assert_eq!(statuses[9], OdometryStatus::Used);
    assert!(statuses[10..].iter().all(|s| *s == OdometryStatus::Used));
}

#[test]
fn stale_wheel_readings_in_a_corridor_do_not_stop_the_robot() {
    // mit-csail's odometry reaches some scans late: a reading stands still for a scan or
    // two, then the wheels make up for it.
    let walls = corridor();
    let step = Pose2::new(0.12, 0.0, 0.0);
    let truth: Vec<Pose2> =
        std::iter::successors(Some(Pose2::new(0.0, 0.2, 0.0)), |p| Some(p.compose(&step)))
            .take(14)
            .collect();
    // What the wheels had counted when each scan took its reading: 1.2 m/s, scan 4's count
    // still at scans 5 and 6, on time again from scan 7.
    let counted = |k: usize| 0.12 * if (5..=6).contains(&k) { 4 } else { k } as f64;
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let mut statuses = Vec::new();
    for (k, pose) in truth.iter().enumerate() {
        let wheels = odometry(Pose2::new(counted(k), 0.0, 0.0), 1e-4 * k as f64);
        let ranges = raycast(&walls, pose, &SICK, 361, 0.0);
        let out = front_end
            .process(&scan(k as u64, &ranges, SICK, Some(wheels)))
            .unwrap();
        if k > 0 {
            assert!(
                matches!(out.status, MatchStatus::Degenerate { .. }),
                "{k}: {out:?}"
            );
            // Along the corridor only the pace tells: the step is the robot's.
            assert_close(&out.increment, &step, 0.01, 0.005);
        }
        statuses.push(out.odometry);
    }
    // The standing readings are stale; the one that makes up for them is measured from
    // the last reading believed, and used.
    assert_stale(&statuses, 5..7);
    assert!(statuses[7..].iter().all(|s| *s == OdometryStatus::Used));
    // Wheels that did stop are believed once they have stood still for longer than a
    // stale reading lags.
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    let mut stopped = Vec::new();
    for k in 0..60usize {
        let x = 0.12 * k.min(10) as f64;
        let pose = Pose2::new(x, 0.2, 0.0);
        let wheels = odometry(Pose2::new(x, 0.0, 0.0), 1e-4 * k as f64);
        let ranges = raycast(&walls, &pose, &SICK, 361, 0.0);
        let out = front_end
            .process(&scan(k as u64, &ranges, SICK, Some(wheels)))
            .unwrap();
        stopped.push((out.odometry, front_end.pose()));
    }
    let (status, end) = stopped[59];
    assert_eq!(status, OdometryStatus::Used);
    assert!((end.x - 1.2).abs() < 0.05, "{end:?}");
}

#[test]
fn wheels_that_count_four_per_cent_too_far_are_learnt() {
    let walls = room();
    let truth = drive_through_room(120);
    let mut front_end = FrontEnd::new(FrontEndConfig::default()).unwrap();
    assert_eq!(front_end.odometry_scale(), 1.0);
    for (k, pose) in truth.iter().enumerate() {
        let moved = truth[0].between(pose);
        let long = Pose2::new(1.04 * moved.x, 1.04 * moved.y, moved.yaw);
        let ranges = raycast(&walls, pose, &SICK, 361, 0.0);
        let out = front_end
            .process(&scan(
                k as u64,
                &ranges,
                SICK,
                Some(odometry(long, 1e-4 * k as f64)),
            ))
            .unwrap();
        if k > 0 {
            assert_eq!(out.odometry, OdometryStatus::Used, "{k}");
        }
    }
    let scale = front_end.odometry_scale();
    assert!((scale - 1.0 / 1.04).abs() < 0.005, "{scale}");
}
