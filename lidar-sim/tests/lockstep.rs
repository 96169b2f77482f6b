//! The simulator as a process: a subscriber in its own domain receives every scan in
//! lockstep, in order, each with its ground truth.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ipc_types::prelude::*;

mod common;
use common::Sim;

#[test]
fn lockstep_delivers_every_scan_with_its_ground_truth() {
    const FRAMES: u64 = 150;
    let frames = FRAMES.to_string();
    let Sim {
        child: mut sim,
        node,
        domain,
    } = Sim::start(
        "lockstep",
        &[
            "--world", "office", "--frames", &frames, "--rate", "0", "--seed", "3",
        ],
        Stdio::inherit(),
    );
    let truth = Inlet::open(&node, topic::GROUND_TRUTH).unwrap();
    let corners = Inlet::open(&node, topic::WORLD_CORNERS).unwrap();
    let scans = Inlet::open(&node, topic::SCAN).unwrap();
    assert_eq!(scans.delivery(), Delivery::Lossless);

    let mut scan_seqs = Vec::new();
    let mut truth_seqs = Vec::new();
    let mut world_corners = 0;
    let mut ended = false;
    let deadline = Instant::now() + Duration::from_secs(60);
    while !ended {
        assert!(
            Instant::now() < deadline,
            "timed out after {} scans",
            scan_seqs.len()
        );
        wait_any(&[&scans, &truth], Duration::from_millis(50)).unwrap();
        while let Some(sample) = corners.receive().unwrap() {
            world_corners = sample.corners().len();
        }
        while let Some(sample) = truth.receive().unwrap() {
            truth_seqs.push(sample.header.seq);
            assert!(sample.pose.x.is_finite() && sample.pose.yaw.abs() <= std::f64::consts::PI);
        }
        while let Some(scan) = scans.receive().unwrap() {
            if scan.header.is_end_of_stream() {
                assert_eq!(scan.header.seq, FRAMES, "the end marker counts the scans");
                ended = true;
                break;
            }
            assert_eq!(scan.ranges().len(), 1081);
            assert_eq!(scan.header.frame_id(), "laser");
            assert_eq!(
                scan.header.stamp_ns,
                scan.header.seq * 25_000_000,
                "40 Hz stamps"
            );
            let valid = scan.ranges().iter().filter(|r| r.is_finite()).count();
            assert!(
                valid > 500,
                "scan {} has only {valid} returns",
                scan.header.seq
            );
            scan_seqs.push(scan.header.seq);
        }
    }
    while let Some(sample) = truth.receive().unwrap() {
        truth_seqs.push(sample.header.seq);
    }
    let status = sim.wait().unwrap();
    assert!(status.success());
    let expected: Vec<u64> = (0..FRAMES).collect();
    assert_eq!(scan_seqs, expected, "every scan, in order, no gaps");
    assert_eq!(truth_seqs, expected, "a ground truth for each scan");
    assert!(
        world_corners > 20,
        "the world's corners arrive ({world_corners})"
    );
    drop((scans, truth, corners, node));
    domain.remove_leftovers().unwrap();
}

#[test]
fn a_bad_world_file_is_named_and_refused() {
    let dir = std::env::temp_dir().join(format!("sim-bad-world-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let world = dir.join("no-walls.json");
    std::fs::write(&world, r#"{"walls": [], "waypoints": [[0, 0], [1, 1]]}"#).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_lidar-sim"))
        .args([
            "--world",
            world.to_str().unwrap(),
            "--domain",
            "sim-bad-world",
        ])
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("wall"), "names the problem: {stderr}");
    let output = Command::new(env!("CARGO_BIN_EXE_lidar-sim"))
        .args(["--world", "atlantis", "--domain", "sim-bad-world"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("atlantis"));
    let _ = std::fs::remove_dir_all(dir);
}
