//! Issue 16, the replay of a recording: a run recorded with `--record` and replayed from its
//! run.mcap (`--replay run.mcap`) gives the same trajectory bit for bit; recordings of a
//! real log and of a live (emulated) Hokuyo read back with the run's own counts and stamps;
//! a recorder killed mid-run leaves a readable file and a finished run; a file that is no
//! recording is refused by name.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(300);

/// The files of a run that must not change when it is replayed from its recording.
const RESULTS: [&str; 3] = ["trajectory.tum", "dead_reckoning.tum", "map_corners.csv"];

fn assert_same_results(a: &Path, b: &Path) {
    for file in RESULTS {
        assert!(
            std::fs::read(a.join(file)).expect("first run's file")
                == std::fs::read(b.join(file)).expect("second run's file"),
            "{file} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// Records `args` into `tag`'s directory, replays its run.mcap with `replay_args` into
/// another, and returns both directories.
fn record_and_replay(
    tag: &str,
    args: &[&str],
    replay_args: &[&str],
) -> (std::path::PathBuf, std::path::PathBuf) {
    let recorded = scratch(&format!("{tag}-recorded"));
    let output = launch(
        &domain(&format!("{tag}-rec")),
        &recorded,
        &[args, &["--record"]].concat(),
    );
    assert_success(&output);
    let recording = recorded.join("run.mcap");
    let replayed = scratch(&format!("{tag}-replayed"));
    let output = launch_replay(
        &domain(&format!("{tag}-rep")),
        &replayed,
        &recording,
        replay_args,
    );
    assert_success(&output);
    let console = String::from_utf8_lossy(&output.stderr);
    assert!(console.contains("nothing lost (every stage"), "{console}");
    (recorded, replayed)
}

#[test]
fn an_office_run_replayed_from_its_recording_gives_the_same_trajectory_bit_for_bit() {
    // The whole loop, so that the loop closure is replayed too.
    let common = ["--rate", "0", "--seed", "1", "--particles", "100"];
    let (recorded, replayed) = record_and_replay(
        "office",
        &[&["--world", "office"][..], &common].concat(),
        &common,
    );
    assert_same_results(&recorded, &replayed);
    assert_eq!(
        metrics(&replayed).frames_processed,
        metrics(&recorded).frames_processed
    );
    for dir in [recorded, replayed] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn the_recorded_odometry_is_replayed_exactly_too() {
    // With odometry the front end fuses it: the pairing and covariances must be the same.
    let common = ["--rate", "0", "--seed", "2", "--particles", "30"];
    let (recorded, replayed) = record_and_replay(
        "odometry",
        &[
            &["--world", "office", "--frames", "300", "--odometry"][..],
            &common,
        ]
        .concat(),
        &common,
    );
    assert_same_results(&recorded, &replayed);
    let used =
        |dir: &Path| std::fs::read_to_string(dir.join("logs/feature-proc.log")).unwrap_or_default();
    // The front end reports the odometry steps it used: as many in both runs, and some.
    let steps = |log: String| {
        log.lines()
            .find(|l| l.contains("odometry steps:"))
            .map(str::to_owned)
            .unwrap_or_default()
    };
    let (a, b) = (steps(used(&recorded)), steps(used(&replayed)));
    assert_eq!(a, b);
    assert!(a.contains(" used, ") && !a.contains(" 0 used"), "{a:?}");
    for dir in [recorded, replayed] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// What one topic of a recording holds.
#[derive(Debug, Default)]
struct TopicRead {
    schema: String,
    schema_encoding: String,
    message_encoding: String,
    messages: u64,
    first_log_time: Option<u64>,
    last_log_time: u64,
}

/// Every message of a recording, by topic, with the summary's statistics checked against
/// them.
fn read_recording(path: &Path) -> BTreeMap<String, TopicRead> {
    let bytes = std::fs::read(path).expect("run.mcap");
    let mut topics: BTreeMap<String, TopicRead> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("a readable file") {
        let message = message.expect("every message reads");
        let channel = &message.channel;
        let topic = topics.entry(channel.topic.clone()).or_default();
        let schema = channel.schema.as_ref().expect("a schema");
        topic.schema = schema.name.clone();
        topic.schema_encoding = schema.encoding.clone();
        topic.message_encoding = channel.message_encoding.clone();
        topic.messages += 1;
        topic.first_log_time.get_or_insert(message.log_time);
        topic.last_log_time = message.log_time;
        serde_json::from_slice::<serde_json::Value>(&message.data).expect("JSON");
    }
    let summary = mcap::Summary::read(&bytes)
        .expect("a readable summary")
        .expect("finished with a summary");
    let stats = summary.stats.expect("statistics");
    assert_eq!(
        stats.message_count,
        topics.values().map(|t| t.messages).sum::<u64>()
    );
    topics
}

/// The exact stamps of a TUM file, first and last.
fn first_and_last_stamps(path: &Path) -> (u64, u64) {
    let text = std::fs::read_to_string(path).expect("TUM file");
    let poses = slam_geom::parse_tum(&text).expect("a TUM file");
    let first = poses.first().expect("poses").1.stamp_ns;
    let last = poses.last().expect("poses").1.stamp_ns;
    (first, last)
}

/// Checks a recording of a run without a simulator (no ground truth, no world) against the
/// run's own counters and files.
fn check_recording_of(out: &Path, odometry: bool) {
    let topics = read_recording(&out.join("run.mcap"));
    let mut expected: Vec<(&str, &str)> = vec![
        ("/lidar/scan", "foxglove.LaserScan"),
        ("/tf", "foxglove.FrameTransform"),
        ("/slam/pose", "foxglove.PoseInFrame"),
        ("/slam/path", "foxglove.PosesInFrame"),
        // The back end's path and grid: these runs map from nothing.
        ("/graph/path", "foxglove.PosesInFrame"),
        ("/graph/grid", "foxglove.Grid"),
        ("/perception/features", "slam.Features"),
        ("/slam/map", "slam.MapSnapshot"),
        ("/slam/map_scene", "foxglove.SceneUpdate"),
        ("/perception/scene", "foxglove.SceneUpdate"),
    ];
    if odometry {
        expected.push(("/robot/odometry", "slam.Odometry"));
    }
    // map-sink's path, its grid when it traced one, and a particle cloud every 40 scans
    // (slam-launch's `PARTICLE_CLOUD_EVERY`).
    let metrics = metrics(out);
    let processed = metrics.frames_processed;
    let grid = out.join("map.pgm").exists();
    expected.push(("/map/path", "foxglove.PosesInFrame"));
    if grid {
        expected.push(("/map/grid", "foxglove.Grid"));
    }
    if processed >= 20 {
        expected.push(("/slam/particles", "foxglove.PosesInFrame"));
    }
    expected.sort_unstable();
    let found: Vec<(&str, &str)> = topics
        .iter()
        .map(|(topic, read)| (topic.as_str(), read.schema.as_str()))
        .collect();
    assert_eq!(found, expected);
    for (topic, read) in &topics {
        assert_eq!(read.schema_encoding, "jsonschema", "{topic}");
        assert_eq!(read.message_encoding, "json", "{topic}");
    }
    let published = metrics.frames_published;
    assert_eq!(topics["/lidar/scan"].messages, published);
    assert_eq!(topics["/perception/features"].messages, published);
    assert_eq!(topics["/slam/pose"].messages, processed);
    // map → base_link at every pose, base_link → laser once.
    assert_eq!(topics["/tf"].messages, processed + 1);
    assert_eq!(topics["/slam/path"].messages, 1);
    // The back end's path and grid as they stand every few seconds of the run, then their
    // final ones.
    assert!(topics["/graph/path"].messages >= 1);
    assert!(topics["/graph/grid"].messages >= 1);
    assert_eq!(topics["/map/path"].messages, 1);
    let count = |topic: &str| topics.get(topic).map_or(0, |t| t.messages);
    assert_eq!(count("/map/grid"), u64::from(grid));
    assert_eq!(count("/slam/particles"), processed / 40);
    // The front end's pose at every scan: the scans' first and last stamps.
    let (first, last) = first_and_last_stamps(&out.join("dead_reckoning.tum"));
    for topic in ["/lidar/scan", "/slam/pose", "/perception/features"] {
        assert_eq!(topics[topic].first_log_time, Some(first), "{topic}");
        assert_eq!(topics[topic].last_log_time, last, "{topic}");
    }
}

#[test]
fn recordings_of_a_real_log_and_a_live_hokuyo_read_back_with_the_runs_counts() {
    let log = test_data::seed_hall_csv();
    let replay_out = replayed(
        "record-seed-hall",
        &log,
        &["--format", "seed-csv", "--particles", "30", "--record"],
    )
    .out;
    assert_eq!(metrics(&replay_out).frames_published, 400);
    check_recording_of(&replay_out, false);

    let (mut emulator, addr) = start_hokuyo_emulator(&log);
    let live_out = scratch("record-hokuyo");
    let output = launch_hokuyo(
        &domain("record-hokuyo"),
        &live_out,
        &addr,
        400,
        &["--particles", "30", "--record"],
    );
    let _ = emulator.kill();
    let _ = emulator.wait();
    assert_success(&output);
    check_recording_of(&live_out, false);

    // The live run replays from its recording offline, with the same results.
    let recording = live_out.join("run.mcap");
    let offline = replayed("record-hokuyo-offline", &recording, &["--particles", "30"]).out;
    assert_same_results(&live_out, &offline);
    for dir in [replay_out, live_out, offline] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn a_recorder_killed_mid_run_leaves_a_readable_file_and_the_run_finishes() {
    let domain = domain("record-killed");
    let out = scratch("record-killed");
    let launcher = spawn_launch(
        &domain,
        &out,
        &[
            "--world",
            "office",
            "--rate",
            "0",
            "--particles",
            "30",
            "--record",
        ],
        Stdio::piped(),
    );
    let launcher_pid = pid_of(&launcher);

    // Mid-run: a few chunks of the recording are on disk (the whole loop makes tens of MB).
    let recording = out.join("run.mcap");
    let deadline = Instant::now() + LIMIT;
    let mut recorder = None;
    while recorder.is_none() {
        let written = std::fs::metadata(&recording).map_or(0, |m| m.len());
        if written > 3 << 20 {
            recorder = child_named(launcher_pid, "slam-record");
        }
        assert!(
            Instant::now() < deadline,
            "no recording under way in {LIMIT:?}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    send(recorder.expect("slam-record"), Signal::SIGKILL);

    let output = launcher.wait_with_output().expect("slam-launch ends");
    let console = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{console}");
    assert!(
        console.contains("slam-record died (killed by signal 9)"),
        "{console}"
    );
    assert!(console.contains("the run goes on without it"), "{console}");
    // The run's results are all there: every scan was processed.
    let run = metrics(&out);
    assert_eq!(run.frames_processed, run.frames_published);
    assert!(run.frames_processed > 3000);
    assert!(out.join("trajectory.tum").is_file());

    // The file reads, in order, up to its last complete chunk.
    let bytes = std::fs::read(&recording).expect("run.mcap");
    let mut scans = 0u64;
    let mut ended_in_error = false;
    for message in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        match message {
            Ok(message) if message.channel.topic == "/lidar/scan" => {
                let json: serde_json::Value = serde_json::from_slice(&message.data).expect("JSON");
                assert_eq!(json["seq"], scans, "scans in order, none missing");
                scans += 1;
            }
            Ok(_) => {}
            Err(_) => {
                ended_in_error = true;
                break;
            }
        }
    }
    assert!(ended_in_error, "an unfinished file has no end");
    assert!(scans > 50, "{scans} scans readable");

    // And it replays: what it holds, with the cut reported.
    let replayed = scratch("record-killed-replayed");
    let output = launch_replay(
        &tests::domain("record-killed-rep"),
        &replayed,
        &recording,
        &["--particles", "30"],
    );
    assert_success(&output);
    let console = String::from_utf8_lossy(&output.stderr);
    assert!(console.contains("cut short:"), "{console}");
    assert_eq!(metrics(&replayed).frames_processed, scans);
    for dir in [out, replayed] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn a_damaged_or_foreign_recording_is_refused_by_name() {
    let source = scratch("refused-source");
    assert_success(&launch(
        &domain("refused-source"),
        &source,
        &[
            "--world", "office", "--frames", "200", "--rate", "0", "--record",
        ],
    ));
    let bytes = std::fs::read(source.join("run.mcap")).expect("run.mcap");
    let dir = scratch("refused");
    let foreign = dir.join("foreign.mcap");
    std::fs::write(&foreign, "14029,14083\n".repeat(100)).expect("write");
    let truncated = dir.join("truncated.mcap");
    std::fs::write(&truncated, &bytes[..4000]).expect("write");
    let damaged = dir.join("damaged.mcap");
    let mut flipped = bytes.clone();
    flipped[10_000] ^= 0x55;
    std::fs::write(&damaged, &flipped).expect("write");
    let csv = test_data::seed_hall_csv();

    for (file, format, reason) in [
        (&foreign, None, "is not an MCAP file"),
        (&truncated, None, "is damaged before its first scan"),
        (&damaged, None, "is damaged before its first scan"),
        (&csv, Some("mcap"), "is not an MCAP file"),
    ] {
        let out = dir.join("out");
        let mut command = Command::new(bin("slam-launch"));
        command
            .args(["--quiet", "--domain", &domain("refused"), "--out"])
            .arg(&out)
            .arg("--replay")
            .arg(file);
        if let Some(format) = format {
            command.args(["--format", format]);
        }
        let output = output_within(&mut command, LIMIT).expect("slam-launch refuses in time");
        let console = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{}: {console}", file.display());
        let expected = format!("{} {reason}", file.display());
        assert!(console.contains(&expected), "{expected}: {console}");
    }
    // lidar-replay on its own says the same, and exits non-zero before any port exists.
    let output = output_within(
        Command::new(bin("lidar-replay"))
            .args([
                "--format",
                "mcap",
                "--domain",
                &domain("refused-own"),
                "--file",
            ])
            .arg(&foreign),
        LIMIT,
    )
    .expect("lidar-replay refuses in time");
    assert!(!output.status.success());
    let console = String::from_utf8_lossy(&output.stderr);
    assert!(
        console.starts_with(&format!(
            "lidar-replay: {} is not an MCAP file",
            foreign.display()
        )),
        "{console}"
    );
    assert!(!String::from_utf8_lossy(&output.stdout).contains("ready"));
    for dir in [source, dir] {
        let _ = std::fs::remove_dir_all(dir);
    }
}
