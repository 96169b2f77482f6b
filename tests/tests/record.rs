//! `slam-launch --record` (issue 16): a short simulated office run recorded into run.mcap,
//! read back with the mcap crate's reader and checked against the run's own counters
//! (metrics.json) and files (ground_truth.tum, trajectory.tum); and the same run without
//! the recorder gives the same results bit for bit.

use std::collections::BTreeMap;

use tests::*;

const FRAMES: u64 = 200;

/// What one topic of the file holds.
#[derive(Debug, Default)]
struct TopicRead {
    messages: u64,
    first_log_time: Option<u64>,
    last_log_time: u64,
    last: Option<serde_json::Value>,
}

#[test]
fn a_recorded_office_run_reads_back_with_every_topic_and_count() {
    let frames = FRAMES.to_string();
    // With odometry, so that every topic is recorded; trajectory.tum kept as the filter's
    // path, which is what the recording holds.
    let args = [
        "--world",
        "office",
        "--frames",
        &frames,
        "--rate",
        "0",
        "--odometry",
        "--refine-passes",
        "0",
    ];
    let out = scratch("record");
    let output = launch(
        &domain("record"),
        &out,
        &[&args[..], &["--record"]].concat(),
    );
    assert_success(&output);
    // The recorder reports its losses like every stage.
    let console = String::from_utf8_lossy(&output.stderr);
    assert!(console.contains("nothing lost (every stage"), "{console}");
    // The recorder is one more subscriber the publishers wait for: the run is the same.
    let plain = scratch("record-plain");
    assert_success(&launch(&domain("record-plain"), &plain, &args));
    for file in ["trajectory.tum", "map_corners.csv", "dead_reckoning.tum"] {
        assert_eq!(
            std::fs::read(out.join(file)).expect("recorded run's file"),
            std::fs::read(plain.join(file)).expect("plain run's file"),
            "{file} differs with --record"
        );
    }
    let _ = std::fs::remove_dir_all(&plain);
    let metrics = metrics(&out);
    let published = metrics.frames_published;
    let processed = metrics.frames_processed;
    let map_corners = metrics.map_corners as u64;
    assert_eq!(published, FRAMES);
    assert_eq!(processed, FRAMES, "lockstep loses nothing");

    let bytes = std::fs::read(out.join("run.mcap")).expect("run.mcap");
    let summary = mcap::Summary::read(&bytes)
        .expect("a readable summary")
        .expect("the file was finished with a summary");

    // Schemas: Foxglove's where they fit, ours otherwise; all JSON schemas.
    let expected: BTreeMap<&str, &str> = [
        ("/lidar/scan", "foxglove.LaserScan"),
        ("/tf", "foxglove.FrameTransform"),
        ("/slam/pose", "foxglove.PoseInFrame"),
        ("/slam/path", "foxglove.PosesInFrame"),
        ("/sim/ground_truth", "foxglove.PoseInFrame"),
        ("/perception/features", "slam.Features"),
        ("/slam/map", "slam.MapSnapshot"),
        ("/slam/map_scene", "foxglove.SceneUpdate"),
        ("/perception/scene", "foxglove.SceneUpdate"),
        ("/sim/world_corners", "slam.WorldCorners"),
        ("/robot/odometry", "slam.Odometry"),
    ]
    .into_iter()
    .collect();
    let mut channels = BTreeMap::new();
    for channel in summary.channels.values() {
        let schema = channel.schema.as_ref().expect("every channel has a schema");
        assert_eq!(schema.encoding, "jsonschema", "{}", channel.topic);
        assert_eq!(channel.message_encoding, "json", "{}", channel.topic);
        let text: serde_json::Value =
            serde_json::from_slice(&schema.data).expect("the schema is JSON");
        assert_eq!(text["title"], schema.name.as_str());
        channels.insert(channel.topic.as_str(), schema.name.as_str());
    }
    assert_eq!(channels, expected);

    // Every message, decoded and counted by topic.
    let mut topics: BTreeMap<String, TopicRead> = BTreeMap::new();
    let mut tf_children: BTreeMap<String, u64> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("a readable file") {
        let message = message.expect("every message reads");
        let json: serde_json::Value =
            serde_json::from_slice(&message.data).expect("every message is JSON");
        if message.channel.topic == "/tf" {
            let child = json["child_frame_id"].as_str().unwrap_or("").to_owned();
            *tf_children.entry(child).or_default() += 1;
        }
        let topic = topics.entry(message.channel.topic.clone()).or_default();
        topic.messages += 1;
        topic.first_log_time.get_or_insert(message.log_time);
        assert!(message.log_time >= topic.last_log_time, "in stamp order");
        topic.last_log_time = message.log_time;
        topic.last = Some(json);
    }
    let count = |topic: &str| topics.get(topic).map_or(0, |t| t.messages);
    assert_eq!(count("/lidar/scan"), published);
    assert_eq!(count("/perception/features"), published);
    assert_eq!(count("/sim/ground_truth"), published);
    assert_eq!(count("/slam/pose"), processed);
    assert_eq!(count("/sim/world_corners"), 1);
    assert_eq!(count("/slam/path"), 1);
    assert!(count("/robot/odometry") > 0);
    // A map every 20 scans (0.5 s), recorded at most every 2 s of data, and the last.
    let maps = count("/slam/map");
    assert!((2..FRAMES / 20).contains(&maps), "{maps} maps");
    // Each drawn as a scene; the features drawn four times a second of data (every tenth
    // scan at 40 Hz).
    assert_eq!(count("/slam/map_scene"), maps);
    assert_eq!(count("/perception/scene"), FRAMES.div_ceil(10));
    // map → base_link at every pose, base_link → laser once.
    assert_eq!(tf_children.get("base_link"), Some(&processed));
    assert_eq!(tf_children.get("laser"), Some(&1));
    assert_eq!(count("/tf"), processed + 1);

    // The summary's statistics say the same as the messages.
    let stats = summary.stats.as_ref().expect("statistics");
    let total: u64 = topics.values().map(|t| t.messages).sum();
    assert_eq!(stats.message_count, total);
    for (id, channel) in &summary.channels {
        assert_eq!(
            stats.channel_message_counts.get(id).copied(),
            Some(count(&channel.topic)),
            "{}",
            channel.topic
        );
    }

    // First and last stamps: the scans' are the ground truth's (map-sink's file), and the
    // final path's last pose is the trajectory's last.
    let truth = read_tum(&out.join("ground_truth.tum"));
    let scans = &topics["/lidar/scan"];
    assert_eq!(scans.first_log_time, Some(truth[0].stamp_ns));
    assert_eq!(scans.last_log_time, truth[truth.len() - 1].stamp_ns);
    assert_eq!(stats.message_start_time, scans.first_log_time.unwrap_or(0));
    assert_eq!(stats.message_end_time, scans.last_log_time);
    let poses = &topics["/slam/pose"];
    assert_eq!(poses.first_log_time, scans.first_log_time);
    assert_eq!(poses.last_log_time, scans.last_log_time);

    let trajectory = read_tum(&out.join("trajectory.tum"));
    let path = topics["/slam/path"].last.as_ref().expect("the path");
    let path_poses = path["poses"].as_array().expect("poses");
    assert_eq!(path_poses.len(), trajectory.len());
    let last = &trajectory[trajectory.len() - 1];
    let last_pose = &path_poses[path_poses.len() - 1]["position"];
    assert!((last_pose["x"].as_f64().unwrap() - last.position[0]).abs() < 1e-5);
    assert!((last_pose["y"].as_f64().unwrap() - last.position[1]).abs() < 1e-5);
    assert_eq!(
        path["stamps_ns"].as_array().map(Vec::len),
        Some(trajectory.len())
    );

    // The last map is the map map-sink wrote, and its scene draws each of its corners.
    let map = topics["/slam/map"].last.as_ref().expect("a map");
    assert_eq!(
        map["corners"].as_array().map(|c| c.len() as u64),
        Some(map_corners)
    );
    let scene = topics["/slam/map_scene"]
        .last
        .as_ref()
        .expect("a map scene");
    assert_eq!(
        scene["entities"].as_array().map(|e| e.len() as u64),
        Some(map_corners)
    );
    assert_eq!(
        topics["/slam/map_scene"].last_log_time,
        topics["/slam/map"].last_log_time
    );
    // A scan holds its beams.
    let scan = scans.last.as_ref().expect("a scan");
    let beams = scan["ranges"].as_array().map_or(0, Vec::len);
    // The simulator gives no intensities: none are written (ROS's rule for LaserScan).
    assert_eq!(scan["intensities"].as_array().map(Vec::len), Some(0));
    assert!(beams > 100, "{beams} beams");
    assert_eq!(scan["frame_id"], "laser");

    let _ = std::fs::remove_dir_all(&out);
}
