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

// A log that stamps some scans late, after scans it has after them (a logger that stamps
// a scan when it gets round to writing it): the replay keeps the log's order, so the front
// end meets the scans in the order they were taken, and each pose is written under the
// log's own stamp, where the log's ground truth looks for it.
#[test]
fn scans_stamped_late_are_processed_in_the_logs_order_under_their_own_stamps() {
    let log = std::fs::read_to_string(test_data::carmen_log("aces")).expect("aces.clf");
    let mut doctored = String::new();
    let mut stamps = Vec::new();
    let mut late = 0;
    for line in log.lines() {
        if !line.starts_with("FLASER ") {
            doctored += line;
            doctored.push('\n');
            continue;
        }
        if stamps.len() == 700 {
            break;
        }
        let mut fields: Vec<String> = line.split_whitespace().map(str::to_owned).collect();
        let at = fields.len() - 3;
        if stamps.len() % 7 == 3 {
            let stamp: f64 = fields[at].parse().expect("a stamp");
            // A few microseconds off the log's grid, so that no stamp is repeated.
            let lateness = 0.300_003 + 0.1 * (stamps.len() % 3) as f64;
            fields[at] = format!("{:.6}", stamp + lateness);
            late += 1;
        }
        stamps.push(slam_geom::parse_stamp_ns(&fields[at]).expect("a stamp"));
        doctored += &fields.join(" ");
        doctored.push('\n');
    }
    let dir = scratch("late-stamps-log");
    let file = dir.join("late.clf");
    std::fs::write(&file, doctored).expect("write the log");
    let run = replayed("late-stamps", &file, &["--particles", "20"]);

    let poses = read_tum(&run.out.join("dead_reckoning.tum"));
    let written: Vec<u64> = poses.iter().map(|pose| pose.stamp_ns).collect();
    assert_eq!(written.len(), stamps.len());
    let differs = written.iter().zip(&stamps).position(|(a, b)| a != b);
    assert_eq!(differs, None, "the log's order, under its stamps");
    // Each late scan's pose lies between its neighbours': the path makes no detour there.
    let apart = |a: usize, b: usize| {
        let (p, q) = (poses[a].position, poses[b].position);
        (q[0] - p[0]).hypot(q[1] - p[1])
    };
    for k in (3..poses.len() - 1).step_by(7) {
        let detour = apart(k - 1, k) + apart(k, k + 1) - apart(k - 1, k + 1);
        assert!(detour < 0.05, "scan {k}: a detour of {detour} m");
    }
    let stderr = String::from_utf8_lossy(&run.output.stderr);
    assert!(
        summary_line(&stderr, "restamped:").starts_with(&format!("{late} scans")),
        "{stderr}"
    );
    assert!(shm_leftovers(&run.domain).is_empty());
}
