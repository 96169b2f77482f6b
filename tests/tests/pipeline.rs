//! The whole pipeline through `slam-launch`: the real binaries, real shared memory.

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use tests::*;

const RESULT_FILES: [&str; 6] = [
    "trajectory.tum",
    "ground_truth.tum",
    "map_corners.csv",
    "map.svg",
    "metrics.json",
    "config.toml",
];

/// Runs a simulated world and checks everything a run must leave behind.
fn run_world(world: &str, frames: u64, particles: u32, ate_limit: f64) -> slam_eval::Metrics {
    let domain = domain(&format!("{}-{frames}", world.replace(['/', '.', '_'], "-")));
    let out = scratch(&format!("world-{}", world.replace('/', "-")));
    let frames_arg = frames.to_string();
    let particles_arg = particles.to_string();
    let output = launch(
        &domain,
        &out,
        &[
            "--world",
            world,
            "--frames",
            &frames_arg,
            "--particles",
            &particles_arg,
            "--seed",
            "1",
        ],
    );
    assert_success(&output);
    for file in RESULT_FILES {
        assert!(
            out.join(file).is_file(),
            "{file} missing in {}",
            out.display()
        );
    }
    let metrics = metrics(&out);
    let published = metrics.frames_published;
    assert!(published > 0);
    assert_eq!(metrics.frames_processed, published, "{metrics:?}");
    assert_eq!(metrics.frames_dropped, 0, "{metrics:?}");
    let trajectory = read_tum(&out.join("trajectory.tum"));
    assert_eq!(trajectory.len() as u64, published);
    assert_eq!(
        read_tum(&out.join("ground_truth.tum")).len() as u64,
        published
    );
    assert!(
        trajectory.windows(2).all(|w| w[1].stamp_ns > w[0].stamp_ns),
        "stamps must increase"
    );
    let ate = metrics.ate_rmse_m.expect("metrics.json has ate_rmse_m");
    assert!(
        ate <= ate_limit,
        "{world}: ATE RMSE {ate} m > {ate_limit} m: {metrics:?}"
    );
    let csv = std::fs::read_to_string(out.join("map_corners.csv")).unwrap();
    assert!(csv.starts_with("x,y,heading,angle,"));
    assert_eq!(csv.lines().count() - 1, metrics.map_corners);
    let svg = std::fs::read_to_string(out.join("map.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(
        shm_leftovers(&domain).is_empty(),
        "{:?}",
        shm_leftovers(&domain)
    );
    metrics
}

#[test]
fn office_loop_is_mapped_within_target() {
    // The whole loop (109 m, about 4 s in lockstep): closing it is what the filter is
    // for. Target 0.10 m; the margin keeps a busy CI machine from flaking.
    let metrics = run_world("office", 0, 100, 0.15);
    // The filter must beat the scan-matching motion integrated alone. (On an open stretch
    // it need not: the motion estimate drifts by millimetres there, and the particles'
    // noise costs about as much as the map gives back.)
    let dead_reckoning = metrics
        .dead_reckoning_ate_rmse_m
        .expect("metrics.json has dead_reckoning_ate_rmse_m");
    assert!(
        metrics.ate_rmse_m.expect("metrics.json has ate_rmse_m") < dead_reckoning,
        "{metrics:?}"
    );
    assert!(
        metrics
            .map_corner_rmse_m
            .expect("metrics.json has map_corner_rmse_m")
            < 0.08,
        "{metrics:?}"
    );
}

#[test]
fn a_180_degree_scanner_does_not_close_the_office_loop_onto_a_look_alike() {
    // A SICK LMS-like scanner (181 beams at 1 degree, nothing behind it) sees few corners
    // a scan, and near the end of the loop two old corners of the repeated rooms fit a
    // landing 5.7 m from the prediction, beyond what the drift allows for at 95 %: taken,
    // the loop closed onto the wrong room (ATE 1.4-1.5 m). Seeds 1-3 measure 0.010-0.031 m;
    // the front end alone 0.10 m.
    let config_dir = scratch("sick-office-config");
    let config = config_dir.join("sick.toml");
    std::fs::write(
        &config,
        "[sim.sensor]\nbeams = 181\nangle_min = -1.5707963267948966\n\
         angle_increment = 0.017453292519943295\nrange_max = 50.0\n",
    )
    .expect("sick.toml");
    let run = launched(
        "sick-office",
        &[
            "--world",
            "office",
            "--seed",
            "1",
            "--config",
            config.to_str().expect("a UTF-8 path"),
        ],
    );
    let metrics = metrics(&run.out);
    let ate = metrics.ate_rmse_m.expect("metrics.json has ate_rmse_m");
    let dead_reckoning = metrics
        .dead_reckoning_ate_rmse_m
        .expect("metrics.json has dead_reckoning_ate_rmse_m");
    assert!(ate < 0.15 && ate < dead_reckoning, "{metrics:?}");
}

#[test]
fn hall_is_mapped_within_target() {
    run_world("hall", 800, 100, 0.25);
}

#[test]
fn the_corridor_walls_keep_the_estimate_on_course() {
    // Without odometry, between the door recesses only the walls carry the heading and
    // constant velocity the advance; the front end learns that advance from each recess
    // as it comes into view (a front end that never takes one into its map stands still
    // for 45 m, ATE over 10 m). Seeds 1-3 measure 0.17-0.40 m; a bound, not a target.
    run_world("corridor", 0, 100, 0.6);
}

#[test]
fn two_pipelines_at_once_do_not_cross_and_repeat_exactly() {
    let outs = [scratch("twin-a"), scratch("twin-b")];
    let domains = [domain("twin-a"), domain("twin-b")];
    let children: Vec<_> = outs
        .iter()
        .zip(&domains)
        .map(|(out, domain)| {
            Command::new(bin("slam-launch"))
                .args(["--quiet", "--domain", domain, "--out"])
                .arg(out)
                .args([
                    "--world",
                    "office",
                    "--frames",
                    "300",
                    "--particles",
                    "30",
                    "--seed",
                    "7",
                ])
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .expect("slam-launch")
        })
        .collect();
    for child in children {
        assert_success(&child.wait_with_output().expect("slam-launch"));
    }
    // Same seed, lockstep: the runs must agree to the last digit; any cross-talk between
    // the two domains would have mixed their scans.
    let a = std::fs::read_to_string(outs[0].join("trajectory.tum")).unwrap();
    let b = std::fs::read_to_string(outs[1].join("trajectory.tum")).unwrap();
    assert_eq!(a.lines().count(), 300);
    assert_eq!(a, b);
    let corners_a = std::fs::read_to_string(outs[0].join("map_corners.csv")).unwrap();
    let corners_b = std::fs::read_to_string(outs[1].join("map_corners.csv")).unwrap();
    assert_eq!(corners_a, corners_b);
    for domain in &domains {
        assert!(shm_leftovers(domain).is_empty());
    }
}

/// The office loop in real time, so that the run lasts long enough to be disturbed halfway,
/// once `poses` poses are recorded; its console piped.
fn office_under_way(domain: &str, out: &Path, poses: usize) -> Child {
    let args = ["--world", "office", "--frames", "2000", "--rate", "40"];
    let mut child = spawn_launch(domain, out, &args, Stdio::piped());
    wait_for_poses(&mut child, out, poses, Duration::from_secs(60));
    child
}

#[test]
fn sigterm_halfway_leaves_a_valid_trajectory() {
    let domain = domain("sigterm");
    let out = scratch("sigterm");
    let child = office_under_way(&domain, &out, 40);
    send(pid_of(&child), Signal::SIGTERM);
    let trajectory = out.join("trajectory.tum");
    let output = child.wait_with_output().unwrap();
    assert_eq!(
        output.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let poses = read_tum(&trajectory);
    assert!(
        poses.len() >= 40 && poses.len() < 2000,
        "{} poses",
        poses.len()
    );
    assert!(
        out.join("metrics.json").is_file(),
        "map-sink writes its results on SIGTERM"
    );
    assert!(
        shm_leftovers(&domain).is_empty(),
        "{:?}",
        shm_leftovers(&domain)
    );
}

#[test]
fn a_world_file_works_like_a_builtin_world() {
    let dir = scratch("world-file");
    let world = dir.join("square.json");
    // A 20 x 14 m room with four pillars, driven round once.
    let pillar = |x: f64, y: f64| {
        format!(
            "[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]",
            x + 0.8,
            x + 0.8,
            y + 0.8,
            y + 0.8
        )
    };
    let text = format!(
        r#"{{"walls": [[[0,0],[20,0],[20,14],[0,14],[0,0]], {}, {}, {}, {}],
            "waypoints": [[3,3],[17,3],[17,11],[3,11],[3,3.5]], "speed": 1.0}}"#,
        pillar(6.0, 6.0),
        pillar(13.0, 6.0),
        pillar(6.0, 8.0),
        pillar(13.0, 8.0)
    );
    std::fs::write(&world, text).unwrap();
    let domain = domain("world-file");
    let out = dir.join("run");
    let output = launch(
        &domain,
        &out,
        &["--world", world.to_str().unwrap(), "--frames", "400"],
    );
    assert_success(&output);
    let metrics = metrics(&out);
    assert_eq!(metrics.frames_processed, 400);
    assert!(
        metrics.ate_rmse_m.expect("metrics.json has ate_rmse_m") < 0.3,
        "{metrics:?}"
    );
}

#[test]
fn a_bad_world_file_is_refused_by_name() {
    let dir = scratch("bad-world");
    let world = dir.join("bad.json");
    std::fs::write(
        &world,
        r#"{"walls": [[[0,0],[1,0]]], "waypoints": [[0.5, 0.5]]}"#,
    )
    .unwrap();
    let domain = domain("bad-world");
    let output = launch(
        &domain,
        &dir.join("run"),
        &["--world", world.to_str().unwrap()],
    );
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    // Refused by slam-launch before lidar-sim starts, naming the file and the problem.
    assert!(
        stderr.contains("refusing to start: world") && stderr.contains("bad.json"),
        "names the file: {stderr}"
    );
    assert!(stderr.contains("waypoint"), "names the problem: {stderr}");
    assert!(shm_leftovers(&domain).is_empty());
}

#[test]
fn a_killed_stage_is_named_and_stops_the_run() {
    let domain = domain("sigkill");
    let out = scratch("sigkill");
    let child = office_under_way(&domain, &out, 20);
    let slam_proc = child_named(pid_of(&child), "slam-proc").expect("slam-proc runs");
    send(slam_proc, Signal::SIGKILL);
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("slam-proc died (killed by signal 9)"),
        "{stderr}"
    );
    assert!(
        shm_leftovers(&domain).is_empty(),
        "{:?}",
        shm_leftovers(&domain)
    );
}
