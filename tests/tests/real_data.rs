//! The pipeline on the real Hokuyo recording: replayed from the log, and served by an
//! emulated sensor to the live driver.

use tests::*;

#[test]
fn seed_hall_replay_maps_the_hall_without_duplicate_corners() {
    let log = test_data::seed_hall_csv();
    let run = replayed(
        "seed-hall",
        &log,
        &["--format", "seed-csv", "--particles", "50"],
    );
    let metrics = metrics(&run.out);
    assert_eq!(metrics.frames_published, 400);
    assert_eq!(metrics.frames_processed, 400);
    let corners = read_map_corners(&run.out);
    assert!(corners.len() >= 20, "{} map corners", corners.len());
    let duplicates = duplicate_corners(&corners, 0.5, 0.5);
    assert!(duplicates.is_empty(), "duplicated corners: {duplicates:?}");
    // About 50 m through the hall, about 0.11 m a scan.
    let path = metrics.path_length_m;
    assert!((30.0..70.0).contains(&path), "path {path} m");
    assert!(shm_leftovers(&run.domain).is_empty());
}

#[test]
fn emulated_hokuyo_gives_the_same_map_as_the_replayed_log() {
    let log = test_data::seed_hall_csv();
    let (mut emulator, addr) = start_hokuyo_emulator(&log);

    let live_out = scratch("hokuyo-live");
    let live_domain = domain("hokuyo-live");
    let output = launch_hokuyo(&live_domain, &live_out, &addr, 400, &["--particles", "50"]);
    let _ = emulator.kill();
    let _ = emulator.wait();
    assert_success(&output);
    assert_eq!(metrics(&live_out).frames_processed, 400);

    let replay = replayed(
        "hokuyo-replay",
        &log,
        &["--format", "seed-csv", "--particles", "50"],
    );

    // Same scans, same geometry, same seed: the same map, up to the stamps' effect on the
    // motion prior (the live sensor runs at 40 Hz, the log is stamped at a nominal 10 Hz),
    // which moves the scans the corners update the particles at (every 0.5 m) and so adds
    // or drops a borderline corner or two.
    let live = read_map_corners(&live_out);
    let replayed = read_map_corners(&replay.out);
    let matched = live
        .iter()
        .filter(|a| {
            replayed
                .iter()
                .any(|b| (a[0] - b[0]).hypot(a[1] - b[1]) < 0.05)
        })
        .count();
    assert!(
        matched as f64 >= 0.9 * live.len() as f64 && live.len().abs_diff(replayed.len()) <= 4,
        "live map {} corners, replayed {}, {matched} match",
        live.len(),
        replayed.len()
    );
    assert!(shm_leftovers(&live_domain).is_empty());
    assert!(shm_leftovers(&replay.domain).is_empty());
}

#[test]
fn a_replay_made_harder_publishes_every_nth_scan_cut_to_the_shorter_range() {
    let log = test_data::seed_hall_csv();
    let run = replayed(
        "seed-hall-harder",
        &log,
        &[
            "--format",
            "seed-csv",
            "--particles",
            "20",
            "--replay-every",
            "4",
            "--replay-max-range",
            "8",
        ],
    );
    assert_eq!(metrics(&run.out).frames_processed, 100);
    // seed-hall is stamped every 0.1 s from 0: the scans kept are 0, 4, 8, ...
    let stamps: Vec<u64> = read_tum(&run.out.join("trajectory.tum"))
        .iter()
        .map(|pose| pose.stamp_ns)
        .collect();
    let expected: Vec<u64> = (0..100).map(|i| i * 400_000_000).collect();
    assert_eq!(stamps, expected);
    // The replay's summary says what it left out, and nothing counts as lost.
    let stderr = String::from_utf8_lossy(&run.output.stderr);
    assert!(
        summary_line(&stderr, "left out:").starts_with("300 scans (--every 4"),
        "{stderr}"
    );
    let shortened = summary_count(&stderr, "shortened:");
    // Much of the hall lies beyond 8 m, not all of it.
    assert!((1000..90 * 1081).contains(&shortened), "{shortened} beams");
    assert!(
        !stderr.contains("skipped_scans"),
        "every scan has walls: {stderr}"
    );
    assert!(!stderr.contains("lidar-replay: malformed"), "{stderr}");
    assert!(shm_leftovers(&run.domain).is_empty());
}
