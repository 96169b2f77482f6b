//! ROS 2 bags replayed through slam-launch: mit-csail written as a bag by an independent
//! writer (the Python `rosbags` package, in a virtual environment the test makes) scores
//! as the CARMEN log does, in both storages; damaged bags are refused or replayed up to
//! the damage, never a panic.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use tests::*;

/// Where the laser sits ahead of base_link in the bags written here (on /tf_static).
const LASER_OFFSET_M: f64 = 0.25;
/// The bag's replay scores within this fraction of the CARMEN replay's (mean translational
/// and rotational relative-pose error, same seed): the bag's odometry is base_link's and is
/// carried to the laser through the mount, its covariance with it, so the runs are alike
/// but not bit for bit.
const SCORE_TOLERANCE: f64 = 0.10;
/// The seed and particle count of both runs.
const SEED_1_100_PARTICLES: [&str; 4] = ["--seed", "1", "--particles", "100"];

/// The Python that has `rosbags`: a virtual environment under the target directory, made
/// (and `rosbags` installed from PyPI) once, kept for later runs. Panics, saying what is
/// missing, when it cannot be made.
fn rosbags_python() -> PathBuf {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON
        .get_or_init(|| {
            let venv = bin_dir().join("e2e-scratch").join("rosbags-venv");
            let python = venv.join("bin").join("python");
            let has_rosbags = |python: &Path| {
                Command::new(python)
                    .args(["-c", "import rosbags.rosbag2, numpy"])
                    .output()
                    .is_ok_and(|out| out.status.success())
            };
            if has_rosbags(&python) {
                return python;
            }
            let _ = std::fs::remove_dir_all(&venv);
            let made = Command::new("python3")
                .args(["-m", "venv"])
                .arg(&venv)
                .output()
                .unwrap_or_else(|e| panic!("cannot run python3 (needed to write ROS 2 bags): {e}"));
            assert!(
                made.status.success(),
                "python3 -m venv {} failed (install python3-venv): {}",
                venv.display(),
                String::from_utf8_lossy(&made.stderr)
            );
            let installed = Command::new(&python)
                .args(["-m", "pip", "install", "--quiet", "rosbags"])
                .output()
                .expect("run pip");
            assert!(
                installed.status.success(),
                "pip install rosbags failed: {}",
                String::from_utf8_lossy(&installed.stderr)
            );
            assert!(has_rosbags(&python), "rosbags installed but not importable");
            python
        })
        .clone()
}

/// Writes `log` as a ROS 2 bag in `storage` (`mcap` or `sqlite3`) at `bag` with
/// tests/scripts/clf_to_rosbag2.py and `extra` arguments.
fn write_bag(log: &Path, bag: &Path, storage: &str, extra: &[&str]) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/clf_to_rosbag2.py");
    let _ = std::fs::remove_dir_all(bag);
    let output = Command::new(rosbags_python())
        .arg(script)
        .arg(log)
        .arg(bag)
        .args([
            "--storage",
            storage,
            "--laser-offset",
            &LASER_OFFSET_M.to_string(),
        ])
        .args(extra)
        .output()
        .expect("run clf_to_rosbag2.py");
    assert!(
        output.status.success(),
        "clf_to_rosbag2.py failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// The run's `trajectory.tum` (base_link poses) moved `LASER_OFFSET_M` forward to the
/// laser, scored against `relations`.
fn laser_score(out: &Path, relations: &[slam_eval::Relation]) -> slam_eval::Score {
    let base = slam_eval::Trajectory::read_tum(&out.join("trajectory.tum")).unwrap();
    let mount = slam_eval::from_xyz_rpy([LASER_OFFSET_M, 0.0, 0.0], 0.0, 0.0, 0.0);
    let laser = base
        .iter()
        .map(|(stamp, pose)| (stamp, pose * mount))
        .collect();
    let laser = slam_eval::Trajectory::new(laser).unwrap();
    slam_eval::score(&laser, relations, slam_eval::DEFAULT_TOLERANCE_NS)
}

fn within(what: &str, bag: f64, carmen: f64) {
    assert!(
        (bag - carmen).abs() <= SCORE_TOLERANCE * carmen,
        "{what}: the bag's {bag} is not within {SCORE_TOLERANCE} of the CARMEN replay's {carmen}"
    );
}

#[test]
fn mit_csail_as_a_ros2_bag_scores_as_its_carmen_log_in_both_storages() {
    let log = test_data::carmen_log("mit-csail");
    let relations_file = log.with_extension("relations");
    let relations = slam_eval::read_relations(&relations_file).unwrap();
    let carmen = replayed(
        "rosbag-carmen",
        &log,
        &[&["--format", "carmen"][..], &SEED_1_100_PARTICLES].concat(),
    );
    let carmen_score = slam_eval::score(
        &slam_eval::Trajectory::read_tum(&carmen.out.join("trajectory.tum")).unwrap(),
        &relations,
        slam_eval::DEFAULT_TOLERANCE_NS,
    );
    let dir = scratch("rosbag-bags");
    for storage in ["mcap", "sqlite3"] {
        let bag = dir.join(format!("mit-csail-{storage}"));
        write_bag(&log, &bag, storage, &[]);
        // No --format: a directory is a bag.
        let run = replayed(
            &format!("rosbag-{storage}"),
            &bag,
            &[
                &["--relations", relations_file.to_str().unwrap()][..],
                &SEED_1_100_PARTICLES,
            ]
            .concat(),
        );
        let metrics = metrics(&run.out);
        assert_eq!(metrics.frames_processed, 1988, "{storage}");
        let stderr = String::from_utf8_lossy(&run.output.stderr);
        assert_eq!(
            summary_line(&stderr, "published:"),
            "1988 scans, 1988 odometry poses",
            "{storage}: {stderr}"
        );
        assert_eq!(summary_line(&stderr, "bad messages:"), "0", "{stderr}");
        // The trajectory is base_link's: its first pose is the mount behind the laser's.
        let [x, y, _] = read_tum(&run.out.join("trajectory.tum"))[0].position;
        assert!(
            (x + LASER_OFFSET_M).abs() < 1e-9 && y.abs() < 1e-9,
            "{storage}: first pose at {x}, {y}"
        );
        let score = laser_score(&run.out, &relations);
        assert_eq!(score.used, carmen_score.used, "{storage}");
        within(
            &format!("{storage}: mean translational error (m)"),
            score.translation_m.mean,
            carmen_score.translation_m.mean,
        );
        within(
            &format!("{storage}: mean rotational error (deg)"),
            score.rotation_deg.mean,
            carmen_score.rotation_deg.mean,
        );
        assert!(shm_leftovers(&run.domain).is_empty());
    }
    assert!(shm_leftovers(&carmen.domain).is_empty());
}

#[test]
fn damaged_bags_are_refused_or_replayed_up_to_the_damage() {
    let log = test_data::carmen_log("mit-csail");
    let dir = scratch("rosbag-damaged");

    // A record of another type on /scan: counted and skipped.
    let wrong = dir.join("wrong-type");
    write_bag(
        &log,
        &wrong,
        "mcap",
        &["--frames", "300", "--wrong-type-after", "100"],
    );
    let run = replayed("rosbag-wrong-type", &wrong, &[]);
    let stderr = String::from_utf8_lossy(&run.output.stderr);
    assert_eq!(
        summary_line(&stderr, "published:"),
        "300 scans, 300 odometry poses"
    );
    assert_eq!(
        summary_line(&stderr, "bad messages:"),
        "1 skipped, by reason:",
        "{stderr}"
    );
    assert_eq!(
        summary_line(&stderr, "/scan: message of another type:"),
        "1"
    );

    // A bag cut short: replayed up to the damage, which the console names.
    let cut = dir.join("cut");
    write_bag(&log, &cut, "mcap", &["--frames", "600"]);
    let file = cut.join("cut.mcap");
    let size = std::fs::metadata(&file).unwrap().len();
    let opened = std::fs::OpenOptions::new().write(true).open(&file).unwrap();
    opened.set_len(size / 2).unwrap();
    let run = replayed("rosbag-cut", &cut, &[]);
    let stderr = String::from_utf8_lossy(&run.output.stderr);
    let cut_short = summary_line(&stderr, "cut short:");
    assert!(
        cut_short.starts_with("the bag cannot be read past its message "),
        "{cut_short}"
    );
    let scans: u64 = summary_count(&stderr, "published:");
    assert!(
        (100..600).contains(&scans),
        "{scans} scans of 600 published"
    );
    assert_eq!(metrics(&run.out).frames_processed, scans);

    // Metadata naming a file that is not there: refused before anything starts.
    let missing = dir.join("missing");
    write_bag(&log, &missing, "sqlite3", &["--frames", "50"]);
    std::fs::remove_file(missing.join("missing.db3")).unwrap();
    let output = launch_replay(
        &domain("rosbag-missing"),
        &dir.join("missing-out"),
        &missing,
        &[],
    );
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!(
            "{} names {}, which is missing",
            missing.join("metadata.yaml").display(),
            missing.join("missing.db3").display()
        )),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");

    // A directory that is no bag, and a bag without a scan topic: refused, saying why.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let output = launch_replay(&domain("rosbag-empty"), &dir.join("empty-out"), &empty, &[]);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("is a directory without metadata.yaml: not a rosbag2 bag"),
        "{stderr}"
    );
    let output = launch_replay(
        &domain("rosbag-no-topic"),
        &dir.join("no-topic-out"),
        &wrong,
        &["--scan-topic", "/laser"],
    );
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("the bag has no topic /laser (--scan-topic); its topics: /tf_static (tf2_msgs/msg/TFMessage), /scan (sensor_msgs/msg/LaserScan)"),
        "{stderr}"
    );
}
