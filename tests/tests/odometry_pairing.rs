//! A replay whose odometry runs on a clock of its own, between the scans, repeats exactly:
//! the odometry paired with a scan depends on the log, not on which topic was read first.

use std::fmt::Write as _;
use std::path::Path;

use lidar_sim::{Simulation, World};
use tests::*;

/// Scans in the fixture: enough for the race between the two topics to show up many
/// times over when the pairing depends on timing.
const SCANS: usize = 600;
/// The odometry's clock runs this far behind the scans' and at 100 Hz against the scans'
/// 40 Hz, so almost every scan falls between two readings.
const ODOMETRY_OFFSET_NS: u64 = 3_700_000;
const ODOMETRY_PERIOD_NS: u64 = 10_000_000;
/// Log clock of the first scan (CARMEN stamps are seconds; not 0, as in real logs).
const START_NS: u64 = 1_000_000_000_000;

fn seconds(ns: u64) -> String {
    format!("{}.{:09}", ns / 1_000_000_000, ns % 1_000_000_000)
}

/// A CARMEN log of the simulated hall: `ROBOTLASER1` scans (whose robot pose is not
/// replayed as odometry) and `ODOM` lines at their own times, interpolated from the
/// simulator's noisy odometry, each written in time order with the scans.
fn write_fixture(path: &Path) {
    let world = World::builtin("hall").expect("hall");
    let sensor = lidar_sim::SensorConfig::default();
    let (angle_min, increment, range_max) =
        (sensor.angle_min, sensor.angle_increment, sensor.range_max);
    let mut simulation = Simulation::new(world, sensor, Default::default(), 7).expect("sim");
    let frames: Vec<_> = (0..SCANS).map_while(|_| simulation.next_frame()).collect();
    assert_eq!(frames.len(), SCANS, "the hall's path is long enough");

    let mut log = String::from("# odometry on its own clock, between the scans\n");
    let mut next_odometry = START_NS + ODOMETRY_OFFSET_NS;
    for pair in frames.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let (ta, tb) = (START_NS + a.stamp_ns, START_NS + b.stamp_ns);
        let ranges: Vec<String> = a
            .ranges
            .iter()
            .map(|r| {
                let r = if r.is_finite() {
                    f64::from(*r)
                } else {
                    range_max
                };
                format!("{r:.4}")
            })
            .collect();
        writeln!(
            log,
            "ROBOTLASER1 0 {angle_min} {} {increment} {range_max} 0.01 0 {} {} 0 \
             0 0 0 {} {} {} 0 0 0 0 0 {} host {}",
            increment * ranges.len() as f64,
            ranges.len(),
            ranges.join(" "),
            a.pose.x,
            a.pose.y,
            a.pose.yaw,
            seconds(ta),
            seconds(ta)
        )
        .unwrap();
        while next_odometry < tb {
            let t = (next_odometry - ta) as f64 / (tb - ta) as f64;
            let yaw_step = lidar_sim::wrap_angle(b.odometry.yaw - a.odometry.yaw);
            writeln!(
                log,
                "ODOM {} {} {} 0 0 0 {} host {}",
                a.odometry.x + t * (b.odometry.x - a.odometry.x),
                a.odometry.y + t * (b.odometry.y - a.odometry.y),
                lidar_sim::wrap_angle(a.odometry.yaw + t * yaw_step),
                seconds(next_odometry),
                seconds(next_odometry)
            )
            .unwrap();
            next_odometry += ODOMETRY_PERIOD_NS;
        }
    }
    std::fs::write(path, log).expect("write the fixture");
}

#[test]
fn a_replay_with_separate_odometry_lines_repeats_exactly() {
    let dir = scratch("odometry-pairing");
    let log = dir.join("separate-odom.clf");
    write_fixture(&log);
    let log = log.to_str().expect("utf-8 path");

    let run = |tag: &str| {
        let out = dir.join(tag);
        let output = launch(
            &domain(&format!("pairing-{tag}")),
            &out,
            &["--replay", log, "--format", "carmen", "--seed", "3"],
        );
        assert_success(&output);
        std::fs::read_to_string(out.join("trajectory.tum")).expect("trajectory.tum")
    };
    let first = run("first");
    let second = run("second");
    // One pose per scan but the last (the fixture's final frame closes the last interval).
    assert_eq!(read_tum(&dir.join("first/trajectory.tum")).len(), SCANS - 1);
    assert!(
        first == second,
        "two replays of one log gave different trajectories"
    );
    // The odometry was used: without it the estimate differs.
    let out = dir.join("no-odometry");
    assert_success(&launch(
        &domain("pairing-none"),
        &out,
        &[
            "--replay",
            log,
            "--format",
            "carmen",
            "--seed",
            "3",
            "--no-odometry",
        ],
    ));
    let without = std::fs::read_to_string(out.join("trajectory.tum")).expect("trajectory.tum");
    assert_ne!(first, without, "the replay's odometry made no difference");
}
