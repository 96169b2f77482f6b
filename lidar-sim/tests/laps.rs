//! Driving a world's route several times in a row (`--laps`): one run whose stamps, sequence
//! numbers, ground truth and noise carry on from lap to lap, a closed route driven round
//! without stopping, an open one back and forth, and one lap exactly as before.

use std::process::Command;

use lidar_sim::{
    BUILTIN_WORLDS, Laps, Pose2, SensorConfig, SimulatedScan, Simulation, VehicleConfig, World,
};

/// Scans 25 ms apart (the default sensor's 40 Hz).
const PERIOD_NS: u64 = 25_000_000;

fn world(name: &str) -> World {
    World::builtin(name).unwrap_or_else(|e| panic!("{e}"))
}

/// Every frame of `laps` laps of `name`, seed 1.
fn drive(name: &str, laps: i64, sensor: &SensorConfig) -> Vec<SimulatedScan> {
    let laps = Laps::new(laps).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::with_laps(
        world(name),
        sensor.clone(),
        VehicleConfig::default(),
        1,
        laps,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    std::iter::from_fn(|| sim.next_frame()).collect()
}

/// A few beams: the truth does not depend on the sensor, and the tests stay fast.
fn few_beams() -> SensorConfig {
    SensorConfig {
        beams: 11,
        angle_increment: 0.45,
        ..SensorConfig::default()
    }
}

/// Frames compared bit for bit (NaN dropouts included).
fn bits(f: &SimulatedScan) -> (u64, u64, [u64; 8], Vec<u32>) {
    let p = [
        f.pose.x,
        f.pose.y,
        f.pose.yaw,
        f.odometry.x,
        f.odometry.y,
        f.odometry.yaw,
        f.linear_velocity,
        f.angular_velocity,
    ];
    (
        f.seq,
        f.stamp_ns,
        p.map(f64::to_bits),
        f.ranges.iter().map(|r| r.to_bits()).collect(),
    )
}

/// FNV-1a over every frame's bits.
fn digest(frames: &[SimulatedScan]) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325_u64;
    let mut add = |x: u64| {
        for byte in x.to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for f in frames {
        let (seq, stamp, pose, ranges) = bits(f);
        add(seq);
        add(stamp);
        pose.into_iter().for_each(&mut add);
        ranges.into_iter().map(u64::from).for_each(&mut add);
    }
    hash
}

fn distance(a: Pose2, b: Pose2) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// Speed between frame `k - 1` and frame `k`, m/s.
fn speed(frames: &[SimulatedScan], k: usize) -> f64 {
    distance(frames[k].pose, frames[k - 1].pose) / (PERIOD_NS as f64 * 1e-9)
}

fn assert_stamps_carry_on(frames: &[SimulatedScan]) {
    for (k, f) in frames.iter().enumerate() {
        assert_eq!((f.seq, f.stamp_ns), (k as u64, k as u64 * PERIOD_NS));
    }
}

#[test]
fn one_lap_is_the_run_it_was_before_there_were_laps() {
    // Every frame of each world's whole run, seed 1, default sensor, as the simulator made
    // them before laps existed (7de36d4); a change to the sensor, the vehicle or a world
    // that is meant changes them too, and then belongs here.
    for (name, frames, expected) in [
        ("hall", 2585, 0x0945_9048_4079_f6d1_u64),
        ("office", 3958, 0xb1c1_53d8_6bcd_ccad),
        ("corridor", 2722, 0x1883_dd73_e2a7_1775),
    ] {
        let run = drive(name, 1, &SensorConfig::default());
        assert_eq!(run.len(), frames, "{name}");
        assert_eq!(digest(&run), expected, "{name}: {:016x}", digest(&run));
    }
}

#[test]
fn a_closed_route_is_driven_round_again_without_stopping() {
    let once = drive("office", 1, &few_beams());
    let thrice = drive("office", 3, &few_beams());
    assert_stamps_carry_on(&thrice);
    let cruise = world("office").speed;
    // The laps start where the route does, at (10, 6.4) heading east: crossed twice at
    // cruise speed, then the run ends there at rest.
    let starts: Vec<usize> = (1..thrice.len())
        .filter(|&k| thrice[k - 1].pose.x < 10.0 && thrice[k].pose.x >= 10.0)
        .filter(|&k| thrice[k].pose.y < 8.0 && speed(&thrice, k) > 0.5 * cruise)
        .collect();
    let end = thrice.len() - 1;
    let [second, third] = starts[..] else {
        panic!("lap starts at {starts:?}");
    };
    for k in [second, third] {
        let (pose, v) = (thrice[k].pose, speed(&thrice, k));
        assert!((v - cruise).abs() < 1e-3, "lap start {k}: {v} m/s");
        assert!(
            (pose.y - 6.4).abs() < 0.01 && pose.yaw.abs() < 0.05,
            "{pose:?}"
        );
    }
    assert!(distance(thrice[end].pose, Pose2::new(10.0, 6.4, 0.0)) < 0.05);
    assert!(speed(&thrice, end) < 4e-3, "at rest at the end");
    // A lap driven through takes the same time as the next; the first is longer by the
    // start from rest (cruise / (2 max_accel) = 1.2 s), and the last ends as one lap does.
    let lap = third - second;
    let start_from_rest = (second - lap) as f64 * PERIOD_NS as f64 * 1e-9;
    assert!((1.1..1.3).contains(&start_from_rest), "{start_from_rest} s");
    assert_eq!(end, once.len() - 1 + 2 * lap);
    // The second lap and the third drive the same line, up to where the third brakes for
    // the end (2.4 s from cruise to rest, 96 scans).
    for j in 0..lap - 100 {
        let gap = distance(thrice[second + j].pose, thrice[third + j].pose);
        assert!(gap < 0.01, "{j} frames into the lap: {gap} m apart");
    }
    // The first lap is the one-lap run, noise and all, until that run brakes for its end
    // (over its last 2.4 s, 96 scans).
    let parted = (0..once.len())
        .find(|&k| bits(&once[k]) != bits(&thrice[k]))
        .unwrap_or(once.len());
    assert!(
        (once.len() - 100..once.len()).contains(&parted),
        "parted at frame {parted} of {}",
        once.len()
    );
}

#[test]
fn a_lap_is_not_a_replay_of_the_last_ones_noise() {
    // The noise of a scan: its ranges less the same scan without noise (the truth does not
    // depend on the sensor's noise), compared a lap apart where the vehicle is on the same
    // line (see the test above).
    let noisy = drive("office", 3, &few_beams());
    let exact = drive("office", 3, &few_beams().noise_free());
    let noise = |k: usize| -> Vec<f32> {
        noisy[k]
            .ranges
            .iter()
            .zip(&exact[k].ranges)
            .map(|(n, e)| n - e)
            .collect()
    };
    let starts: Vec<usize> = (1..noisy.len())
        .filter(|&k| noisy[k - 1].pose.x < 10.0 && noisy[k].pose.x >= 10.0)
        .collect();
    let (second, third) = (starts[0], starts[1]);
    let mut same = 0;
    for j in 0..200 {
        let (a, b) = (noise(second + j), noise(third + j));
        same += a
            .iter()
            .zip(&b)
            .filter(|(x, y)| x.to_bits() == y.to_bits())
            .count();
    }
    // Dropouts (NaN less NaN) and the odd beam on the same wall may agree; a replayed
    // noise stream would make every beam agree.
    eprintln!(
        "{same} of {} beams with the same noise a lap apart",
        200 * 11
    );
    assert!(same < 200 * 11 / 20, "{same} of {} beams", 200 * 11);
}

#[test]
fn an_open_route_is_driven_back_and_forth() {
    let once = drive("corridor", 1, &few_beams());
    let thrice = drive("corridor", 3, &few_beams());
    assert_stamps_carry_on(&thrice);
    // The first lap is the one-lap run, noise and all, up to that run's last frame: the
    // vehicle arrives in the period before it, and has begun to turn round by then.
    let last = once.len() - 1;
    for (k, f) in once[..last].iter().enumerate() {
        assert_eq!(bits(f), bits(&thrice[k]), "frame {k}");
    }
    assert!(distance(once[last].pose, thrice[last].pose) < 1e-3);
    // Each lap ends at rest (under 4 mm/s), alternately at the far end and the start.
    let at_rest = |k: usize| speed(&thrice, k) < 4e-3;
    let ends: Vec<usize> = (1..thrice.len())
        .filter(|&k| at_rest(k) && !at_rest(k - 1))
        .collect();
    let end = thrice.len() - 1;
    assert_eq!(ends, [once.len() - 1, ends[1], end], "{ends:?}");
    for (k, [x, y]) in ends.iter().zip([[68.0, 1.25], [2.0, 1.25], [68.0, 1.25]]) {
        let pose = thrice[*k].pose;
        assert!(
            distance(pose, Pose2::new(x, y, 0.0)) < 0.05,
            "{k}: {pose:?}"
        );
    }
    // At an end the vehicle turns on the spot and leaves the way it came.
    let turned = thrice[ends[0] + 1..]
        .iter()
        .position(|f| distance(f.pose, thrice[ends[0]].pose) > 1e-3)
        .unwrap_or_else(|| panic!("never leaves the far end"));
    assert!(turned > 10, "{turned} frames standing");
    let away = thrice[ends[0] + turned + 100].pose;
    assert!(
        away.x < 67.5 && std::f64::consts::PI - away.yaw.abs() < 0.3,
        "4 s after the turn: {away:?}"
    );
    // The laps back and there again take the same time: the first lap's and a turn.
    let (second, third) = (ends[1] - ends[0], end - ends[1]);
    assert_eq!(second, third);
    let turn_s = (second - once.len() + 1) as f64 * PERIOD_NS as f64 * 1e-9;
    assert!((1.0..6.0).contains(&turn_s), "{turn_s} s to turn round");
}

#[test]
fn a_lap_count_out_of_range_is_refused_by_name() {
    for laps in ["0", "-1", "1001", "two"] {
        let output = Command::new(env!("CARGO_BIN_EXE_lidar-sim"))
            .args(["--frames", "1", "--domain", "sim-laps-refused"])
            .arg(format!("--laps={laps}"))
            .output()
            .expect("run lidar-sim");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "--laps {laps}: {stderr}");
        assert!(
            stderr.contains(&format!("invalid value '{laps}' for '--laps <N>'")),
            "{stderr}"
        );
        assert!(stderr.contains("laps"), "{stderr}");
        assert!(output.stdout.is_empty(), "refused before announcing ready");
    }
}

#[test]
fn every_world_is_driven_several_laps_to_the_right_end() {
    for name in BUILTIN_WORLDS {
        let w = world(name);
        let (first, last) = (w.waypoints[0], w.waypoints[w.waypoints.len() - 1]);
        let closed = first == last;
        for laps in [2, 3] {
            let frames = drive(name, laps, &few_beams());
            let once = drive(name, 1, &few_beams()).len() as f64;
            let end = frames[frames.len() - 1].pose;
            let goal = if closed || laps % 2 == 1 { last } else { first };
            assert!(
                distance(end, Pose2::new(goal[0], goal[1], 0.0)) < 0.05,
                "{name}, {laps} laps: ends at {end:?}"
            );
            let ratio = frames.len() as f64 / once;
            assert!(
                (laps as f64 - 0.1..laps as f64 + 0.1).contains(&ratio),
                "{name}, {laps} laps: {ratio} times one lap's scans"
            );
        }
    }
}
