//! `lidar-replay` as a process: a subscriber in its own domain receives every scan and
//! odometry pose in order with the log's exact stamps, then the end of the stream.

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use ipc_types::prelude::*;

fn fixture(name: &str, text: &str) -> PathBuf {
    test_child::fixture("lidar-replay-test", name, text)
}

fn domain(tag: &str) -> Domain {
    Domain::new(&format!("replay-test-{tag}-{}", std::process::id())).unwrap()
}

/// A replay process in its own domain. Dropping it (a test failed half-way) kills the
/// process and removes the domain's shared memory, so nothing outlives the test.
struct Replay {
    child: Option<Child>,
    domain: Domain,
}

impl Replay {
    fn start(domain: Domain, args: &[&str]) -> Self {
        let child = Command::new(env!("CARGO_BIN_EXE_lidar-replay"))
            .args(args)
            .args(["--domain", domain.name()])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start lidar-replay");
        Self {
            child: Some(child),
            domain,
        }
    }

    /// Writes `log` as `{tag}.clf` and replays it as a CARMEN log with `extra` arguments, in
    /// a domain of its own.
    fn carmen(tag: &str, log: &str, extra: &[&str]) -> Self {
        let file = fixture(&format!("{tag}.clf"), log);
        let mut args = vec!["--format", "carmen", "--file", file.to_str().unwrap()];
        args.extend_from_slice(extra);
        Self::start(domain(tag), &args)
    }

    /// Waits for the process; it must succeed. Returns its stderr.
    fn finish(mut self) -> String {
        let child = self.child.take().expect("running");
        let output = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "lidar-replay failed: {stderr}");
        stderr
    }
}

impl Drop for Replay {
    fn drop(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
        let _ = self.domain.remove_leftovers();
    }
}

/// Beams of the fixtures' FLASER lines (a SICK LMS 1-degree mode).
const BEAMS: usize = 180;

/// A FLASER line of 180 beams with the stamp `stamp` and odometry x = `x`.
fn flaser(x: f64, stamp: &str) -> String {
    let rest = vec!["2.50"; BEAMS - 2].join(" ");
    format!("FLASER {BEAMS} 1.00 81.91 {rest} {x} 0 0 {x} 0 0.5 {stamp} robot 0.1\n")
}

/// What a subscriber saw.
#[derive(Debug, Default)]
struct Received {
    scans: Vec<(u64, u64)>,
    odometry: Vec<(u64, u64, f64)>,
    end: Option<(u64, u64)>,
    odometry_end: Option<(u64, u64)>,
    first_to_last_scan: Duration,
    /// When each scan came, after the first.
    arrivals: Vec<Duration>,
}

/// Subscribes to the replay's topics in `domain` and collects until end of stream.
fn receive(domain: &Domain, with_odometry: bool) -> Received {
    let node = domain.node("test-subscriber").unwrap();
    wait_for_topic(&node, topic::SCAN).unwrap();
    // The replay creates the odometry topic before the scan topic.
    let odometry = if with_odometry {
        Some(Inlet::open(&node, topic::ODOMETRY).unwrap())
    } else {
        assert!(Inlet::try_open(&node, topic::ODOMETRY).unwrap().is_none());
        None
    };
    let scans = Inlet::open(&node, topic::SCAN).unwrap();
    let mut received = Received::default();
    let mut first_scan = None;
    let deadline = Instant::now() + Duration::from_secs(30);
    while received.end.is_none() {
        assert!(Instant::now() < deadline, "no end of stream: {received:?}");
        match &odometry {
            Some(odometry) => wait_any(&[&scans, odometry], Duration::from_millis(50)),
            None => wait_any(&[&scans], Duration::from_millis(50)),
        }
        .unwrap();
        if let Some(odometry) = &odometry {
            while let Some(sample) = odometry.receive().unwrap() {
                if sample.header.is_end_of_stream() {
                    received.odometry_end = Some((sample.header.seq, sample.header.stamp_ns));
                    continue;
                }
                assert_eq!(sample.header.frame_id(), "odom");
                received
                    .odometry
                    .push((sample.header.seq, sample.header.stamp_ns, sample.pose.x));
            }
        }
        while let Some(scan) = scans.receive().unwrap() {
            if scan.header.is_end_of_stream() {
                received.end = Some((scan.header.seq, scan.header.stamp_ns));
                break;
            }
            assert_eq!(scan.header.frame_id(), "laser");
            assert_eq!(scan.ranges().len(), BEAMS);
            assert_eq!(scan.ranges()[0], 1.0);
            assert_eq!(scan.ranges()[1], f32::INFINITY, "81.91 m = no return");
            let now = Instant::now();
            received.first_to_last_scan = now - *first_scan.get_or_insert(now);
            received.arrivals.push(received.first_to_last_scan);
            received.scans.push((scan.header.seq, scan.header.stamp_ns));
        }
    }
    received
}

/// The summary block that ends the replay's stderr: its head and the indented lines after.
/// iceoryx2's own log lines (`0 [W] "origin"` and its `| ...` continuation) may come at any
/// time, the end included, and are not the replay's: they are left out.
fn summary_block(stderr: &str) -> String {
    let own: String = stderr
        .lines()
        .filter(|line| !is_iceoryx2_log(line))
        .map(|line| format!("{line}\n"))
        .collect();
    let start = own
        .rfind(lidar_replay::SUMMARY_HEAD)
        .unwrap_or_else(|| panic!("no summary: {stderr}"));
    let block = &own[start..];
    assert!(
        block.lines().skip(1).all(|line| line.starts_with("  ")),
        "the summary is one block at the end: {block}"
    );
    block.to_owned()
}

/// A line of iceoryx2's logger: `<n> [<level>] "<origin>"`, `| <message>`, or the blank line
/// that ends an entry.
fn is_iceoryx2_log(line: &str) -> bool {
    let entry_head = line
        .split_once(" [")
        .is_some_and(|(n, rest)| n.parse::<u64>().is_ok() && rest.get(1..3) == Some("] "));
    entry_head || line.starts_with("| ") || line.trim().is_empty()
}

#[test]
fn iceoryx2_log_lines_are_told_from_the_replays_own() {
    assert!(is_iceoryx2_log("0 [W] \"Config::global_config()\" "));
    assert!(is_iceoryx2_log(
        "| No config file was loaded, a config with default values will be used. "
    ));
    assert!(is_iceoryx2_log(""));
    assert!(!is_iceoryx2_log(
        "  published:       5 scans, 5 odometry poses"
    ));
    assert!(!is_iceoryx2_log(
        "lidar-replay: summary of a.clf (7 lines read)"
    ));
}

#[test]
fn lockstep_delivers_every_scan_and_odometry_with_exact_stamps() {
    let mut log = String::from("# CARMEN log fixture\nPARAM robot_use_laser on host 0\n");
    // 0.1 s apart from 1058295543.123456, written with microseconds as CARMEN does.
    let stamps: Vec<String> = (0..25u64)
        .map(|k| 1_058_295_543_123_456 + 100_000 * k)
        .map(|us| format!("{}.{:06}", us / 1_000_000, us % 1_000_000))
        .collect();
    for (k, stamp) in stamps.iter().enumerate() {
        log.push_str(&flaser(k as f64, stamp));
        if k == 3 {
            log.push_str("FLASER 180 1.0 oops\n");
        }
    }
    let replay = Replay::carmen("lockstep", &log, &["--rate", "0", "--subscribers", "1"]);
    let received = receive(&replay.domain, true);
    let stderr = replay.finish();

    let expected: Vec<(u64, u64)> = (0..25u64)
        .map(|k| (k, 1_058_295_543_123_456_000 + k * 100_000_000))
        .collect();
    assert_eq!(
        received.scans, expected,
        "every scan, in order, exact stamps"
    );
    let odometry: Vec<(u64, u64)> = received.odometry.iter().map(|o| (o.0, o.1)).collect();
    assert_eq!(odometry, expected, "odometry with its scan's seq and stamp");
    assert!(
        received
            .odometry
            .iter()
            .enumerate()
            .all(|(k, o)| o.2 == k as f64)
    );
    assert_eq!(received.end, Some((25, expected[24].1)));
    // The odometry's end came before the scans' end.
    assert_eq!(received.odometry_end, Some((25, expected[24].1)));
    assert!(
        stderr.contains("line 7: FLASER: range 2: \"oops\" is not a number (skipped)"),
        "{stderr}"
    );
    let summary = summary_block(&stderr);
    assert!(
        summary.contains("published:       25 scans, 25 odometry poses"),
        "{summary}"
    );
    assert!(
        summary.contains(
            "malformed lines: 1 skipped, by reason:\n    FLASER: a field is not a number: 1"
        ),
        "{summary}"
    );
    assert!(summary.contains("not replayed:    PARAM x1"), "{summary}");
    assert!(summary.contains("reordered:       none"), "{summary}");
}

#[test]
fn a_log_out_of_time_order_is_published_in_order_within_the_window() {
    // Line 3 goes back 0.4 s; line 5 by 3.4 s, behind what line 4 let out of the window;
    // line 6 repeats a stamp.
    let log: String = [
        flaser(0.0, "100.0"),
        flaser(2.0, "100.6"),
        flaser(1.0, "100.2"),
        flaser(3.0, "103.9"),
        flaser(9.0, "100.5"),
        flaser(3.0, "103.9"),
        flaser(4.0, "104.0"),
    ]
    .concat();
    let file = fixture("disorder.clf", &log);
    let file = file.to_str().unwrap();
    let replay = Replay::start(
        domain("disorder"),
        &[
            "--format",
            "carmen",
            "--file",
            file,
            "--reorder-window",
            "2",
        ],
    );
    let received = receive(&replay.domain, true);
    let stderr = replay.finish();
    let stamps: Vec<u64> = received.scans.iter().map(|s| s.1 / 100_000_000).collect();
    assert_eq!(stamps, vec![1000, 1002, 1006, 1039, 1040], "{received:?}");
    let odometry_x: Vec<f64> = received.odometry.iter().map(|o| o.2).collect();
    assert_eq!(odometry_x, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
    let summary = summary_block(&stderr);
    for expected in [
        "published:       5 scans, 5 odometry poses",
        "reordered:       1 scans, 1 odometry poses",
        "window 2 s",
        "dropped late:    1 scans, 1 odometry poses",
        "dropped repeats: 1 scans, 1 odometry poses",
    ] {
        assert!(summary.contains(expected), "{expected:?} in {summary}");
    }

    let refused = Command::new(env!("CARGO_BIN_EXE_lidar-replay"))
        .args(["--format", "carmen", "--file", file, "--reorder-window=-1"])
        .args(["--domain", "replay-refused-window"])
        .output()
        .unwrap();
    assert!(!refused.status.success());
    assert!(
        String::from_utf8_lossy(&refused.stderr).contains("--reorder-window must be between"),
        "{refused:?}"
    );
}

#[test]
fn no_odometry_and_frames_limit_what_is_published() {
    let log: String = (0..10)
        .map(|k| flaser(0.0, &format!("{}.5", 100 + k)))
        .collect();
    let replay = Replay::carmen("frames", &log, &["--no-odometry", "--frames", "4"]);
    let received = receive(&replay.domain, false);
    let stderr = replay.finish();
    let seqs: Vec<u64> = received.scans.iter().map(|s| s.0).collect();
    assert_eq!(seqs, vec![0, 1, 2, 3]);
    assert_eq!(received.end, Some((4, 103_500_000_000)));
    let summary = summary_block(&stderr);
    assert!(summary.contains("published:       4 scans\n"), "{summary}");
    assert!(
        summary.contains("stopped early:   --frames 4 reached"),
        "{summary}"
    );
    assert!(
        summary.contains("not published:   4 odometry poses (--no-odometry)"),
        "{summary}"
    );
}

#[test]
fn real_time_follows_the_logs_clock_scaled_by_the_rate() {
    // Five scans over 2 s of log time, replayed ten times as fast: 0.2 s.
    let log: String = (0..5)
        .map(|k| flaser(0.0, &format!("{:.1}", 50.0 + 0.5 * f64::from(k))))
        .collect();
    let replay = Replay::carmen("rate", &log, &["--rate", "10"]);
    let received = receive(&replay.domain, true);
    replay.finish();
    assert_eq!(received.scans.len(), 5);
    assert!(
        received.first_to_last_scan >= Duration::from_millis(180),
        "{:?}",
        received.first_to_last_scan
    );
}

#[test]
fn a_recording_replays_at_its_recorded_pace_scaled_by_the_rate() {
    // Five scans recorded over 1.6 s with a long pause in the middle, replayed twice as fast:
    // they come 0, 25, 525, 550 and 800 ms after the first, the pause kept (a replay at a
    // steady rate would spread them evenly).
    let offsets_ms: [u64; 5] = [0, 50, 1050, 1100, 1600];
    let start_ns = 1_700_000_000_000_000_000;
    let dir = std::env::temp_dir().join(format!("lidar-replay-paced-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut recording = recorder::Recording::create(&dir).unwrap();
    let mut ranges = vec![2.5_f32; BEAMS];
    ranges[0] = 1.0;
    ranges[1] = f32::INFINITY;
    for (seq, offset) in offsets_ms.iter().enumerate() {
        let mut scan = LaserScan::boxed_zeroed();
        scan.header = Header::new(seq as u64, start_ns + offset * 1_000_000, "laser");
        scan.angle_increment = std::f32::consts::PI / 180.0;
        scan.range_max = 81.0;
        scan.set_beams(&ranges, &[]).unwrap();
        recording.scan(&scan).unwrap();
    }
    let file = recording.finish().unwrap().path;

    let args = [
        "--format",
        "mcap",
        "--file",
        file.to_str().unwrap(),
        "--rate",
        "2",
    ];
    let replay = Replay::start(domain("mcap-paced"), &args);
    let received = receive(&replay.domain, false);
    replay.finish();
    let _ = std::fs::remove_dir_all(&dir);
    let stamps: Vec<u64> = received.scans.iter().map(|s| s.1).collect();
    let expected: Vec<u64> = offsets_ms
        .iter()
        .map(|offset| start_ns + offset * 1_000_000)
        .collect();
    assert_eq!(stamps, expected, "the recorded stamps, exactly");
    // Never much early: a busy machine may delay a scan (which shortens the gap before the
    // next), so the bounds leave 150 ms; a steady rate would leave 200 ms for the pause and
    // lockstep almost nothing for the whole.
    let arrivals = &received.arrivals;
    let pause = arrivals[2] - arrivals[1];
    assert!(pause >= Duration::from_millis(350), "{arrivals:?}");
    assert!(
        received.first_to_last_scan >= Duration::from_millis(650),
        "{arrivals:?}"
    );
}

#[test]
fn a_file_of_another_format_is_refused_before_publishing() {
    let csv = fixture("scans.csv", &"1,2,3\n".repeat(5));
    let output = Command::new(env!("CARGO_BIN_EXE_lidar-replay"))
        .args(["--format", "carmen", "--file", csv.to_str().unwrap()])
        .args(["--domain", "replay-refused"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("is not a carmen log: no valid scan in its 5 lines"),
        "{stderr}"
    );
    assert!(stderr.contains("line 1: not a CARMEN record"), "{stderr}");
    assert!(output.stdout.is_empty(), "refused before announcing ready");

    let missing = Command::new(env!("CARGO_BIN_EXE_lidar-replay"))
        .args(["--format", "seed-csv", "--file", "/nonexistent/scans.csv"])
        .output()
        .unwrap();
    assert!(!missing.status.success());
    assert!(
        String::from_utf8_lossy(&missing.stderr)
            .contains("cannot open the log /nonexistent/scans.csv")
    );
}
